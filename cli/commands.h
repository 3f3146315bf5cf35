#pragma once
#include <string>
#include <vector>

#include "viewcells/pipeline/options.h"

namespace viewcells::cli {
/// Parses the command line, runs the subcommand, returns the process exit code. Errors are
/// printed as "viewcells: error: ..." and give a non-zero code.
int run(int argc, char** argv);

/// What `viewcells bake ARGS...` sets, parsed by the command line (CLI11, with the options the
/// library's table lists): the tests compare it with the library's own parse of the same words
/// (pipeline::parse_bake_words, what vc_bake runs). Error on bad options.
pipeline::BakeOptions bake_options_from_args(const std::vector<std::string>& args);
}  // namespace viewcells::cli
