// JSON as mpath writes it (report.json, compare.json, preprocess.json, the
// store's manifest): indented by two, and bytes that are not UTF-8 (a name
// from a damaged or foreign file) replaced rather than an error.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace mpath {

inline std::string json_text(const nlohmann::json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace mpath
