// mpath-solve: solves the radiosity of a scene described by a TOML config.
// Under mpirun or srun, the ranks share every pass (ranks.h).
#include "process_memory.h"
#include "program.h"
#include "ranks.h"
#include "solve.h"

namespace {

int solve_main(int argc, char** argv) {
  CLI::App app{"mpath-solve: hierarchical Multipath radiosity solver", "mpath-solve"};
  mpath::ProgramFlags flags;
  bool resume = false;
  mpath::add_common_flags(app, flags);
  app.add_flag("--resume", resume, "continue from the last checkpoint in output.dir");
  if (const int status = mpath::parse_command_line(app, argc, argv); status >= 0) return status;
  // Rank 0 speaks for all; the others print errors only.
  if (!mpath::Ranks::root()) flags.quiet = true;
  const char* advice = "the passes finished so far are in output.dir/checkpoint.bin: run again with --resume";
  return mpath::run_program("mpath-solve", advice, flags, [&](const mpath::Options& options) {
    mpath::SolveFlags solve;
    solve.resume = resume;
    solve.dry_run = flags.dry_run;
    for (int i = 0; i < argc; ++i) solve.command_line += (i ? " " : "") + std::string(argv[i]);
    mpath::run_solve(options, solve);
  });
}

}  // namespace

int main(int argc, char** argv) {
  mpath::use_huge_pages(argv);        // first: it may run the program again in place
  mpath::Ranks::start(&argc, &argv);  // MPI, when mpirun or srun started this process
  const int status = solve_main(argc, argv);
  mpath::Ranks::finish(status);
  return status;
}
