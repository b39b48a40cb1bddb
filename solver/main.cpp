// mpath-solve: solves the radiosity of a scene described by a TOML config.
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>

#include "error.h"
#include "progress.h"
#include "solve.h"

int main(int argc, char** argv) {
  CLI::App app{"mpath-solve: hierarchical Multipath radiosity solver"};
  std::string config;
  std::vector<std::string> overrides;
  bool resume = false, print_config = false, quiet = false, dry_run = false;
  std::string log_level = "info";
  app.add_option("config", config, "TOML config file")->required();
  app.add_option("overrides", overrides, "key=value overrides of config values (dotted TOML keys)");
  app.add_flag("--resume", resume, "continue from the last checkpoint");
  app.add_flag("--print-config", print_config, "print the effective config and exit");
  app.add_flag("--dry-run", dry_run, "check config and scene, solve nothing");
  app.add_flag("-q,--quiet", quiet, "no progress and no log below warnings");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  auto logger = spdlog::stderr_logger_mt("mpath");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("[%H:%M:%S] %^%l%$ %v");
  spdlog::set_level(quiet ? spdlog::level::warn : spdlog::level::from_str(log_level));
  mpath::Progress::set_enabled_default(!quiet);

  try {
    const mpath::Options options = mpath::load_options(config, overrides);
    if (print_config) {
      std::cout << mpath::options_to_toml(options);
      return 0;
    }
    if (!quiet) std::cerr << "# effective config\n" << mpath::options_to_toml(options);
    mpath::SolveFlags flags;
    flags.resume = resume;
    flags.dry_run = dry_run;
    for (int i = 0; i < argc; ++i) flags.command_line += (i ? " " : "") + std::string(argv[i]);
    mpath::run_solve(options, flags);
  } catch (const mpath::InputError& e) {
    std::fprintf(stderr, "mpath-solve: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mpath-solve: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
