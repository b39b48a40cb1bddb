#include "config.h"

#include <algorithm>
#include <cmath>
#include <toml++/toml.h>

#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "config_keys.h"
#include "error.h"

namespace mpath {
namespace {

namespace fs = std::filesystem;

std::string where(const toml::node& node, const fs::path& file) {
  return fmt::format("{}:{}", file.string(), node.source().begin.line);
}

// Applies every value of `table` (recursively), naming unknown keys.
void apply_table(const toml::table& table, const std::string& prefix, const fs::path& file,
                 const std::set<std::string>& cli_keys, Options& options) {
  for (const auto& [k, node] : table) {
    const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    const ConfigKey* known = find_config_key(key);
    const bool from_cli = cli_keys.count(key) > 0;
    ValueSource src{key, from_cli ? "command line" : where(node, file), from_cli,
                    from_cli ? fs::current_path() : file.parent_path()};
    if (known) {
      known->set(node, src, options);
    } else if (const toml::table* sub = node.as_table()) {
      apply_table(*sub, key, file, cli_keys, options);
    } else {
      throw InputError(fmt::format("{}: unknown config key '{}'", src.where, key));
    }
  }
}

// Parses the right-hand side of key=value as TOML; a bare word is a string.
toml::table parse_override_value(const std::string& text) {
  try {
    return toml::parse("v = " + text);
  } catch (const toml::parse_error&) {
    toml::table t;
    t.insert("v", text);
    return t;
  }
}

void apply_override(toml::table& root, const std::string& assignment, std::set<std::string>& cli_keys) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(fmt::format("command line: expected key=value, got '{}'", assignment));
  const std::string key = assignment.substr(0, eq);
  toml::table value = parse_override_value(assignment.substr(eq + 1));
  toml::table* node = &root;
  size_t start = 0;
  for (;;) {
    const size_t dot = key.find('.', start);
    const std::string part = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (part.empty()) throw InputError(fmt::format("command line: malformed key '{}'", key));
    if (dot == std::string::npos) {
      node->insert_or_assign(part, std::move(*value.get("v")));
      break;
    }
    auto [it, inserted] = node->insert(part, toml::table{});
    if (it->second.is_array_of_tables())
      throw InputError(fmt::format("command line: '{}' is a list of tables ([[{}]]) and cannot be overridden by key "
                                   "'{}'; set it in the config file", part, part, key));
    node = it->second.as_table();
    if (!node) throw InputError(fmt::format("command line: '{}' is not a table in key '{}'", part, key));
    start = dot + 1;
  }
  cli_keys.insert(key);
}

// The effective options as nested TOML tables, a table per dotted prefix.
toml::table options_table(const Options& o) {
  toml::table root;
  for (const ConfigKey& k : config_keys()) {
    toml::array value = k.get(o);
    if (value.empty()) continue;
    toml::table* section = &root;
    size_t start = 0;
    for (size_t dot; (dot = k.key.find('.', start)) != std::string::npos; start = dot + 1)
      section = section->insert(k.key.substr(start, dot - start), toml::table{}).first->second.as_table();
    section->insert_or_assign(k.key.substr(start), *value.get(0));
  }
  return root;
}

}  // namespace

Options load_options(const fs::path& config_path, const std::vector<std::string>& overrides) {
  if (!fs::exists(config_path)) throw InputError(fmt::format("{}: config file not found", config_path.string()));
  const fs::path file = fs::absolute(config_path).lexically_normal();
  toml::table root;
  try {
    root = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw InputError(fmt::format("{}:{}: malformed TOML: {}", file.string(), e.source().begin.line,
                                 std::string(e.description())));
  }
  std::set<std::string> cli_keys;
  for (const auto& assignment : overrides) apply_override(root, assignment, cli_keys);

  Options options;
  options.config_file = file;
  // Default folders live beside the config file, like the paths written in it.
  options.store.dir = file.parent_path() / options.store.dir;
  options.output.dir = file.parent_path() / options.output.dir;
  apply_table(root, "", file, cli_keys, options);
  if (options.scene.file.empty()) throw InputError(fmt::format("{}: config key 'scene.file' is required", file.string()));
  if (options.first_shot.accelerate && options.hierarchy.transport == "lines")
    throw InputError(fmt::format("{}: config key 'first_shot.accelerate' needs the associated patches of "
                                 "hierarchy.transport = \"transmittance\" (the \"lines\" transport has none)",
                                 file.string()));
  return options;
}

std::string options_to_toml(const Options& options) {
  std::ostringstream out;
  out << options_table(options) << "\n";
  return out.str();
}

std::string options_to_json(const Options& options) {
  std::ostringstream out;
  out << toml::json_formatter{options_table(options)};
  return out.str();
}

long long first_shot_lines(const Options& options) {
  if (options.first_shot.lines > 0) return options.first_shot.lines;
  if (options.first_shot.chosen > 0) return options.first_shot.chosen;
  return std::max<long long>(10'000, options.lines.total / 2);
}

long long first_shot_lines_for_share(const Options& options, double share) {
  if (!(share > 0)) return first_shot_lines(options);  // called before first_shot.chosen is set
  return std::max<long long>(10'000, std::llround(share * static_cast<double>(options.lines.total)));
}

int effective_threads(const Options& options) {
  if (options.solver.threads > 0) return options.solver.threads;
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace mpath
