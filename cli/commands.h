#pragma once
#include <string>
#include <vector>

#include "viewcells/pipeline/bake.h"

namespace viewcells::cli {
/// Parses the command line, runs the subcommand, returns the process exit code. Errors are
/// printed as "viewcells: error: ..." and give a non-zero code.
int run(int argc, char** argv);

/// The configuration `viewcells bake ARGS...` would run, with the command line's defaults and
/// checks (its options are bound in one place): what bindings that bake from code start from
/// (python/). `args` follow "bake" and name the scene and -o; Error on bad options.
pipeline::BakeConfig bake_config_from_args(const std::vector<std::string>& args, bool quiet = true);
}  // namespace viewcells::cli
