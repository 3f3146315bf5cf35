#pragma once

namespace viewcells::cli {
/// Parses the command line, runs the subcommand, returns the process exit code. Errors are
/// printed as "viewcells: error: ..." and give a non-zero code.
int run(int argc, char** argv);
}  // namespace viewcells::cli
