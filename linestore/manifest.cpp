#include "manifest.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "atomic_file.h"
#include "box_file.h"
#include "error.h"

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
                     {"patches", b.patches}, {"ars", b.ars}, {"objects", b.objects}, {"quotient", b.quotient}});
  const json j = {{"format_version", m.format_version}, {"mpath_version", m.mpath_version},
                  {"identity", m.identity},             {"patches", m.patches},
                  {"faces", m.faces},                   {"lines_total", m.lines_total},
                  {"chunk_lines", m.chunk_lines},       {"boxes", boxes},
                  {"files", files}};
  AtomicFile file(path, partial_path(path));
  file.stream() << j.dump(2) << "\n";
  file.commit();
}

Manifest read_manifest(const fs::path& path) {
  if (!fs::exists(path))
    throw InputError(fmt::format("{}: missing; run mpath-preprocess with this config first", path.string()));
  std::ifstream in(path);
  json j;
  try {
    j = json::parse(in);
    Manifest m;
    m.format_version = j.at("format_version").get<uint32_t>();
    if (m.format_version != kFormatVersion)
      throw InputError(fmt::format("{}: store format version {} (this mpath reads version {}); re-run mpath-preprocess",
                                   path.string(), m.format_version, kFormatVersion));
    m.mpath_version = j.at("mpath_version").get<std::string>();
    m.identity = j.at("identity").get<std::map<std::string, std::string>>();
    m.patches = j.at("patches").get<uint64_t>();
    m.faces = j.at("faces").get<uint64_t>();
    m.lines_total = j.at("lines_total").get<uint64_t>();
    m.chunk_lines = j.at("chunk_lines").get<uint64_t>();
    for (const json& b : j.at("boxes")) {
      BoxEntry e;
      e.parent = b.at("parent").get<int>();
      e.depth = b.at("depth").get<int>();
      for (int i = 0; i < 3; ++i) {
        e.lo[i] = b.at("lo").at(i).get<double>();
        e.hi[i] = b.at("hi").at(i).get<double>();
      }
      e.lines = b.at("lines").get<uint64_t>();
      e.patches = b.at("patches").get<uint64_t>();
      e.ars = b.at("ars").get<uint64_t>();
      e.objects = b.at("objects").get<uint64_t>();
      e.quotient = b.at("quotient").get<double>();
      m.boxes.push_back(e);
    }
    for (const json& f : j.at("files"))
      m.files.push_back({f.at("name").get<std::string>(), f.at("box").get<uint32_t>(), f.at("first_line").get<uint64_t>(),
                         f.at("lines").get<uint64_t>(), f.at("events").get<uint64_t>(), f.at("chunks").get<uint64_t>(),
                         f.at("bytes").get<uint64_t>(), f.at("hash").get<std::string>()});
    return m;
  } catch (const json::exception& e) {
    throw InputError(fmt::format("{}: malformed manifest: {}", path.string(), e.what()));
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
