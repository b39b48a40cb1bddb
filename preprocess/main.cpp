// mpath-preprocess: meshes the scene and writes the line store for mpath-solve.
#include "preprocess.h"
#include "process_memory.h"
#include "program.h"

int main(int argc, char** argv) {
  mpath::use_huge_pages(argv);  // first: it may run the program again in place
  CLI::App app{"mpath-preprocess: traces and stores the global lines of a scene", "mpath-preprocess"};
  mpath::ProgramFlags flags;
  std::string shard = "1/1";
  bool print_hierarchy = false;
  mpath::add_common_flags(app, flags);
  app.add_option("--shard", shard, "trace part i of n (i/n) of the lines; run every part, in any order");
  app.add_flag("--print-hierarchy", print_hierarchy, "print the hierarchy of subscenes (boxes, depth, objects, "
               "polygons, quotient, lines per box) and stop");
  if (const int status = mpath::parse_command_line(app, argc, argv); status >= 0) return status;
  const char* advice = "finished shards are kept and verified; run again to finish the store";
  return mpath::run_program("mpath-preprocess", advice, flags, [&](const mpath::Options& options) {
    mpath::run_preprocess(options, mpath::parse_shard(shard), flags.dry_run, print_hierarchy);
  });
}
