// The store's manifest (manifest.json): what made the store (format version,
// scene and mesh hashes, every config value that shaped it) and its files
// (lines, events, sizes and checksums). mpath-solve refuses a store whose
// manifest does not match its own scene and config.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace mpath::linestore {

struct StoreFile {
  std::string name;  // relative to the store folder
  uint32_t box = 0;
  uint64_t first_line = 0;
  uint64_t lines = 0;
  uint64_t events = 0;
  uint64_t chunks = 0;
  uint64_t bytes = 0;
  std::string hash;  // hash_file (util/hash.h) of the whole file
};

// One box of the hierarchy as the store records it (the solver rebuilds the
// hierarchy from the scene and checks it against these).
struct BoxEntry {
  int parent = -1;
  int depth = 0;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  uint64_t lines = 0;    // lines traced for this box
  uint64_t patches = 0;  // patches directly in it
  uint64_t ars = 0;      // ARs of its walls
  uint64_t objects = 0;  // objects in it and its children
  double quotient = 0;
  std::vector<int> direct_objects;  // the grouping's objects directly in it (the solver assembles the hierarchy from them)
  bool operator==(const BoxEntry&) const = default;
};

struct Manifest {
  uint32_t format_version = 0;
  std::string mpath_version;
  // Values that shaped the store: "scene.file_hash", "mesh.hash", config keys...
  std::map<std::string, std::string> identity;
  uint64_t patches = 0;
  uint64_t faces = 0;
  uint64_t lines_total = 0;
  uint64_t chunk_lines = 0;
  // The first shot's local lines of first_shot.bin (the pilot's choice where
  // first_shot.lines was 0); 0 in stores made before it was recorded.
  uint64_t first_shot_lines = 0;
  std::vector<BoxEntry> boxes;
  std::vector<StoreFile> files;
};

void write_manifest(const std::filesystem::path& path, const Manifest& manifest);
// Throws InputError naming the file when it is missing, malformed or of another version.
Manifest read_manifest(const std::filesystem::path& path);

// The first key whose value differs between `expected` and `found`, as
// "key: store has X, this run has Y"; empty when they agree.
std::string identity_mismatch(const std::map<std::string, std::string>& expected,
                              const std::map<std::string, std::string>& found);

}  // namespace mpath::linestore
