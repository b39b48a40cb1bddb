// The line store as the solver reads it (docs/method.md, 6 and 7): the
// manifest checked against this run's scene and config, the hierarchy rebuilt
// and checked against the one the store was made with, every box file opened
// and checked, and per box what its passes need: its own faces (numbered
// locally), exact crossing counts, transmittances of its walls' ARs, where
// power held in an AR that no line can carry is moved, and its chunks.
#pragma once

#include <exception>
#include <optional>
#include <filesystem>
#include <memory>

#include <tbb/enumerable_thread_specific.h>
#include <vector>

#include "box_file.h"
#include "config.h"
#include "hierarchy.h"
#include "manifest.h"
#include "mesh.h"

namespace mpath {

inline constexpr uint32_t kNoTarget = 0xFFFFFFFFu;

struct LineSets;

// A box's own patch as its passes read it: its local faces {front, back or
// -1 (black) or kInvisibleSide} and its contact plane
// (PatchMesh::contact_plane), in one load of 16 bytes.
struct alignas(16) LocalPatch {
  std::array<int, 2> faces{kBlackSide, kBlackSide};
  int contact = -1;
  int& operator[](size_t side) { return faces[side]; }
  const int& operator[](size_t side) const { return faces[side]; }
  const int* begin() const { return faces.data(); }
  const int* end() const { return faces.data() + 2; }
};

struct StoreBox {
  // Faces of the box's own patches: local patch k has local faces
  // local_faces[k] = {front, back or -1}; face_global maps them to the mesh.
  std::vector<LocalPatch> local_faces;
  std::vector<int> face_global;
  std::vector<double> face_crossings;  // per local face
  // Per local face: itself when the box's lines cross it; else the nearest
  // crossed face of the same polygon facing the same way, which sends its
  // power for it (-1: none; the power stays unshot).
  std::vector<int> face_proxy;
  linestore::BoxCounts counts;         // summed over the box's files
  std::vector<double> transmittance;   // per wall AR: n_R^d / n_R, interpolated where n_R = 0
  // Per wall AR, the AR whose power it hands on when no line can carry its
  // own (itself when one can; kNoTarget when no AR of the box can):
  std::vector<uint32_t> in_target;     // In: lines meeting something inside
  std::vector<uint32_t> out_target;    // Out: lines of the parent crossing it
  size_t ar_base = 0;                  // first of its ARs in the state's AR arrays
  std::vector<uint32_t> child_ar_base; // per child: first of its ARs in counts.child_crossings
  // Chunks: (file, chunk within the file), in line order.
  std::vector<std::pair<uint32_t, uint32_t>> chunks;
  std::vector<uint64_t> chunk_lines;  // lines in each
  uint64_t lines = 0, events = 0, bytes = 0;
  // The least share of its lines a pass takes: enough for its median face to
  // be crossed 16 times and its walls' ARs 4 times on average; at least 1/4
  // for a subscene.
  double coverage = 1;
};

// The local face of a stored patch crossing turned towards `dir` along the
// line (+1: the way the line runs; -1: back); -1 for a black back side.
inline int face_towards(const StoreBox& box, const linestore::Event& e, int dir) {
  const auto& f = box.local_faces[e.id];
  return (dir > 0) == e.along ? f[0] : f[1];
}

// Whether the patch crossings `a` and `b`, neighbours on a line, touch
// (PatchMesh::touching): the faces they turn towards each other exchange
// nothing. Both must be patch crossings. Without branches on the contact
// planes, which a fifth of a furnished scene's patches have, at random.
inline bool touching(const StoreBox& box, const linestore::Event& a, const linestore::Event& b) {
  const int ca = box.local_faces[a.id].contact, cb = box.local_faces[b.id].contact;
  return (ca >= 0) & (ca == cb);
}

// A store's manifest and its files checked against it (a plain name, the
// size and the hash recorded for each), which needs no scene: mpath-solve
// checks them on another thread while it loads and meshes the scene, then
// hands them to BoxStore. Throws when the manifest cannot be read; a
// missing, cut or damaged file is kept in `damage`, thrown by BoxStore once
// the store is known to be this scene's (a store of another scene is named
// as such, not by its first differing file). No MPI call: any thread may
// run it.
struct CheckedFiles {
  linestore::Manifest manifest;
  std::exception_ptr damage;
};
CheckedFiles check_store_files(const std::filesystem::path& dir);

class BoxStore {
 public:
  // Throws InputError naming the mismatching key, the differing hierarchy, or
  // the missing, truncated or foreign file. Without `checked` it reads the
  // manifest and checks the files itself (after the identity, so that a
  // store of another scene is not hashed first).
  BoxStore(const Options& options, const PatchMesh& mesh, std::optional<CheckedFiles> checked = std::nullopt);

  const linestore::Manifest& manifest() const { return manifest_; }
  // The store's lines.seed (its identity holds it): the passes' line orders
  // depend on it (chunk_line_order).
  unsigned long long seed() const { return seed_; }
  // The line-set data of a store of transparent boxes (hierarchy.transport =
  // "lines"), derived from every line at opening; null otherwise.
  const LineSets* line_sets() const { return line_sets_.get(); }
  const Hierarchy& hierarchy() const { return hierarchy_; }
  const StoreBox& box(int b) const { return boxes_[b]; }
  size_t box_count() const { return boxes_.size(); }
  size_t ar_total() const { return ar_total_; }
  uint64_t lines() const { return total(&StoreBox::lines); }
  uint64_t events() const { return total(&StoreBox::events); }
  uint64_t bytes() const { return total(&StoreBox::bytes); }
  // Per mesh face: crossings by the lines of every box that holds it.
  std::vector<double> face_crossings(size_t faces) const;
  // The same for the root's lines alone (those that cross the whole scene).
  std::vector<double> root_crossings(size_t faces) const;
  // Per mesh face: crossed by the lines of any box.
  std::vector<bool> faces_crossed(size_t faces) const;

  // Reads a chunk with the calling thread's readers, which stay open from
  // pass to pass (a thread runs one chunk at a time).
  void read(int box, uint64_t chunk, linestore::DecodedChunk& out) const;
  // Lines order[0 .. take) of the chunk, in that order (a pass's, decoded
  // straight into its order: linestore::decode_chunk_lines).
  // With `sides`, each kept event's sides written from it (linestore::EventSides).
  void read_lines(int box, uint64_t chunk, const uint32_t* order, size_t take, linestore::DecodedChunk& out,
                  const linestore::EventSides* sides = nullptr) const;
  uint64_t chunk_lines(int box, uint64_t chunk) const { return boxes_[box].chunk_lines[chunk]; }

 private:
  // The steps of the constructor: the manifest against this scene, config and
  // hierarchy; each box's faces and AR offsets; every file opened and checked
  // against the manifest, its counts summed; what the passes derive from them.
  void check_against(const Options& options, const PatchMesh& mesh, const std::filesystem::path& manifest_path);
  void lay_out_boxes(const PatchMesh& mesh);
  void open_files(const std::filesystem::path& dir, const std::filesystem::path& manifest_path);
  void derive_box_data(const PatchMesh& mesh, size_t b);
  uint64_t total(uint64_t StoreBox::*field) const;
  // The calling thread's reader of the file holding the chunk, and the chunk's index in it.
  linestore::BoxFileReader& reader(int box, uint64_t chunk, uint32_t& local) const;

  linestore::Manifest manifest_;
  Hierarchy hierarchy_;
  std::vector<StoreBox> boxes_;
  std::vector<std::filesystem::path> files_;
  using Readers = std::vector<std::unique_ptr<linestore::BoxFileReader>>;
  mutable tbb::enumerable_thread_specific<Readers> readers_;
  std::shared_ptr<const LineSets> line_sets_;
  size_t ar_total_ = 0;
  unsigned long long seed_ = 0;
};

// Transmittance of every AR from its counts (exposed for tests).
std::vector<double> transmittances(const SceneBox& box, const std::vector<uint32_t>& lines,
                                   const std::vector<uint32_t>& open);
// Per AR: itself if `valid`, else the nearest valid AR (same face, sector and
// band, nearest VP; else the same face; else the box), kNoTarget if none is.
std::vector<uint32_t> redirect_targets(const SceneBox& box, const std::vector<bool>& valid);

}  // namespace mpath
