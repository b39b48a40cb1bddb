// What mpath's programs share on the command line: the common flags, logging
// to stderr, and turning errors into one line and an exit status.
#pragma once

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "process_memory.h"
#include "config.h"
#include "config_keys.h"
#include "error.h"
#include "mpath_version.h"
#include "interrupt.h"
#include "progress.h"

namespace mpath {

struct ProgramFlags {
  std::string config;
  std::vector<std::string> overrides;
  bool print_config = false, quiet = false, dry_run = false;
  std::string log_level = "info";
};

inline void add_common_flags(CLI::App& app, ProgramFlags& f) {
  app.set_version_flag("--version", std::string(app.get_name()) + " " + MPATH_VERSION + " (" + MPATH_GIT_COMMIT + ")",
                       "print the version and exit");
  app.add_option("config", f.config, "TOML config file")->required();
  app.add_option("overrides", f.overrides, "key=value overrides of config values (dotted TOML keys)");
  app.add_flag("--print-config", f.print_config, "print the effective config and exit");
  app.add_flag_callback(
      "--list-keys",
      [] {
        std::cout << config_keys_markdown();
        throw CLI::Success();
      },
      "print every config key with its default and meaning, and exit");
  app.add_flag("--dry-run", f.dry_run, "check config and scene, then stop");
  app.add_flag("-q,--quiet", f.quiet, "no progress and no log below warnings");
  app.add_option("--log-level", f.log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
}

// Parses the command line. --help and --version print and give exit status
// 0; a usage error prints `NAME: error: ...` and gives 1. Returns the exit
// status when the program should stop, -1 when it should go on.
inline int parse_command_line(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::Success&) {
    return 0;
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: error: %s (see %s --help)\n", app.get_name().c_str(), printable(e.what()).c_str(), app.get_name().c_str());
    return 1;
  }
  return -1;
}

// Sets up logging and interrupt handling (`advice`: what to do after an
// interruption), loads the config, prints it (--print-config: only that)
// and runs `body`; bad input exits 1 and anything else 2, with one line on stderr.
template <typename Body>
int run_program(const char* name, const char* advice, const ProgramFlags& f, Body body) {
  install_interrupt_handlers(name, advice);
  keep_freed_memory();
  spdlog::set_default_logger(spdlog::stderr_logger_mt("mpath"));
  spdlog::set_pattern("[%H:%M:%S] %^%l%$ %v");
  spdlog::set_level(f.quiet ? spdlog::level::warn : spdlog::level::from_str(f.log_level));
  Progress::set_enabled_default(!f.quiet);
  try {
    const Options options = load_options(f.config, f.overrides);
    if (f.print_config) {
      std::cout << options_to_toml(options);
      return 0;
    }
    if (!f.quiet) std::cerr << "# effective config\n" << options_to_toml(options);
    body(options);
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s: error: %s\n", name, printable(e.what()).c_str());
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    // A folder that cannot be made or a file that cannot be written: the
    // user's paths or disk, not mpath's state.
    std::fprintf(stderr, "%s: error: %s: %s\n", name, printable(e.path1().string()).c_str(), e.code().message().c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", name, printable(e.what()).c_str());
    return 2;
  }
  return 0;
}

}  // namespace mpath
