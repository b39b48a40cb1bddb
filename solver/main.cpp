// mpath-solve: solves the radiosity of a scene described by a TOML config.
#include "program.h"
#include "solve.h"

int main(int argc, char** argv) {
  CLI::App app{"mpath-solve: hierarchical Multipath radiosity solver", "mpath-solve"};
  mpath::ProgramFlags flags;
  bool resume = false;
  mpath::add_common_flags(app, flags);
  app.add_flag("--resume", resume, "continue from the last checkpoint in output.dir");
  if (const int status = mpath::parse_command_line(app, argc, argv); status >= 0) return status;
  const char* advice = "the passes finished so far are in output.dir/checkpoint.bin: run again with --resume";
  return mpath::run_program("mpath-solve", advice, flags, [&](const mpath::Options& options) {
    mpath::SolveFlags solve;
    solve.resume = resume;
    solve.dry_run = flags.dry_run;
    for (int i = 0; i < argc; ++i) solve.command_line += (i ? " " : "") + std::string(argv[i]);
    mpath::run_solve(options, solve);
  });
}
