#pragma once
// The web viewer's files, bundled at build time (web/src, three.js from web/node_modules) and
// compiled in by cmake/embed_web.cmake, so that the executable writes a site on its own.
#include <string>

namespace viewcells::web_assets {

/// False when the build had no web/node_modules: the functions below then return "".
bool available();
std::string viewer_js();
std::string index_html();

}  // namespace viewcells::web_assets
