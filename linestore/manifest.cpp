#include "manifest.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "atomic_file.h"
#include "box_file.h"
#include "error.h"
#include "json_text.h"

namespace mpath::linestore {

namespace fs = std::filesystem;
using json = nlohmann::json;

void write_manifest(const fs::path& path, const Manifest& m) {
  json files = json::array();
  for (const StoreFile& f : m.files)
    files.push_back({{"name", f.name}, {"box", f.box}, {"first_line", f.first_line}, {"lines", f.lines},
                     {"events", f.events}, {"chunks", f.chunks}, {"bytes", f.bytes}, {"hash", f.hash}});
  json boxes = json::array();
  for (const BoxEntry& b : m.boxes)
    boxes.push_back({{"parent", b.parent}, {"depth", b.depth}, {"lo", b.lo}, {"hi", b.hi}, {"lines", b.lines},
                     {"patches", b.patches}, {"ars", b.ars}, {"objects", b.objects}, {"quotient", b.quotient},
                     {"direct_objects", b.direct_objects}});
  const json j = {{"format_version", m.format_version}, {"mpath_version", m.mpath_version},
                  {"identity", m.identity},             {"patches", m.patches},
                  {"faces", m.faces},                   {"lines_total", m.lines_total},
                  {"chunk_lines", m.chunk_lines},       {"first_shot_lines", m.first_shot_lines},
                  {"boxes", boxes},
                  {"files", files}};
  AtomicFile file(path, partial_path(path));
  file.stream() << json_text(j);
  file.commit();
}

Manifest read_manifest(const fs::path& path) {
  if (!fs::exists(path))
    throw InputError(fmt::format("{}: missing; run mpath-preprocess with this config first", path.string()));
  std::ifstream in(path);
  json j;
  // Counts must be whole numbers in range: a float or a negative number in
  // their place is damage (and no cast is made of a value that does not fit).
  const auto whole_value = [&](const json& x, const std::string& what, double most) {
    if (!x.is_number_integer() || (x.is_number_unsigned() ? double(x.get<uint64_t>()) > most : x.get<int64_t>() < -1 ||
                                                                                                    double(x.get<int64_t>()) > most))
      throw json::type_error::create(302, fmt::format("'{}' is not a whole number in range", what), &x);
    return x;
  };
  const auto whole = [&](const json& v, const char* key, double most) { return whole_value(v.at(key), key, most); };
  const auto count = [&](const json& v, const char* key) {
    const json x = whole(v, key, 1.8e19);
    if (!x.is_number_unsigned()) throw json::type_error::create(302, fmt::format("'{}' is negative", key), &x);
    return x.get<uint64_t>();
  };
  const auto small = [&](const json& v, const char* key) { return static_cast<int>(whole(v, key, 2e9).get<int64_t>()); };
  try {
    j = json::parse(in);
    Manifest m;
    m.format_version = static_cast<uint32_t>(small(j, "format_version"));
    if (m.format_version != kFormatVersion)
      throw InputError(fmt::format("{}: store format version {} (this mpath reads version {}); re-run mpath-preprocess",
                                   path.string(), m.format_version, kFormatVersion));
    m.mpath_version = j.at("mpath_version").get<std::string>();
    m.identity = j.at("identity").get<std::map<std::string, std::string>>();
    m.patches = count(j, "patches");
    m.faces = count(j, "faces");
    m.lines_total = count(j, "lines_total");
    m.chunk_lines = count(j, "chunk_lines");
    if (j.contains("first_shot_lines")) m.first_shot_lines = count(j, "first_shot_lines");
    for (const json& b : j.at("boxes")) {
      BoxEntry e;
      e.parent = small(b, "parent");
      e.depth = small(b, "depth");
      for (int i = 0; i < 3; ++i) {
        e.lo[i] = b.at("lo").at(i).get<double>();
        e.hi[i] = b.at("hi").at(i).get<double>();
      }
      e.lines = count(b, "lines");
      e.patches = count(b, "patches");
      e.ars = count(b, "ars");
      e.objects = count(b, "objects");
      e.quotient = b.at("quotient").get<double>();
      const json& direct = b.at("direct_objects");
      if (!direct.is_array()) throw json::type_error::create(302, "'direct_objects' is not a list", &direct);
      for (size_t k = 0; k < direct.size(); ++k) e.direct_objects.push_back(static_cast<int>(whole_value(direct[k], "direct_objects", 2e9).get<int64_t>()));
      m.boxes.push_back(e);
    }
    for (const json& f : j.at("files"))
      m.files.push_back({f.at("name").get<std::string>(), static_cast<uint32_t>(small(f, "box")), count(f, "first_line"),
                         count(f, "lines"), count(f, "events"), count(f, "chunks"),
                         count(f, "bytes"), f.at("hash").get<std::string>()});
    return m;
  } catch (const json::exception& e) {
    // nlohmann's messages start "[json.exception.KIND.ID] ": the rest says what is wrong.
    std::string what = e.what();
    if (what.rfind("[json.exception.", 0) == 0 && what.find("] ") != std::string::npos) what = what.substr(what.find("] ") + 2);
    throw InputError(fmt::format("{}: malformed manifest: {}", path.string(), what));
  }
}

std::string identity_mismatch(const std::map<std::string, std::string>& expected,
                              const std::map<std::string, std::string>& found) {
  for (const auto& [key, value] : expected) {
    auto it = found.find(key);
    if (it == found.end()) return fmt::format("{}: the store does not record it", key);
    if (it->second != value) return fmt::format("{}: the store was made with {}, this run has {}", key, it->second, value);
  }
  for (const auto& [key, value] : found)
    if (!expected.count(key)) return fmt::format("{}: the store records {}, which this run does not know", key, value);
  return "";
}

}  // namespace mpath::linestore
