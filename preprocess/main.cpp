// mpath-preprocess: meshes the scene and writes the line store for mpath-solve.
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "error.h"
#include "preprocess.h"
#include "progress.h"

int main(int argc, char** argv) {
  CLI::App app{"mpath-preprocess: traces and stores the global lines of a scene"};
  std::string config, shard = "1/1";
  std::vector<std::string> overrides;
  bool print_config = false, quiet = false, dry_run = false;
  std::string log_level = "info";
  app.add_option("config", config, "TOML config file")->required();
  app.add_option("overrides", overrides, "key=value overrides of config values (dotted TOML keys)");
  app.add_option("--shard", shard, "trace part i of n (i/n) of the lines; run every part, in any order");
  app.add_flag("--print-config", print_config, "print the effective config and exit");
  app.add_flag("--dry-run", dry_run, "check config and scene, trace nothing");
  app.add_flag("-q,--quiet", quiet, "no progress and no log below warnings");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  spdlog::set_default_logger(spdlog::stderr_logger_mt("mpath"));
  spdlog::set_pattern("[%H:%M:%S] %^%l%$ %v");
  spdlog::set_level(quiet ? spdlog::level::warn : spdlog::level::from_str(log_level));
  mpath::Progress::set_enabled_default(!quiet);
  try {
    const mpath::Options options = mpath::load_options(config, overrides);
    if (print_config) {
      std::cout << mpath::options_to_toml(options);
      return 0;
    }
    const mpath::ShardSpec spec = mpath::parse_shard(shard);
    if (!quiet) std::cerr << "# effective config\n" << mpath::options_to_toml(options);
    mpath::run_preprocess(options, spec, dry_run);
  } catch (const mpath::InputError& e) {
    std::fprintf(stderr, "mpath-preprocess: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mpath-preprocess: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
