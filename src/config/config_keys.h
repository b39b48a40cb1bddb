// The table of config keys: for every key, how its value is read and checked,
// how the effective value prints, and its line in docs/user-guide.md. Parsing,
// --print-config and the user guide's key table all come from it; a key's
// default is the value it prints for a default-constructed Options.
#pragma once

#include <toml++/toml.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "config.h"

namespace mpath {

// Where a value came from, for messages and for resolving relative paths.
struct ValueSource {
  std::string key;
  std::string where;  // "file:line" or "command line"
  bool from_command_line = false;
  std::filesystem::path base_dir;  // relative paths are taken from here
};

struct ConfigKey {
  std::string key;      // dotted TOML path ("lines.total"); "camera" is the [[camera]] array
  std::string meaning;  // one line for the user guide
  // Reads and checks the value into the options; InputError naming the key.
  std::function<void(const toml::node&, const ValueSource&, Options&)> set;
  // The effective value as a one-element array (empty: the key is not set).
  std::function<toml::array(const Options&)> get;
};

const std::vector<ConfigKey>& config_keys();
// The key, or nullptr.
const ConfigKey* find_config_key(const std::string& key);

// The user guide's table of keys (markdown: key, default, meaning).
std::string config_keys_markdown();

}  // namespace mpath
