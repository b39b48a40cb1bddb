// Bottom-up grouping of objects into the hierarchy of subscene boxes
// (docs/algorithm.md, "Hierarchy of subscenes").
#include "hierarchy.h"

#include "error.h"
#include "patch_tree.h"

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <numeric>
#include <queue>
#include <unordered_map>
#include <utility>

namespace mpath {

namespace {

// The finest VP grid a face gets (64 x 64 VPs, 98,304 ARs per face).
constexpr int kMaxGrid = 64;
// A group box that would enclose a single group item growing its surface by
// less than this factor takes that item's contents instead of nesting it.
constexpr double kAbsorbGrowth = 1.5;
// An object whose box has more than this share of the scene box's surface is
// too large to be grouped whole (hierarchy.max_share bounds the groups).
constexpr double kMaxSceneShare = 0.5;
// A subscene holds at least this many polygons (two books on a shelf do not
// pay for the walls, ARs and lines of a box of their own)...
constexpr size_t kMinPolygons = 24;
// ...and has at most this share of the surface of the box it is in (a box
// nearly as large as its parent adds a level and nothing else).
constexpr double kMaxNesting = 0.5;
// A group holding an emitter that would be dissolved (below max_depth, or
// with fewer than kMinPolygons polygons) is a box of its own (a lamp in its
// shade, a fluorescent strip in its trough) when its surface is at most this
// share of the box it would be dissolved into (docs/algorithm.md, "Bright
// subscenes").
constexpr double kBrightShare = 1.0 / 16.0;

Bounds merged(const Bounds& a, const Bounds& b) {
  Bounds m = a;
  m.extend(b.lo);
  m.extend(b.hi);
  return m;
}

// The interior of `box` shrunk by `eps` meets the interior of `other`.
bool interiors_overlap(const Bounds& box, const Bounds& other, double eps) {
  for (int i = 0; i < 3; ++i)
    if (other.hi[i] <= box.lo[i] + eps || other.lo[i] >= box.hi[i] - eps) return false;
  return true;
}

bool contains(const Bounds& box, const Bounds& inner, double eps) {
  for (int i = 0; i < 3; ++i)
    if (inner.lo[i] < box.lo[i] - eps || inner.hi[i] > box.hi[i] + eps) return false;
  return true;
}

}  // namespace

namespace {

// Boxes of grouping items in a loose octree: level L has cells of size
// base * 2^L, and a box sits in the cell of its centre at the finest level
// whose cells are at least as large as the box, so that it lies within its
// cell grown by half a cell each way (and a cell's descendants' boxes within
// it grown by a quarter). A query returns the boxes of every cell whose grown
// extent meets a region (a superset of the boxes meeting it), in no
// particular order, descending from the coarsest cells into the occupied
// children in range only, so that its work follows the occupied cells near
// the region rather than every cell of a level; entries are never removed
// (callers skip dead items). Build work and queries are near linear where
// the scene is (the grouping compared every pair of items before, and then
// scanned every occupied cell of a level for a region larger than a few of
// its cells, quadratic on large scenes: docs/performance.md).
class LooseGrid {
 public:
  LooseGrid(const Bounds& scene) : origin_(scene.lo) {
    base_ = std::max(scene.diagonal(), 1e-30) / double(1 << kLevels);
  }

  // `tag`: a number the caller keeps with the box (rounded down to a float),
  // handed to the callers of the const query.
  void insert(int id, const Bounds& b, double tag = 0) {
    const Vec3 s = b.size();
    const double extent = std::max({s.x, s.y, s.z, 0.0});
    int level = 0;
    while (level < kLevels && base_ * double(1 << level) < extent) ++level;
    const double cell = base_ * double(1 << level);
    const Vec3 c = b.center();
    Cell k{};
    for (int i = 0; i < 3; ++i) k[i] = clamp_cell(std::floor((c[i] - origin_[i]) / cell), level);
    Node* node = &levels_[level][key(k)];
    node->entries.push_back(entry(id, b, tag));
    // The chain of ancestors up to the coarsest level, each knowing its child
    // (a map's nodes stay where they are, so a parent holds its children's
    // addresses and a query descends without hashing).
    for (int l = level; l < kLevels; ++l) {
      Cell parent{};
      int bit = 0;
      for (int i = 0; i < 3; ++i) {
        parent[i] = k[i] >> 1;  // floor(k / 2), k may be negative
        bit |= int(k[i] - 2 * parent[i]) << i;
      }
      Node& up = levels_[l + 1][key(parent)];
      const bool known = up.child[bit] != nullptr;
      up.child[bit] = node;
      if (known) break;
      k = parent;
      node = &up;
    }
  }

  // Calls f(id) for every box that meets `r` (its bounds, rounded outwards
  // to floats, kept beside its id in its cell: a cell's ids are tested
  // without reading the caller's items), after dropping from the visited
  // cells every id meeting `r` that `dead(id)` names (each is dropped once,
  // so the grid does not fill with dead items). A cell left with no id and
  // no occupied child is unlinked from its parent and dropped, so that later
  // queries no longer descend through the emptied cells under a large group
  // (the items it swallowed): without that, a query over a group of n dead
  // items walked their n cells again each time, and scenes of a million
  // single-polygon objects took minutes.
  template <typename Dead, typename F>
  void query(const Bounds& r, const Dead& dead, const F& f) {
    query(everywhere(r), dead, f);
  }

  static constexpr int kLevels = 20;  // the finest cells: a millionth of the scene's diagonal

  // A query's region level by level: the boxes of level l's cells are looked
  // for where they meet at[l], and levels below min_level are skipped. A
  // level's cells hold boxes no larger than the cell, so a caller that knows
  // how far a box of that size can lie (a small partner lies closer) asks
  // less of the fine levels. The regions must grow with the level (at[l]
  // within at[l + 1]): a query descends into a cell only where its grown
  // extent meets the region of the cell's level.
  struct Region {
    std::array<Bounds, kLevels + 1> at;
    int min_level = 0;
  };
  static Region everywhere(const Bounds& r) {
    Region out;
    out.at.fill(r);
    return out;
  }
  // The size of a level's cells: the largest box its cells hold.
  double cell_size(int level) const { return base_ * double(1 << level); }

  template <typename Dead, typename F>
  void query(const Region& r, const Dead& dead, const F& f) {
    visit_cells<true>(levels_, r, [&](int level, std::vector<Entry>& entries) {
      const Bounds& at = r.at[level];
      size_t kept = 0;
      for (const Entry& e : entries) {
        if (meets(e, at)) {
          if (dead(e.id)) continue;
          f(e.id);
        }
        entries[kept++] = e;
      }
      entries.resize(kept);
    });
  }
  // The same, dropping nothing (threads may query at once), as f(id, tag):
  // a caller can skip a box by its tag without reading its own record of it.
  template <typename F>
  void query(const Region& r, const F& f) const {
    visit_cells(levels_, r, [&](int level, const std::vector<Entry>& entries) {
      const Bounds& at = r.at[level];
      for (const Entry& e : entries)
        if (meets(e, at)) f(e.id, e.tag);
    });
  }

 private:
  // A box in a cell: its id, tag and bounds (floats, the bounds rounded
  // outwards, the tag down): 32 bytes.
  struct Entry {
    int id;
    float tag;
    std::array<float, 3> lo, hi;
  };
  static Entry entry(int id, const Bounds& b, double tag) {
    Entry e{id, static_cast<float>(tag), {}, {}};
    if (e.tag > tag) e.tag = std::nextafter(e.tag, -INFINITY);
    for (int i = 0; i < 3; ++i) {
      e.lo[i] = static_cast<float>(b.lo[i]);
      if (e.lo[i] > b.lo[i]) e.lo[i] = std::nextafter(e.lo[i], -INFINITY);
      e.hi[i] = static_cast<float>(b.hi[i]);
      if (e.hi[i] < b.hi[i]) e.hi[i] = std::nextafter(e.hi[i], INFINITY);
    }
    return e;
  }
  static bool meets(const Entry& e, const Bounds& r) {
    for (int i = 0; i < 3; ++i)
      if (e.hi[i] < r.lo[i] || e.lo[i] > r.hi[i]) return false;
    return true;
  }
  using Cell = std::array<long long, 3>;
  struct Node {
    std::vector<Entry> entries;      // boxes of this level whose centre is in the cell
    std::array<Node*, 8> child{};    // [x + 2y + 4z]: the child cell (2k + (x, y, z)) if occupied
  };
  using Levels = std::array<std::unordered_map<uint64_t, Node>, kLevels + 1>;

  // visit(level, entries) for the cells of `levels` (const or not) whose
  // grown extent meets `r`; `prune`: cells that end up empty (no entries, no
  // occupied child) are unlinked from their parents and erased.
  template <bool prune = false, typename L, typename V>
  void visit_cells(L& levels, const Region& r, const V& visit) const {
    std::array<Cell, kLevels + 1> lo{}, hi{};  // per level: the cells in range
    for (int level = r.min_level; level <= kLevels; ++level) {
      const double cell = cell_size(level);
      for (int i = 0; i < 3; ++i) {
        // Cell k grown by half a cell, [k - 1/2, k + 3/2] cells, meets the
        // region where k >= lo - 3/2 and k <= hi + 1/2: two cells a side
        // for a point (floor for the first, as before December 2026, took
        // three: 27 cells a level instead of 8). The millionth of a cell
        // to spare covers the rounding of a centre's cell.
        lo[level][i] = clamp_cell(std::ceil((r.at[level].lo[i] - origin_[i]) / cell - 1.5 - 1e-6), level);
        hi[level][i] = clamp_cell(std::floor((r.at[level].hi[i] - origin_[i]) / cell + 0.5 + 1e-6), level);
      }
    }
    auto in_range = [&](int level, const Cell& c) {
      for (int i = 0; i < 3; ++i)
        if (c[i] < lo[level][i] || c[i] > hi[level][i]) return false;
      return true;
    };
    // Depth first from each coarsest cell in range, into occupied children in
    // range; returns whether the cell is empty now (pruning only).
    auto descend = [&](auto& self, int level, const Cell& c, auto& node) -> bool {
      if (!node.entries.empty()) visit(level, node.entries);
      // Below min_level nothing is looked at: children there stay.
      bool occupied = level == r.min_level && std::any_of(node.child.begin(), node.child.end(),
                                                           [](const auto* child) { return child != nullptr; });
      if (level > r.min_level) {
        for (int bit = 0; bit < 8; ++bit) {
          if (!node.child[bit]) continue;
          const Cell child{2 * c[0] + (bit & 1), 2 * c[1] + ((bit >> 1) & 1), 2 * c[2] + ((bit >> 2) & 1)};
          if (!in_range(level - 1, child)) {
            occupied = true;
            continue;
          }
          const bool emptied = self(self, level - 1, child, *node.child[bit]);
          if constexpr (prune) {
            if (emptied) {
              // An insert below it later links the chain again (insert sets
              // the children it finds unset up to the first one set).
              levels[level - 1].erase(key(child));
              node.child[bit] = nullptr;
              continue;
            }
          }
          occupied = true;
        }
      }
      return prune && node.entries.empty() && !occupied;
    };
    for (auto& [k, node] : levels[kLevels]) {
      const Cell c = unkey(k);
      if (in_range(kLevels, c)) descend(descend, kLevels, c, node);
    }
  }

  static long long clamp_cell(double c, int level) {
    const double most = double((1LL << (kLevels - level)) + 2);
    return static_cast<long long>(std::clamp(c, -2.0, most));
  }
  static uint64_t key(const Cell& k) {
    uint64_t out = 0;
    for (long long v : k) out = (out << 21) | static_cast<uint64_t>(v + 4);
    return out;
  }
  static Cell unkey(uint64_t k) {
    Cell out{};
    for (int i = 2; i >= 0; --i, k >>= 21) out[i] = static_cast<long long>(k & ((1u << 21) - 1)) - 4;
    return out;
  }
  Vec3 origin_;
  double base_ = 1;
  Levels levels_;
};

// A grouping item: an object or a group (a future box).
struct Item {
  Bounds bounds;
  double area = 0;
  int object = -1;  // for an object item
  // For a group: its direct members (items), and the quotient that formed it.
  std::vector<int> members;
  double quotient = 0;
};

class Builder {
 public:
  Builder(const PatchMesh& mesh, const HierarchyOptions& options, const std::vector<uint8_t>& emitting = {})
      : mesh_(mesh), options_(options), emitting_(emitting) {
    int objects = 0;
    for (const Patch& p : mesh.patches) objects = std::max(objects, p.object + 1);
    object_patches_.resize(objects);
    for (size_t p = 0; p < mesh.patches.size(); ++p) object_patches_[mesh.patches[p].object].push_back(static_cast<uint32_t>(p));
    eps_ = 1e-6 * std::max(mesh.bounds.diagonal(), 1e-30);
    scene_area_ = mesh.bounds.surface_area();
    // An object too large to group whole (a file whose furniture is one
    // object, or the whole scene in one) is split into its connected parts,
    // which are the items instead (docs/method.md, 3).
    for (int o = 0; o < objects; ++o) {
      Bounds b;
      for (uint32_t p : object_patches_[o])
        for (uint32_t v : mesh.patches[p].v) b.extend(mesh.vertices[v]);
      if (object_patches_[o].empty() || b.surface_area() <= kMaxSceneShare * scene_area_) continue;
      auto parts = connected_parts(object_patches_[o]);
      object_patches_[o] = std::move(parts[0]);
      for (size_t k = 1; k < parts.size(); ++k) object_patches_.push_back(std::move(parts[k]));
    }
    objects = static_cast<int>(object_patches_.size());
    object_trees_.resize(objects);
    object_polygons_.resize(objects);
    for (int o = 0; o < objects; ++o) {
      start_polygon_count();
      object_polygons_[o] = count_new_polygons(object_patches_[o]);
    }
    object_bounds_.resize(objects);
    for (int o = 0; o < objects; ++o) {
      if (object_patches_[o].empty()) continue;
      Item item;
      item.object = o;
      for (uint32_t p : object_patches_[o])
        for (uint32_t v : mesh.patches[p].v) item.bounds.extend(mesh.vertices[v]);
      object_bounds_[o] = item.bounds;
      item.area = item.bounds.surface_area();
      if (is_shell(item.bounds)) {
        shell_.push_back(o);  // stays in the root, never grouped
        continue;
      }
      items_.push_back(std::move(item));
    }
    gone_.assign((items_.size() + 63) / 64, 0);
    plain_ = std::make_unique<LooseGrid>(mesh.bounds);
    reach_ = std::make_unique<LooseGrid>(mesh.bounds);
  }

  // Patches joined by shared corners (positions equal to 1e-6 of the scene's
  // size), as sets of patches, largest first (ties by first patch).
  std::vector<std::vector<uint32_t>> connected_parts(const std::vector<uint32_t>& patches) const {
    std::vector<uint32_t> parent(patches.size());
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    std::map<std::array<long long, 3>, uint32_t> corner;  // position -> first patch seen there
    for (uint32_t i = 0; i < patches.size(); ++i)
      for (uint32_t v : mesh_.patches[patches[i]].v) {
        const Vec3& x = mesh_.vertices[v];
        const std::array<long long, 3> key{std::llround(x.x / eps_), std::llround(x.y / eps_), std::llround(x.z / eps_)};
        const auto [it, fresh] = corner.emplace(key, i);
        if (!fresh) parent[find(i)] = find(it->second);
      }
    std::map<uint32_t, std::vector<uint32_t>> by_root;
    for (uint32_t i = 0; i < patches.size(); ++i) by_root[find(i)].push_back(patches[i]);
    std::vector<std::vector<uint32_t>> parts;
    for (auto& [root, list] : by_root) parts.push_back(std::move(list));
    std::stable_sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
    return parts;
  }

  // The scene's shell: an object lying against a side of the scene box and
  // spanning at least half of it both ways (a floor, a wall, a ceiling). The
  // area quotient favours grouping such a flat, large object with whatever
  // stands near it, which would make a subscene of half the room; the shell
  // belongs to the root.
  bool is_shell(const Bounds& b) const {
    const Bounds& scene = mesh_.bounds;
    const Vec3 s = scene.size(), e = b.size();
    for (int axis = 0; axis < 3; ++axis) {
      const bool on_side = std::fabs(b.lo[axis] - scene.lo[axis]) <= 1e3 * eps_ ||
                           std::fabs(b.hi[axis] - scene.hi[axis]) <= 1e3 * eps_;
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      if (on_side && e[u] >= 0.5 * s[u] && e[v] >= 0.5 * s[v]) return true;
    }
    return false;
  }

  // Greedy bottom-up grouping: the pair with the largest quotient above the
  // threshold first; each new group is an item at once. `all_pairs`: every
  // pair is compared (quadratic; the reference the tests hold the grid to).
  void group(bool all_pairs) {
    all_pairs_ = all_pairs;
    const int n = static_cast<int>(items_.size());
    for (int i = 0; i < n; ++i) index_item(i);
    // Every pair once, on every thread; the queue orders candidates totally
    // (quotient, then indices), so the grouping does not depend on threads
    // (nor on the order in which the grid finds them).
    // Each thread's candidates in bands of quotient (CandidateQueue).
    const std::vector<std::vector<Candidate>> no_bands(CandidateQueue::kBands);
    tbb::enumerable_thread_specific<std::vector<std::vector<Candidate>>> found(no_bands);
    tbb::parallel_for(0, n, [&](int a) {
      auto& local = found.local();
      Candidate c;
      auto keep = [&] { local[CandidateQueue::band(c.q, options_.group_threshold)].push_back(c); };
      if (all_pairs_) {
        for (int b = a + 1; b < n; ++b)
          if (candidate(a, b, c)) keep();
        return;
      }
      // Each pair from the side of its larger item, whose reach holds the smaller.
      if (!(items_[a].area > 0)) return;
      std::as_const(*plain_).query(smaller_reach(a), [&](int b, float area) {
        // (A tag above a's area is a larger item's, known without reading it.)
        if (b >= n || b == a || area > items_[a].area) return;
        if (items_[b].area > items_[a].area || (items_[b].area == items_[a].area && b < a)) return;
        if (candidate(std::min(a, b), std::max(a, b), c)) keep();
      });
    });
    queue_ = {};
    for (auto& local : found) queue_.add_bands(local);
    const auto dead_pair = [this](const Candidate& c) { return gone(c.a) || gone(c.b); };
    for (Candidate c; queue_.take(c, dead_pair);)
      if (!dead_pair(c)) try_group(c);
  }

  Hierarchy finish() {
    Hierarchy h;
    h.patch_box.assign(mesh_.patches.size(), 0);
    h.boxes.emplace_back();
    SceneBox& root = h.boxes[0];
    root.bounds = mesh_.bounds;
    std::vector<int> top;
    root.objects = shell_;
    for (size_t i = 0; i < items_.size(); ++i)
      if (!gone(static_cast<int>(i))) top.push_back(static_cast<int>(i));
    place(h, 0, top, scene_area_);
    // Deeper than max_depth: dissolved into the ancestor at max_depth.
    return complete(std::move(h));
  }

  // The hierarchy of a layout recorded by hierarchy_layout (a store's
  // manifest), without grouping again; InputError when it cannot be this
  // mesh's (boxes out of order, objects missing, repeated or out of range).
  Hierarchy assemble(const std::vector<BoxLayout>& layout) {
    auto bad = [](const std::string& what) { throw InputError("the store's hierarchy does not fit this scene: " + what); };
    if (layout.empty() || layout[0].parent != -1 || layout[0].depth != 0) bad("no root box first");
    Hierarchy h;
    h.patch_box.assign(mesh_.patches.size(), 0);
    std::vector<uint8_t> placed(object_patches_.size(), 0);
    for (size_t b = 0; b < layout.size(); ++b) {
      const BoxLayout& l = layout[b];
      if (b > 0 && (l.parent < 0 || l.parent >= static_cast<int>(b) || l.depth != layout[l.parent].depth + 1))
        bad(fmt::format("box {} has parent {} and depth {}", b, l.parent, l.depth));
      SceneBox box;
      box.parent = l.parent;
      box.depth = l.depth;
      box.quotient = l.quotient;
      for (int o : l.objects) {
        if (o < 0 || o >= static_cast<int>(placed.size()) || placed[o]) bad(fmt::format("object {} of box {}", o, b));
        placed[o] = 1;
        box.objects.push_back(o);
      }
      h.boxes.push_back(std::move(box));
      if (b > 0) h.boxes[l.parent].children.push_back(static_cast<int>(b));
    }
    for (size_t o = 0; o < placed.size(); ++o)
      if (!placed[o] && !object_patches_[o].empty()) bad(fmt::format("object {} is in no box", o));
    h.boxes[0].bounds = mesh_.bounds;
    return complete(std::move(h));
  }

 private:
  // Patches, bounds, totals and VP grids of every box, and the depth order.
  Hierarchy complete(Hierarchy h) {
    for (size_t b = 0; b < h.boxes.size(); ++b) finish_box(h, static_cast<int>(b));
    // Boxes listed by depth, then index (children run after their parents).
    h.depth_order.resize(h.boxes.size());
    for (size_t b = 0; b < h.boxes.size(); ++b) h.depth_order[b] = static_cast<int>(b);
    std::stable_sort(h.depth_order.begin(), h.depth_order.end(),
                     [&](int a, int b) { return h.boxes[a].depth < h.boxes[b].depth; });
    return h;
  }

  struct Candidate {
    double q;
    int a, b;
    bool operator<(const Candidate& o) const {
      if (q != o.q) return q < o.q;
      if (a != o.a) return a > o.a;
      return b > o.b;
    }
    static bool best_first(const Candidate& x, const Candidate& y) { return y < x; }
  };

  // The candidates waiting, in runs sorted best first (each new group's
  // pairs a run of its own), and a heap of the runs' fronts: taking the best
  // front each time gives the order of one queue of all of them (the order
  // is total). One binary heap of every candidate, sifted at random through
  // tens of megabytes, took a quarter of OFFICE's build when it held the
  // first candidates too, and most of the time of the pairs new groups
  // bring (5.2M of them, a few hundred a group, on OFFICE tiled 3x3 with
  // an object per polygon); the heap of fronts holds a run's best alone.
  //
  // The first candidates come in bands of quotient, the best band first,
  // and a band is sorted only when its turn comes, after dropping its
  // candidates whose items are gone by then (they would be skipped when
  // taken; items never come back): with an object per polygon every try of
  // OFFICE tiled 3x3 was a pair of quotient above 1, and the 17 million
  // pairs below it were all gone when they were taken, sorted for nothing.
  class CandidateQueue {
   public:
    static constexpr int kBands = 64;
    // The band of quotient q (in (threshold, 2]: the merged box is no
    // smaller than either item's), the best first: a lower band holds only
    // higher quotients.
    static int band(double q, double threshold) {
      const double x = (2.0 - q) / std::max(2.0 - threshold, 1e-9) * kBands;
      return static_cast<int>(std::clamp(x, 0.0, double(kBands - 1)));
    }
    // Adds a set of bands (kBands lists, each in any order), emptying them.
    void add_bands(std::vector<std::vector<Candidate>>& bands) {
      bands_.resize(kBands);
      for (int k = 0; k < kBands; ++k) bands_[k].push_back(std::move(bands[k]));
    }
    void add_sorted(std::vector<Candidate> run) {
      if (run.empty()) return;
      fronts_.push({run.front(), runs_.size(), 0});
      runs_.push_back(std::move(run));
    }
    void add(std::vector<Candidate> run) {
      std::sort(run.begin(), run.end(), Candidate::best_first);
      add_sorted(std::move(run));
    }
    // The best candidate left, taken out; false when none is left.
    // `dead(c)`: whether c's items are gone (a band's are dropped then).
    template <typename Dead>
    bool take(Candidate& c, const Dead& dead) {
      if (!band_open_) next_band(dead);
      if (fronts_.empty()) return false;
      const Front f = fronts_.top();
      fronts_.pop();
      c = f.c;
      std::vector<Candidate>& run = runs_[f.run];
      if (f.next + 1 < run.size()) {
        fronts_.push({run[f.next + 1], f.run, f.next + 1});
      } else {
        std::vector<Candidate>().swap(run);  // its memory back
        if (f.run == band_run_) next_band(dead);
      }
      return true;
    }

   private:
    // The next band with a living candidate, sorted, as a run.
    template <typename Dead>
    void next_band(const Dead& dead) {
      band_open_ = true;
      band_run_ = SIZE_MAX;
      for (; next_band_ < bands_.size(); ++next_band_) {
        std::vector<Candidate> run;
        for (std::vector<Candidate>& part : bands_[next_band_]) {
          for (const Candidate& c : part)
            if (!dead(c)) run.push_back(c);
          std::vector<Candidate>().swap(part);
        }
        if (run.empty()) continue;
        tbb::parallel_sort(run.begin(), run.end(), Candidate::best_first);
        band_run_ = runs_.size();
        add_sorted(std::move(run));
        ++next_band_;
        return;
      }
    }
    std::vector<std::vector<std::vector<Candidate>>> bands_;  // [band][part]
    size_t next_band_ = 0, band_run_ = SIZE_MAX;
    bool band_open_ = false;

    struct Front {
      Candidate c;
      size_t run, next;
      bool operator<(const Front& o) const { return c < o.c; }
    };
    std::vector<std::vector<Candidate>> runs_;
    std::priority_queue<Front> fronts_;
  };

  // The pair (a, b) as a candidate when its quotient passes the threshold.
  bool candidate(int a, int b, Candidate& out) const {
    const Bounds& x = items_[a].bounds;
    const Bounds& y = items_[b].bounds;
    const double dx = std::max(x.hi.x, y.hi.x) - std::min(x.lo.x, y.lo.x);
    const double dy = std::max(x.hi.y, y.hi.y) - std::min(x.lo.y, y.lo.y);
    const double dz = std::max(x.hi.z, y.hi.z) - std::min(x.lo.z, y.lo.z);
    const double area = 2 * (dx * dy + dy * dz + dz * dx);
    if (!(area > 0) || area > options_.max_share * scene_area_) return false;
    out = {(items_[a].area + items_[b].area) / area, a, b};
    return out.q > options_.group_threshold;
  }

  // Where an item b no larger than `a` must lie for the pair to pass: the
  // merged box's area is below 2 A_a / threshold (and the max_share bound),
  // and a box holding a's box with that area extends along axis i at most
  // (area / 2 - a_j a_k) / (a_j + a_k).
  Bounds reach(int a) const { return reach(a, items_[a].area); }
  // The same for partners of at most `partner` area: the merged box's area is
  // below (A_a + partner) / threshold.
  Bounds reach(int a, double partner) const {
    const Bounds& x = items_[a].bounds;
    const Vec3 e = x.size();
    const double most = std::min((items_[a].area + partner) / options_.group_threshold, options_.max_share * scene_area_);
    Bounds r = x;
    for (int i = 0; i < 3; ++i) {
      const double ej = e[(i + 1) % 3], ek = e[(i + 2) % 3];
      const double along = ej + ek > 0 ? (0.5 * most - ej * ek) / (ej + ek) : 0.0;
      const double grow = std::max(0.0, along - e[i]) * (1 + 1e-9) + eps_;
      r.lo[i] -= grow;
      r.hi[i] += grow;
    }
    return r;
  }

  // Where the plain grid's items no larger than `a` must lie for a pair with
  // it to pass, level by level: a level's cells hold boxes no larger than
  // the cell, of at most 6 cell^2 area, so the fine levels' partners (a
  // polygon near a large group) lie much closer than reach(a) (at the
  // default threshold a cube's reach spans 13 of its sides for a partner of
  // its own area, 5.5 for a tiny one).
  LooseGrid::Region smaller_reach(int a) const {
    LooseGrid::Region r;
    const Bounds full = reach(a);  // every level where a partner may be as large as a
    for (int level = 0; level <= LooseGrid::kLevels; ++level) {
      const double cell = plain_->cell_size(level), most = 6 * cell * cell;
      r.at[level] = level == LooseGrid::kLevels || most >= items_[a].area ? full : reach(a, most);
    }
    return r;
  }

  // Where to look in the reach grid for items at least as large as `id`
  // whose reach holds it: levels whose cells are smaller than such a reach
  // hold none of them (near a large group, the reaches of thousands of small
  // polygons). An item b of area A_b and sides e_1 >= e_2 >= e_3 grows its
  // reach along e_1 to 2 along - e_1, where along = c e_1 + (c - 1) e_2 e_3 /
  // (e_2 + e_3) with c = 2 / threshold, unless its pairs' area is capped at
  // max_share of the scene. Over the boxes of area A_b that length is least
  // for a cube, (3c - 2) sqrt(A_b / 6) (13 sides of the cube at the default
  // threshold; a flat square's reach spans 9 of its sides, 6.4 sqrt(A_b)
  // against the cube's 5.3); for c < 1 the item's own side, sqrt(A_b / 6),
  // bounds it. A capped reach holds a box of the cap's area, so it is at
  // least the root of a sixth of it.
  LooseGrid::Region larger_reach(int id) const {
    LooseGrid::Region r = LooseGrid::everywhere(items_[id].bounds);
    const double c = 2.0 / options_.group_threshold;
    const double side = std::min(std::max(3 * c - 2, 1.0) * std::sqrt(items_[id].area / 6),
                                 std::sqrt(options_.max_share * scene_area_ / 6)) *
                        (1 - 1e-9);
    while (r.min_level < LooseGrid::kLevels && reach_->cell_size(r.min_level) < side) ++r.min_level;
    return r;
  }

  // The parts of `after` outside `before` (which it holds), as up to six slabs.
  static std::vector<Bounds> slabs(const Bounds& before, const Bounds& after) {
    std::vector<Bounds> out;
    Bounds core = before;
    for (int i = 0; i < 3; ++i) {
      if (after.lo[i] < core.lo[i]) {
        Bounds s = core;
        s.lo[i] = after.lo[i];
        s.hi[i] = core.lo[i];
        out.push_back(s);
        core.lo[i] = after.lo[i];
      }
      if (after.hi[i] > core.hi[i]) {
        Bounds s = core;
        s.lo[i] = core.hi[i];
        s.hi[i] = after.hi[i];
        out.push_back(s);
        core.hi[i] = after.hi[i];
      }
    }
    return out;
  }

  // Puts item i into the grids: its box, and its reach (where its smaller partners are).
  void index_item(int i) {
    if (all_pairs_) return;
    plain_->insert(i, items_[i].bounds, items_[i].area);
    if (items_[i].area > 0) reach_->insert(i, reach(i));
  }

  // Whether item i is no longer alive (merged into a group): a bit per item
  // (the queue's candidates name items at random; the bits stay in the
  // caches where items of 100 bytes do not).
  bool gone(int i) const { return (gone_[static_cast<size_t>(i) >> 6] >> (i & 63)) & 1; }

  // gone() for the grids' queries: a lambda, not a std::function, so that
  // it is inlined.
  auto dead() const {
    return [this](int i) { return gone(i); };
  }

  // Candidates of the new item `id` with every living item before it.
  void push_pairs(int id) {
    Candidate c;
    std::vector<Candidate> run;
    if (all_pairs_) {
      for (int i = 0; i < id; ++i)
        if (!gone(i) && candidate(i, id, c)) run.push_back(c);
      queue_.add(std::move(run));
      return;
    }
    seen_.resize(items_.size(), 0);
    auto take = [&](int i) {
      if (i >= id || seen_[i]) return;
      seen_[i] = 1;
      touched_.push_back(i);
      if (candidate(i, id, c)) run.push_back(c);
    };
    plain_->query(smaller_reach(id), dead(), take);  // the smaller ones
    reach_->query(larger_reach(id), dead(), take);   // the larger ones
    forget_seen();
    queue_.add(std::move(run));
  }

  // Living items, not members and not yet `seen_`, whose boxes may meet one of
  // `regions`; marked seen and added to `out`. With the grid, only items
  // whose boxes come within 2 eps of `box` (the group's box as it is now,
  // holding the regions): the grid's cells return many more (a cell's items
  // anywhere in it), and an item farther away cannot reach into the box
  // before it grows towards it, when the slabs it grows by find the item
  // (it is not marked seen). Without this filter a scene of a million
  // single-polygon objects, whose coplanar neighbours are tried as flat
  // boxes and refused, visited 1,200 items per try (the all-pairs build,
  // the tests' reference, keeps every item).
  void near_regions(const std::vector<Bounds>& regions, const Bounds& box, std::vector<int>& out) {
    auto mark = [&](int i) {
      seen_[i] = 1;
      touched_.push_back(i);
      out.push_back(i);
    };
    if (all_pairs_) {
      for (int i = 0; i < static_cast<int>(items_.size()); ++i)
        if (!seen_[i] && !member_[i] && !gone(i)) mark(i);
      return;
    }
    const double margin = 2 * eps_;
    auto take = [&](int i) {
      if (seen_[i] || member_[i]) return;
      const Bounds& b = items_[i].bounds;
      for (int k = 0; k < 3; ++k)
        if (b.hi[k] < box.lo[k] - margin || b.lo[k] > box.hi[k] + margin) return;
      mark(i);
    };
    for (const Bounds& r : regions) plain_->query(r, dead(), take);
  }

  // Clears the seen marks.
  void forget_seen() {
    for (int i : touched_) seen_[i] = 0;
    touched_.clear();
  }

  void collect_objects(int item, std::vector<int>& out) const {
    if (items_[item].object >= 0) out.push_back(items_[item].object);
    for (int m : items_[item].members) collect_objects(m, out);
  }

  // Would a box with these bounds hold polygons of `item` (not a member) in its interior?
  bool intrudes(int item, const Bounds& box) const {
    if (items_[item].object >= 0) return object_meets(items_[item].object, box);
    return interiors_overlap(box, items_[item].bounds, eps_);  // another box overlapping: never
  }

  bool object_meets(int object, const Bounds& box) const {
    // An object whose bounds stay clear of the box's interior (the usual
    // case) has no polygon in it.
    if (!interiors_overlap(box, object_bounds_[object], eps_)) return false;
    Bounds inner = box;
    for (int i = 0; i < 3; ++i) {
      inner.lo[i] += eps_;
      inner.hi[i] -= eps_;
    }
    auto meets = [&](uint32_t p) {
      const Patch& patch = mesh_.patches[p];
      const Vec3& a = mesh_.vertices[patch.v[0]];
      const Vec3& b = mesh_.vertices[patch.v[1]];
      const Vec3& c = mesh_.vertices[patch.v[2]];
      return triangle_meets_box(a, b, c, inner) ||
             (!patch.is_triangle() && triangle_meets_box(a, c, mesh_.vertices[patch.v[3]], inner));
    };
    const std::vector<uint32_t>& patches = object_patches_[object];
    if (patches.size() <= kTreePatches) return std::any_of(patches.begin(), patches.end(), meets);
    std::unique_ptr<PatchTree>& tree = object_trees_[static_cast<size_t>(object)];
    if (!tree) tree = std::make_unique<PatchTree>(mesh_, patches);
    return tree->any_near(inner, meets);
  }
  // Objects with more patches than this ask a PatchTree whether a box holds one.
  static constexpr size_t kTreePatches = 64;

  void try_group(const Candidate& c) {
    std::vector<int> members = {c.a, c.b};
    member_.resize(items_.size(), 0);
    seen_.resize(items_.size(), 0);
    member_[c.a] = member_[c.b] = 1;
    const bool formed = form_group(c, members);
    forget_seen();  // a refused group returns in the middle of a sweep
    for (int m : members) member_[m] = 0;
    if (!formed) return;
    const int id = static_cast<int>(items_.size()) - 1;
    member_.resize(items_.size(), 0);
    index_item(id);
    push_pairs(id);
  }

  // The group of candidate c (members so far in `members`): false when refused.
  bool form_group(const Candidate& c, std::vector<int>& members) {
    Bounds box = merged(items_[c.a].bounds, items_[c.b].bounds);
    // Items reaching into the box join it (a cup on a table, a chair pushed
    // under it), the box growing to hold them, unless one is larger than the
    // box: then the box is refused (it would cut through a wall, a floor).
    // Items are visited in index order, each against the box as it has grown
    // so far, and again from the first while the box grows.
    // pending: a min-heap of the items met so far in this sweep and not yet
    // visited; when the box grows, the items in the slabs it grew by join it.
    std::vector<int> pending, found;
    for (bool grew = true; grew;) {
      grew = false;
      forget_seen();
      pending.clear();
      near_regions({box}, box, pending);
      std::make_heap(pending.begin(), pending.end(), std::greater<int>());
      while (!pending.empty()) {
        std::pop_heap(pending.begin(), pending.end(), std::greater<int>());
        const int i = pending.back();
        pending.pop_back();
        if (member_[i] || !intrudes(i, box)) continue;
        if (!contains(box, items_[i].bounds, eps_) && items_[i].area > box.surface_area()) return false;
        member_[i] = 1;
        members.push_back(i);
        const Bounds before = box;
        box = merged(box, items_[i].bounds);
        if (box.surface_area() > options_.max_share * scene_area_) return false;
        grew = true;
        // The larger box may meet items after this one that it did not meet before.
        found.clear();
        near_regions(slabs(before, box), box, found);
        for (int j : found)
          if (j > i) {
            pending.push_back(j);
            std::push_heap(pending.begin(), pending.end(), std::greater<int>());
          } else {
            seen_[j] = 0;  // before i: the next sweep's
          }
      }
    }
    forget_seen();
    for (int o : shell_)
      if (object_meets(o, box)) return false;
    const Vec3 size = box.size();
    if (std::min({size.x, size.y, size.z}) < 1e3 * eps_) return false;  // a flat box holds nothing inside
    if (box.surface_area() > options_.max_share * scene_area_) return false;
    Item group;
    group.bounds = box;
    group.area = box.surface_area();
    group.quotient = c.q;
    for (int m : members) {
      Item& it = items_[m];
      gone_[static_cast<size_t>(m) >> 6] |= uint64_t{1} << (m & 63);
      if (it.object < 0 && group.area < kAbsorbGrowth * it.area) {
        group.members.insert(group.members.end(), it.members.begin(), it.members.end());
        group.quotient = std::max(group.quotient, it.quotient);
      } else {
        group.members.push_back(m);
      }
    }
    items_.push_back(std::move(group));
    gone_.resize((items_.size() + 63) / 64, 0);
    return true;
  }

  // Polygons in the item (each group counted once; the answers are kept).
  size_t item_polygons(int item) const {
    if (items_[item].object >= 0) return object_polygons_[items_[item].object];
    if (polygons_.size() < items_.size()) polygons_.resize(items_.size(), kUnknown);
    if (polygons_[item] != kUnknown) return polygons_[item];
    size_t sum = 0;
    for (int m : items_[item].members) sum += item_polygons(m);
    return polygons_[item] = sum;
  }

  // Does the item hold a patch that emits (the `emitting` flags given)?
  // Each item is looked at once (the answers are kept).
  bool item_lit(int item) const {
    if (emitting_.empty()) return false;
    if (lit_.size() < items_.size()) lit_.resize(items_.size(), -1);
    if (lit_[item] >= 0) return lit_[item] > 0;
    bool lit = false;
    if (items_[item].object >= 0) {
      const auto& patches = object_patches_[items_[item].object];
      lit = std::any_of(patches.begin(), patches.end(), [&](uint32_t p) { return emitting_[p] != 0; });
    } else {
      for (int m : items_[item].members) lit = item_lit(m) || lit;
    }
    lit_[item] = lit;
    return lit;
  }

  // A group holding an emitter (never without the emitters: item_lit says no
  // at once).
  bool lit_group(int item) const { return items_[item].object < 0 && item_lit(item); }
  // A lit group with enough polygons to be a subscene on its own merits.
  bool bright_candidate(int item) const { return lit_group(item) && item_polygons(item) >= kMinPolygons; }

  // Puts `items` into box `box` (of surface area `area`): objects directly,
  // groups as child boxes, except groups that would not pay as subscenes,
  // whose contents go into `box` instead: deeper than max_depth, holding
  // fewer than kMinPolygons polygons, or nearly as large as `box`. A group
  // around an emitter, small beside `box`, that would be dissolved for being
  // too deep or too small is a box of its own all the same (bright
  // subscenes, made only when the emitters are given): the smallest such
  // group, going down through lit member groups of kMinPolygons polygons or
  // more, and through any lit member group once below kMinPolygons. `flatten`:
  // every group's contents go into `box` (a bright box holds its contents
  // directly).
  void place(Hierarchy& h, int box, const std::vector<int>& items, double area, bool flatten = false) {
    for (int i : items) {
      const Item& it = items_[i];
      if (it.object >= 0) {
        h.boxes[box].objects.push_back(it.object);
        continue;
      }
      const bool too_deep = h.boxes[box].depth + 1 > options_.max_depth;
      const bool too_small = item_polygons(i) < kMinPolygons;
      if ((too_deep || too_small) && !flatten && lit_group(i) && it.area <= kBrightShare * area) {
        // The smallest such group: go down while a member group still
        // qualifies (any lit member of a group too small already: two
        // fixtures side by side get a box each).
        const bool smaller = std::any_of(it.members.begin(), it.members.end(),
                                         [&](int m) { return too_small ? lit_group(m) : bright_candidate(m); });
        if (smaller) place(h, box, it.members, area);
        else add_box(h, box, i, true);
        continue;
      }
      if (too_deep || flatten || too_small || it.area > kMaxNesting * area) {
        place(h, box, it.members, area, flatten);
        continue;
      }
      add_box(h, box, i, false);
    }
  }

  // Makes group `item` a child box of `box`; a bright box holds all of its contents directly.
  void add_box(Hierarchy& h, int box, int item, bool bright) {
    const Item& it = items_[item];
    const int child = static_cast<int>(h.boxes.size());
    h.boxes.emplace_back();
    h.boxes[child].parent = box;
    h.boxes[child].depth = h.boxes[box].depth + 1;
    h.boxes[child].quotient = it.quotient;
    h.boxes[box].children.push_back(child);
    place(h, child, it.members, it.area, bright);
  }

  // Distinct polygons among patches, counted with a stamp per polygon (a
  // std::set took every polygon of the scene into one tree for the root's
  // count, 2-3 % of a solve's start on OFFICE): start_polygon_count() begins
  // a count, count_new_polygons() adds the polygons not met since.
  void start_polygon_count() {
    if (polygon_stamp_.empty()) {
      int polygons = 0;
      for (const Patch& p : mesh_.patches) polygons = std::max(polygons, p.polygon + 1);
      polygon_stamp_.assign(static_cast<size_t>(polygons), 0);
    }
    ++stamp_;
  }
  size_t count_new_polygons(const std::vector<uint32_t>& patches) {
    size_t added = 0;
    for (uint32_t p : patches) {
      uint32_t& seen = polygon_stamp_[static_cast<size_t>(mesh_.patches[p].polygon)];
      if (seen != stamp_) {
        seen = stamp_;
        ++added;
      }
    }
    return added;
  }

  void finish_box(Hierarchy& h, int b) {
    SceneBox& box = h.boxes[b];
    std::sort(box.objects.begin(), box.objects.end());
    for (int o : box.objects)
      for (uint32_t p : object_patches_[o]) {
        box.patches.push_back(p);
        h.patch_box[p] = b;
      }
    std::sort(box.patches.begin(), box.patches.end());
    if (b > 0) {
      std::vector<int> objects;
      std::vector<int> stack = {b};
      box.bounds = Bounds{};
      while (!stack.empty()) {
        const int x = stack.back();
        stack.pop_back();
        objects.insert(objects.end(), h.boxes[x].objects.begin(), h.boxes[x].objects.end());
        stack.insert(stack.end(), h.boxes[x].children.begin(), h.boxes[x].children.end());
      }
      for (int o : objects)
        for (uint32_t p : object_patches_[o])
          for (uint32_t v : mesh_.patches[p].v) box.bounds.extend(mesh_.vertices[v]);
    }
    // Totals over the box and its descendants.
    start_polygon_count();
    size_t polygons = 0;
    std::vector<int> stack = {b};
    box.objects_total = 0;
    while (!stack.empty()) {
      const int x = stack.back();
      stack.pop_back();
      box.objects_total += static_cast<int>(h.boxes[x].objects.size());
      for (int o : h.boxes[x].objects) polygons += count_new_polygons(object_patches_[o]);
      stack.insert(stack.end(), h.boxes[x].children.begin(), h.boxes[x].children.end());
    }
    box.polygons_total = polygons;
    // Virtual patches: 2^k x 2^k per face, k grown until a VP's area is at most
    // vp_area_ratio x max_patch_area (or vp_grid x vp_grid).
    const Vec3 s = box.bounds.size();
    const double limit = options_.vp_area_ratio * mesh_.max_patch_area;
    for (int f = 0; f < 6; ++f) {
      const int axis = f / 2;
      const double area = s[(axis + 1) % 3] * s[(axis + 2) % 3];
      int n = options_.vp_grid;
      if (n <= 0) {
        n = 1;
        while (n < kMaxGrid && area / (double(n) * n) > limit) n *= 2;
      }
      box.grid[f] = b == 0 ? 0 : n;  // the root has no walls of its own
    }
    box.set_ar_offsets();
  }

  const PatchMesh& mesh_;
  HierarchyOptions options_;
  const std::vector<uint8_t>& emitting_;  // per patch; empty: no bright subscenes
  mutable std::vector<int8_t> lit_;       // per item: item_lit's answer (-1: not yet known)
  static constexpr size_t kUnknown = ~size_t{0};
  mutable std::vector<size_t> polygons_;  // per group: item_polygons's answer (kUnknown: not yet known)
  std::vector<std::vector<uint32_t>> object_patches_;
  std::vector<size_t> object_polygons_;
  std::vector<uint32_t> polygon_stamp_;  // per polygon: the count that last met it (start_polygon_count)
  uint32_t stamp_ = 0;
  std::vector<Bounds> object_bounds_;
  mutable std::vector<std::unique_ptr<PatchTree>> object_trees_;  // per object, made when first asked (object_meets)
  std::vector<Item> items_;
  std::vector<uint64_t> gone_;  // a bit per item: merged into a group (gone())
  std::vector<int> shell_;  // objects of the scene's shell
  CandidateQueue queue_;
  std::vector<uint8_t> member_;  // try_group's scratch: items in the box being formed (all 0 between calls)
  std::vector<uint8_t> seen_;    // form_group's scratch: items met in the current sweep (all 0 between calls)
  std::vector<int> touched_;     // the items seen_ marks
  bool all_pairs_ = false;
  std::unique_ptr<LooseGrid> plain_, reach_;  // item boxes; item reaches
  double eps_ = 0, scene_area_ = 0;
};

}  // namespace

int Hierarchy::max_depth() const {
  int d = 0;
  for (const SceneBox& b : boxes) d = std::max(d, b.depth);
  return d;
}

int Hierarchy::common_box(int a, int b) const {
  return common_ancestor(a, b, [&](int x) { return boxes[x].depth; }, [&](int x) { return boxes[x].parent; });
}

size_t Hierarchy::ar_total() const {
  size_t n = 0;
  for (size_t b = 1; b < boxes.size(); ++b) n += boxes[b].ar_count();
  return n;
}


std::vector<BoxLayout> hierarchy_layout(const Hierarchy& h) {
  std::vector<BoxLayout> out;
  for (const SceneBox& b : h.boxes) out.push_back({b.parent, b.depth, b.quotient, b.objects});
  return out;
}

Hierarchy assemble_hierarchy(const PatchMesh& mesh, const HierarchyOptions& options, const std::vector<BoxLayout>& layout) {
  Builder builder(mesh, options);
  return builder.assemble(layout);
}

Hierarchy build_hierarchy(const PatchMesh& mesh, const HierarchyOptions& options, bool flat, bool all_pairs,
                          const std::vector<uint8_t>& emitting) {
  HierarchyOptions o = options;
  if (flat) o.max_depth = 0;
  Builder builder(mesh, o, emitting);
  if (o.max_depth > 0) builder.group(all_pairs);
  return builder.finish();
}

void make_boxes_transparent(Hierarchy& h) {
  h.transparent = true;
  // Children come after parents: add each box's patches to its ancestors', deepest first.
  std::vector<std::vector<uint32_t>> own(h.boxes.size());
  for (size_t b = 0; b < h.boxes.size(); ++b) own[b] = h.boxes[b].patches;
  for (size_t b = h.boxes.size(); b-- > 1;)
    for (int a = h.boxes[b].parent; a >= 0; a = h.boxes[a].parent)
      h.boxes[a].patches.insert(h.boxes[a].patches.end(), own[b].begin(), own[b].end());
  for (SceneBox& box : h.boxes) {
    std::sort(box.patches.begin(), box.patches.end());
    box.grid.fill(0);
    box.set_ar_offsets();
  }
}

std::string describe_hierarchy(const Hierarchy& h, const std::vector<uint64_t>& lines) {
  std::string out = fmt::format("{} box(es), depth {}, {} ARs in subscene walls\n", h.boxes.size(), h.max_depth(), h.ar_total());
  std::vector<std::pair<int, int>> stack = {{0, 0}};
  while (!stack.empty()) {
    const auto [b, indent] = stack.back();
    stack.pop_back();
    const SceneBox& box = h.boxes[b];
    const Vec3 s = box.bounds.size();
    out += fmt::format("{:{}}box {}{}: depth {}, {} object(s) ({} direct), {} polygon(s), {} patch(es) {}, "
                       "{} child box(es), size {:.4g} x {:.4g} x {:.4g}",
                       "", 2 * indent, b, b == 0 ? " (root)" : "", box.depth, box.objects_total, box.objects.size(),
                       box.polygons_total, box.patches.size(), h.transparent ? "seen by its lines" : "direct",
                       box.children.size(), s.x, s.y, s.z);
    if (b > 0)
      out += fmt::format(", quotient {:.3f}, VP grids {}x{}, {}x{}, {}x{} (x, y, z faces), {} ARs", box.quotient, box.grid[0],
                         box.grid[0], box.grid[2], box.grid[2], box.grid[4], box.grid[4], box.ar_count());
    if (b < static_cast<int>(lines.size())) out += fmt::format(", {} lines", lines[b]);
    out += "\n";
    for (auto it = box.children.rbegin(); it != box.children.rend(); ++it) stack.push_back({*it, indent + 1});
  }
  return out;
}

}  // namespace mpath
