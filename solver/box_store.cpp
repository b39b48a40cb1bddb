#include "box_store.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "line_sets.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "error.h"
#include "hash.h"
#include "nearest_point.h"
#include "ranks.h"
#include "progress.h"
#include "store_identity.h"

namespace mpath {

namespace fs = std::filesystem;

namespace {

// ARs of the same sector and band in the VPs at Chebyshev distance r of (column, row).
template <typename Visit>
void ring(const SceneBox& box, const SceneBox::ArPlace& p, int r, Visit visit) {
  const int n = box.grid[p.face];
  for (int row = p.row - r; row <= p.row + r; ++row)
    for (int column = p.column - r; column <= p.column + r; ++column) {
      if (row < 0 || column < 0 || row >= n || column >= n) continue;
      if (std::max(std::abs(row - p.row), std::abs(column - p.column)) != r) continue;
      SceneBox::ArPlace q = p;
      q.row = row;
      q.column = column;
      visit(box.ar_of(q), (row - p.row) * (row - p.row) + (column - p.column) * (column - p.column));
    }
}

}  // namespace

std::vector<double> transmittances(const SceneBox& box, const std::vector<uint32_t>& lines,
                                   const std::vector<uint32_t>& open) {
  const uint32_t ars = box.ar_count();
  std::vector<double> t(ars, -1.0);
  double sum = 0;
  int known = 0;
  for (uint32_t r = 0; r < ars; ++r)
    if (lines[r] > 0) {
      t[r] = double(open[r]) / lines[r];
      sum += t[r];
      ++known;
    }
  const double box_mean = known > 0 ? sum / known : 1.0;
  for (uint32_t r = 0; r < ars; ++r) {
    if (lines[r] > 0) continue;
    const SceneBox::ArPlace p = box.place(r);
    // The other directions over the same VP...
    double s = 0;
    int n = 0;
    for (int sector = 0; sector < kSectors; ++sector)
      for (int band = 0; band < kBands; ++band) {
        SceneBox::ArPlace q = p;
        q.sector = sector;
        q.band = band;
        const uint32_t a = box.ar_of(q);
        // Neighbouring directions only: adjacent sector (cyclic) and band.
        const int ds = std::min((sector - p.sector + kSectors) % kSectors, (p.sector - sector + kSectors) % kSectors);
        if (lines[a] > 0 && ds <= 1 && std::abs(band - p.band) <= 1) {
          s += double(open[a]) / lines[a];
          ++n;
        }
      }
    // ...else the same direction over the nearest VPs that have lines...
    for (int radius = 1; n == 0 && radius < box.grid[p.face]; ++radius)
      ring(box, p, radius, [&](uint32_t a, int) {
        if (lines[a] > 0) {
          s += double(open[a]) / lines[a];
          ++n;
        }
      });
    // ...else the box's mean.
    t[r] = n > 0 ? s / n : box_mean;
  }
  return t;
}

std::vector<uint32_t> redirect_targets(const SceneBox& box, const std::vector<bool>& valid) {
  const uint32_t ars = box.ar_count();
  std::vector<uint32_t> target(ars, kNoTarget);
  uint32_t any = kNoTarget;
  std::array<uint32_t, 6> face_any;
  face_any.fill(kNoTarget);
  for (uint32_t r = 0; r < ars; ++r)
    if (valid[r]) {
      if (any == kNoTarget) any = r;
      const int f = box.place(r).face;
      if (face_any[f] == kNoTarget) face_any[f] = r;
    }
  for (uint32_t r = 0; r < ars; ++r) {
    if (valid[r]) {
      target[r] = r;
      continue;
    }
    const SceneBox::ArPlace p = box.place(r);
    uint32_t best = kNoTarget;
    int best_d = 0;
    for (int radius = 1; best == kNoTarget && radius < box.grid[p.face]; ++radius)
      ring(box, p, radius, [&](uint32_t a, int d) {
        if (valid[a] && (best == kNoTarget || d < best_d || (d == best_d && a < best))) {
          best = a;
          best_d = d;
        }
      });
    if (best == kNoTarget) best = face_any[p.face];
    if (best == kNoTarget) best = any;
    target[r] = best;
  }
  return target;
}

namespace {

// The least share of its lines a subscene's pass takes. Power held in the
// ARs of a subscene's walls and of its children leaves only along lines
// crossing those ARs; with fewer lines per pass most ARs see none and their
// power waits: on a furnished office, floors of 0.25, 0.5 and 1 reached
// 1e-3 of the emitted power left in 1.6 s, 1.9 s and 2.6 s, and no floor
// stalled above it (docs/algorithm.md).
constexpr double kSubsceneCoverage = 0.25;

Vec3 patch_centre(const PatchMesh& mesh, const Patch& p) {
  Vec3 c;
  for (uint32_t v : p.v) c += mesh.vertices[v];
  return c * 0.25;
}

// A face no line of its box crosses (a small patch in a box with few lines)
// could never send its power: the nearest crossed face of its polygon, on
// the same side, sends it instead; failing that, the nearest crossed face of
// its object facing within 45 degrees of it.
std::vector<int> face_proxies(const PatchMesh& mesh, const SceneBox& sb, const StoreBox& box) {
  std::vector<int> proxy(box.face_global.size(), -1);
  // (polygon or object, side) -> its crossed patches, and the search over
  // their centres, made when a face first asks.
  struct Group {
    std::vector<int> patches;
    std::optional<NearestPoint> centres;
  };
  std::map<std::pair<int, int>, Group> by_polygon, by_object;
  for (size_t k = 0; k < box.local_faces.size(); ++k)
    for (int side = 0; side < 2; ++side) {
      const int f = box.local_faces[k][side];
      if (f < 0 || !(box.face_crossings[f] > 0)) continue;
      proxy[f] = f;
      const Patch& p = mesh.patches[sb.patches[k]];
      by_polygon[{p.polygon, side}].patches.push_back(static_cast<int>(k));
      by_object[{p.object, side}].patches.push_back(static_cast<int>(k));
    }
  for (size_t k = 0; k < box.local_faces.size(); ++k)
    for (int side = 0; side < 2; ++side) {
      const int f = box.local_faces[k][side];
      if (f < 0 || proxy[f] >= 0) continue;
      const Patch& patch = mesh.patches[sb.patches[k]];
      const Vec3 c = patch_centre(mesh, patch);
      // The nearest crossed patch of the group whose normal is within
      // acos(min_cos) of this one's (NaN cosines not refused, as before).
      auto nearest = [&](Group& g, double min_cos) {
        if (!g.centres) {
          std::vector<Vec3> centres;
          centres.reserve(g.patches.size());
          for (int j : g.patches) centres.push_back(patch_centre(mesh, mesh.patches[sb.patches[j]]));
          g.centres.emplace(std::move(centres));
        }
        const int i = g.centres->nearest(c, [&](int i) {
          return !(dot(mesh.patches[sb.patches[g.patches[i]]].normal, patch.normal) < min_cos);
        });
        if (i >= 0) proxy[f] = box.local_faces[g.patches[i]][side];
      };
      if (auto it = by_polygon.find({patch.polygon, side}); it != by_polygon.end()) nearest(it->second, -2.0);
      if (proxy[f] < 0)
        if (auto it = by_object.find({patch.object, side}); it != by_object.end()) nearest(it->second, std::sqrt(0.5));
    }
  return proxy;
}

}  // namespace

namespace {

// Every file the manifest lists: a plain name, its size and its hash as
// recorded (before any work); the first found wrong, or null.
std::exception_ptr check_files(const fs::path& dir, const linestore::Manifest& manifest) try {
  const fs::path manifest_path = dir / "manifest.json";
  uint64_t bytes = 0;
  for (const linestore::StoreFile& f : manifest.files) {
    const fs::path name(f.name);
    if (name.empty() || name != name.filename() || f.name == "." || f.name == "..")
      throw InputError(fmt::format("{}: lists \"{}\", not a file name in the store's folder (damaged manifest); run "
                                   "mpath-preprocess again", manifest_path.string(), f.name));
    const fs::path path = dir / name;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
      throw InputError(fmt::format("{}: missing (listed in {})", path.string(), manifest_path.string()));
    const uint64_t size = fs::file_size(path, ec);
    if (ec || size != f.bytes)
      throw InputError(fmt::format("{}: {} bytes, the manifest says {} (truncated or from another run)", path.string(),
                                   size, f.bytes));
    bytes += size;
  }
  // The whole store is read once and hashed, in parallel, before any work:
  // damage or a file of another store of the same size is found now, not in
  // the middle of an iteration. MPI ranks share the files as they share a
  // pass's shards (Ranks::owns: a contiguous run each), so a shared file
  // system serves the store once; a rank that finds damage ends them all.
  const int file_count = static_cast<int>(manifest.files.size());
  const auto mine = [&](size_t i) { return Ranks::owns(static_cast<int>(i), file_count); };
  if (Ranks::size() > 1) {
    bytes = 0;
    for (size_t i = 0; i < manifest.files.size(); ++i)
      if (mine(i)) bytes += manifest.files[i].bytes;
  }
  Progress progress("checking store", bytes, "bytes", true);
  tbb::parallel_for(size_t{0}, manifest.files.size(), [&](size_t i) {
    if (!mine(i)) return;
    const linestore::StoreFile& f = manifest.files[i];
    const fs::path path = dir / f.name;
    if (hash_file(path) != f.hash)
      throw InputError(fmt::format("{}: its contents do not match the hash in {} (damaged, or a file of another "
                                   "store); run mpath-preprocess again", path.string(), manifest_path.string()));
    progress.advance(f.bytes);
  });
  progress.finish();
  return nullptr;
} catch (...) {
  return std::current_exception();
}

}  // namespace

CheckedFiles check_store_files(const fs::path& dir) {
  CheckedFiles checked{linestore::read_manifest(dir / "manifest.json"), nullptr};
  checked.damage = check_files(dir, checked.manifest);
  return checked;
}

BoxStore::BoxStore(const Options& options, const PatchMesh& mesh, std::optional<CheckedFiles> checked) {
  const fs::path manifest_path = options.store.dir / "manifest.json";
  manifest_ = checked ? std::move(checked->manifest) : linestore::read_manifest(manifest_path);
  check_against(options, mesh, manifest_path);
  seed_ = options.lines.seed;
  lay_out_boxes(mesh);
  const std::exception_ptr damage = checked ? checked->damage : check_files(options.store.dir, manifest_);
  if (damage) std::rethrow_exception(damage);
  // The ranks go on together once every one has checked its files: a rank
  // that found damage ends them all (Ranks::finish) while the others wait
  // here, so the error is the hash's, naming the file, and not whatever
  // another rank's passes meet later in that file (a chunk's own checksum).
  if (Ranks::size() > 1) {
    uint64_t agreed = 1;
    Ranks::sum(&agreed, 1);
  }
  open_files(options.store.dir, manifest_path);
  // Each box's data from its own counts and its parent's (read only here).
  tbb::parallel_for(size_t{0}, boxes_.size(), [&](size_t b) { derive_box_data(mesh, b); });
  if (hierarchy_.transparent)
    line_sets_ = std::make_shared<const LineSets>(derive_line_sets(*this, mesh));
}

void BoxStore::check_against(const Options& options, const PatchMesh& mesh, const fs::path& manifest_path) {
  const std::string mismatch = linestore::identity_mismatch(store_identity(options, mesh), manifest_.identity);
  if (!mismatch.empty())
    throw InputError(fmt::format("{}: the store does not match this scene and config: {}; run mpath-preprocess again",
                                 manifest_path.string(), mismatch));
  // The store's boxes as its manifest records them (grouping again took
  // minutes at a million polygons); the identity above makes them this
  // scene's, and every box is checked against its record below.
  std::vector<BoxLayout> layout;
  for (const linestore::BoxEntry& e : manifest_.boxes) layout.push_back({e.parent, e.depth, e.quotient, e.direct_objects});
  try {
    hierarchy_ = store_hierarchy(options, mesh, &layout);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {} (damaged manifest); run mpath-preprocess again", manifest_path.string(), e.what()));
  }
  const auto& recorded = manifest_.boxes;
  auto differs = [&](size_t b) {
    const SceneBox& box = hierarchy_.boxes[b];
    const linestore::BoxEntry& e = recorded[b];
    for (int i = 0; i < 3; ++i)
      if (e.lo[i] != box.bounds.lo[i] || e.hi[i] != box.bounds.hi[i]) return true;
    return e.parent != box.parent || e.patches != box.patches.size() || e.ars != box.ar_count();
  };
  if (recorded.size() != hierarchy_.boxes.size())
    throw InputError(fmt::format("{}: the store has {} box(es), this scene and config build {}; run mpath-preprocess again",
                                 manifest_path.string(), recorded.size(), hierarchy_.boxes.size()));
  for (size_t b = 0; b < recorded.size(); ++b)
    if (differs(b))
      throw InputError(fmt::format("{}: box {} of the store differs from the one this scene and config build; run "
                                   "mpath-preprocess again", manifest_path.string(), b));
}

void BoxStore::lay_out_boxes(const PatchMesh& mesh) {
  boxes_.resize(hierarchy_.boxes.size());
  for (size_t b = 0; b < boxes_.size(); ++b) {
    const SceneBox& sb = hierarchy_.boxes[b];
    StoreBox& box = boxes_[b];
    box.ar_base = ar_total_;
    ar_total_ += sb.ar_count();
    for (uint32_t p : sb.patches) {
      LocalPatch local;
      if (!mesh.contact_plane.empty()) local.contact = mesh.contact_plane[p];
      for (int side = 0; side < 2; ++side) {
        const int face = mesh.patch_faces[p][side];
        if (face < 0) {
          local[side] = face;  // black or invisible
          continue;
        }
        local[side] = static_cast<int>(box.face_global.size());
        box.face_global.push_back(face);
      }
      box.local_faces.push_back(local);
    }
    uint32_t offset = 0;
    for (int c : sb.children) {
      box.child_ar_base.push_back(offset);
      offset += hierarchy_.boxes[c].ar_count();
    }
    box.counts.resize(sb.patches.size(), sb.ar_count(), offset, static_cast<size_t>(hierarchy_.class_span(static_cast<int>(b))));
  }
}

void BoxStore::open_files(const fs::path& dir, const fs::path& manifest_path) {
  // Files, box by box, in line order; a shard's empty part (a box with fewer
  // chunks than shards) before the part that starts where it would.
  auto files = manifest_.files;
  std::sort(files.begin(), files.end(), [](const auto& a, const auto& b) {
    return std::tie(a.box, a.first_line, a.lines) < std::tie(b.box, b.first_line, b.lines);
  });
  std::vector<uint64_t> next_line(boxes_.size(), 0);
  for (const linestore::StoreFile& f : files) {
    const fs::path path = dir / f.name;
    if (f.box >= boxes_.size()) throw InputError(fmt::format("{}: box {} is not in the store's hierarchy", path.string(), f.box));
    // (Its name, size and hash were checked by verify_files.)
    StoreBox& box = boxes_[f.box];
    if (f.first_line != next_line[f.box])
      throw InputError(fmt::format("{}: starts at line {}, expected {} (a shard is missing)", path.string(), f.first_line,
                                   next_line[f.box]));
    // Opened once here to check it; kept as this thread's reader for the passes.
    auto opened = std::make_unique<linestore::BoxFileReader>(path);
    const linestore::BoxFileReader& reader = *opened;
    if (reader.box() != f.box || reader.lines() != f.lines)
      throw InputError(fmt::format("{}: does not match the manifest (box or line count differs)", path.string()));
    try {
      box.counts.add(reader.counts());
    } catch (const InputError&) {
      throw InputError(fmt::format("{}: its counts do not fit box {} of this hierarchy", path.string(), f.box));
    }
    for (uint32_t c = 0; c < reader.chunks().size(); ++c) {
      box.chunks.push_back({static_cast<uint32_t>(files_.size()), c});
      box.chunk_lines.push_back(reader.chunks()[c].lines);
    }
    files_.push_back(path);
    Readers& mine = readers_.local();
    mine.resize(files_.size());
    mine.back() = std::move(opened);
    next_line[f.box] += f.lines;
    box.lines += f.lines;
    box.events += f.events;
    box.bytes += f.bytes;
  }
  for (size_t b = 0; b < boxes_.size(); ++b)
    if (next_line[b] != manifest_.boxes[b].lines)
      throw InputError(fmt::format("{}: the files of box {} hold {} lines of {} (a shard is missing)",
                                   manifest_path.string(), b, next_line[b], manifest_.boxes[b].lines));

}

void BoxStore::derive_box_data(const PatchMesh& mesh, size_t b) {
  const SceneBox& sb = hierarchy_.boxes[b];
  StoreBox& box = boxes_[b];
  box.face_crossings.assign(box.face_global.size(), 0.0);
  for (size_t k = 0; k < box.local_faces.size(); ++k)
    for (int face : box.local_faces[k])
      if (face >= 0) box.face_crossings[face] = box.counts.patch_crossings[k];
  box.face_proxy = face_proxies(mesh, sb, box);
  std::vector<double> c = box.face_crossings;
  double coverage = 0;
  if (!c.empty()) {
    std::nth_element(c.begin(), c.begin() + c.size() / 2, c.end());
    coverage = c[c.size() / 2] > 0 ? 16.0 / c[c.size() / 2] : 1.0;
  }
  if (box.lines > 0) coverage = std::max(coverage, 2.0 * sb.ar_count() / static_cast<double>(box.lines));
  // A subscene's walls hold power only its own lines move on; transparent boxes have none.
  if (b > 0 && !hierarchy_.transparent) coverage = std::max(coverage, kSubsceneCoverage);
  box.coverage = std::min(1.0, coverage);
  if (b == 0) return;
  box.transmittance = transmittances(sb, box.counts.wall_lines, box.counts.wall_open);
  std::vector<bool> carried(sb.ar_count());
  for (uint32_t r = 0; r < sb.ar_count(); ++r) carried[r] = box.counts.wall_lines[r] > box.counts.wall_open[r];
  box.in_target = redirect_targets(sb, carried);
  // Out power leaves along the parent's lines that cross the AR.
  const StoreBox& parent = boxes_[sb.parent];
  const auto& siblings = hierarchy_.boxes[sb.parent].children;
  const size_t k = static_cast<size_t>(std::find(siblings.begin(), siblings.end(), static_cast<int>(b)) - siblings.begin());
  for (uint32_t r = 0; r < sb.ar_count(); ++r) carried[r] = parent.counts.child_crossings[parent.child_ar_base[k] + r] > 0;
  box.out_target = redirect_targets(sb, carried);
}

uint64_t BoxStore::total(uint64_t StoreBox::*field) const {
  uint64_t n = 0;
  for (const StoreBox& b : boxes_) n += b.*field;
  return n;
}

std::vector<double> BoxStore::face_crossings(size_t faces) const {
  std::vector<double> out(faces, 0.0);
  // A face of a transparent hierarchy is in every box above it too, and all
  // their lines carry its power: its crossings are theirs summed.
  for (const StoreBox& b : boxes_)
    for (size_t f = 0; f < b.face_global.size(); ++f) out[b.face_global[f]] += b.face_crossings[f];
  return out;
}

std::vector<double> BoxStore::root_crossings(size_t faces) const {
  std::vector<double> out(faces, 0.0);
  const StoreBox& root = boxes_.front();
  for (size_t f = 0; f < root.face_global.size(); ++f) out[root.face_global[f]] = root.face_crossings[f];
  return out;
}

std::vector<bool> BoxStore::faces_crossed(size_t faces) const {
  std::vector<bool> out(faces, false);
  for (const StoreBox& b : boxes_)
    for (size_t f = 0; f < b.face_global.size(); ++f)
      if (b.face_crossings[f] > 0) out[b.face_global[f]] = true;
  return out;
}

linestore::BoxFileReader& BoxStore::reader(int box, uint64_t chunk, uint32_t& local) const {
  const auto [file, index] = boxes_[box].chunks[chunk];
  Readers& readers = readers_.local();
  if (readers.size() != files_.size()) readers.resize(files_.size());
  auto& reader = readers[file];
  if (!reader) reader = std::make_unique<linestore::BoxFileReader>(files_[file]);
  local = index;
  return *reader;
}

void BoxStore::read(int box, uint64_t chunk, linestore::DecodedChunk& out) const {
  uint32_t local;
  reader(box, chunk, local).read_chunk(local, out);
}

void BoxStore::read_lines(int box, uint64_t chunk, const uint32_t* order, size_t take, linestore::DecodedChunk& out,
                          const linestore::EventSides* sides) const {
  uint32_t local;
  reader(box, chunk, local).read_chunk_lines(local, order, take, out, sides);
}

}  // namespace mpath
