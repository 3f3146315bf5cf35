// The viewcells command line: options in, library calls (viewcells/pipeline), output. The
// subcommands live in scene_commands.cpp, build_commands.cpp, cut_commands.cpp,
// pvs_commands.cpp and compare_command.cpp.
#include "commands.h"

#include "viewcells/q3/bsp_file.h"

#include <cstdlib>
#include <iostream>

#include "options.h"
#include "viewcells/core/ranks.h"
#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/binary_file.h"

namespace viewcells::cli {

int run(int argc, char** argv) {
  register_q3_map_format();  // the front end brings the formats the library leaves to adapters
  CLI::App app{
      "viewcells: builds view cells for visibility preprocessing from the visibility of the scene itself.\n"
      "Pipeline: generate or load a scene -> sample visibility segments -> subdivide the view space\n"
      "into cells and merge them into a hierarchy (build) -> cut view cells from it (extract) ->\n"
      "write their compressed PVS (compress, or by AGVS: pvs) -> look a viewpoint up (query), look at the cells (view: web page, glTF).\n"
      "bake does the whole chain in one command under a budget of cells or bytes."};
  app.require_subcommand(1);
  app.fallthrough();
  Common common;
  app.add_option("--threads", common.threads, "Worker threads (0 = all cores); results do not depend on it")
      ->check(non_negative());
  app.add_flag("-q,--quiet", common.quiet, "No progress bars or log lines on stderr");
  std::string isa;
  app.add_option("--embree-isa", isa,
                 "Embree's instruction set: sse2, sse4.2, avx, avx2 or avx512 (default: VIEWCELLS_EMBREE_ISA, else "
                 "the CPU's best). Sampled results are bit-identical across machines only for the same ISA; reports "
                 "and file headers record it");
  Commands commands;
  add_scene_commands(app, common, commands);
  add_build_commands(app, common, commands);
  add_compare_command(app, common, commands);
  add_cut_commands(app, common, commands);
  add_pvs_commands(app, common, commands);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::cerr << "viewcells: error: " << e.what() << "\nRun with --help for more information.\n";
    return e.get_exit_code();
  }
  try {
    // One setting for the whole process, read by every caster and file header (core/isa.h).
    if (!isa.empty()) setenv("VIEWCELLS_EMBREE_ISA", checked_embree_isa(isa).c_str(), 1);
    embree_isa();  // a bad VIEWCELLS_EMBREE_ISA fails here, before any work
    // Every file a command writes is renamed into place only when the whole command succeeded.
    OutputBatch outputs;
    int rc = 0;
    for (const Command& c : commands)
      if (*c.app) {
        check_no_empty_values(*c.app);
        rc = c.run();
      }
    // On a cluster every rank computes the same files; rank 0 installs them, the others'
    // staged copies go with their batch.
    if (rc == 0 && ranks::writer()) outputs.commit();
    return rc;
  } catch (const Interrupted& e) {
    std::cerr << "viewcells: " << e.what() << '\n';
    return 130;  // as a shell reports a process ended by SIGINT
  } catch (const Error& e) {
    std::cerr << "viewcells: error: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "viewcells: error: " << e.what() << '\n';
    return 2;
  }
}

}  // namespace viewcells::cli
