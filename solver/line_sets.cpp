#include "line_sets.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

#include "error.h"
#include "progress.h"

namespace mpath {

using linestore::Event;

namespace {

// The class of the pair of crossings i and j of a line of box `box`, as the
// offset of its slot from face's first slot; -1 when the box does not carry
// it (j off the line of a subscene: the pair's other end is outside the box).
inline int pair_class(const LineSets& sets, const LineSetBox& lines, bool root, const Event* ev, int n, int i,
                      int j) {
  const int a = lines.owner[ev[i].id];
  if (j < 0 || j >= n) return root ? sets.depth[a] : -1;  // the outside is the root's
  return sets.depth[a] - sets.depth[sets.common_box(a, lines.owner[ev[j].id])];
}


void check_chunk(const StoreBox& box, const linestore::DecodedChunk& chunk, int x, uint64_t c) {
  for (const Event& e : chunk.events)
    if (e.kind != Event::patch || e.id >= box.local_faces.size())
      throw InputError(fmt::format("store: box {} chunk {} names patches the box does not have (damaged or "
                                   "foreign store); run mpath-preprocess again", x, c));
}

// Per slot: what the lines of the slot's own box do at the face, and the
// crossings of every carrier of the slot's class.
struct SlotCounts {
  std::vector<double> crossings;  // by the slot's box: crossings of the face in the direction it faces
  std::vector<double> carriers;   // by any box: crossings that carry the slot's class
  std::vector<double> entries;    // by one box, per entry of the box: the same
};

void count_box(const BoxStore& store, LineSets& sets, int x, int threads, SlotCounts& counts) {
  const StoreBox& box = store.box(x);
  LineSetBox& lines = sets.boxes[x];
  const uint64_t chunks = box.chunks.size();
  const int shards = static_cast<int>(std::max<uint64_t>(1, std::min<uint64_t>(threads, chunks)));
  const size_t slots = sets.slots();
  std::vector<SlotCounts> part(shards);
  tbb::parallel_for(0, shards, [&](int s) {
    SlotCounts& p = part[s];
    for (auto* v : {&p.crossings, &p.carriers}) v->assign(slots, 0.0);
    p.entries.assign(lines.slot.size(), 0.0);
    linestore::DecodedChunk chunk;
    for (uint64_t c = chunks * s / shards; c < chunks * (s + 1) / shards; ++c) {
      store.read(x, c, chunk);
      check_chunk(box, chunk, x, c);
      for (size_t l = 0; l < chunk.lines(); ++l) {
        const Event* ev = chunk.events.data() + chunk.first[l];
        const int n = static_cast<int>(chunk.first[l + 1] - chunk.first[l]);
        for (int i = 0; i < n; ++i)
          for (const int dir : {+1, -1}) {
            const int face = face_towards(box, ev[i], dir);
            if (face < 0) continue;
            const uint32_t own = lines.slot[lines.entry[face + 1] - 1];  // this box's own class at the face
            const int k = pair_class(sets, lines, x == 0, ev, n, i, i + dir);
            p.crossings[own] += 1;
            if (k < 0) continue;
            p.carriers[sets.face_slot[box.face_global[face]] + k] += 1;
            p.entries[lines.entry[face] + k] += 1;
          }
      }
    }
  });
  lines.carried.assign(lines.slot.size(), 0.0);
  for (const SlotCounts& p : part) {
    for (size_t i = 0; i < slots; ++i) {
      counts.crossings[i] += p.crossings[i];
      counts.carriers[i] += p.carriers[i];
    }
    for (size_t e = 0; e < p.entries.size(); ++e) lines.carried[e] += p.entries[e];
  }
}

// Per box: its lines' crossings per unit area of the faces they see (the
// lines are uniform and isotropic in the box, so this is one number per box,
// estimated from all its faces at once).
std::vector<double> box_densities(const BoxStore& store, const PatchMesh& mesh, const LineSets& sets,
                                  const SlotCounts& counts) {
  std::vector<double> density(store.box_count(), 0.0);
  for (size_t x = 0; x < store.box_count(); ++x) {
    const StoreBox& box = store.box(static_cast<int>(x));
    const LineSetBox& lines = sets.boxes[x];
    double crossings = 0, area = 0;
    for (size_t f = 0; f < box.face_global.size(); ++f) {
      crossings += counts.crossings[lines.slot[lines.entry[f + 1] - 1]];
      area += mesh.face_area(box.face_global[f]);
    }
    density[x] = area > 0 ? crossings / area : 0.0;
  }
  return density;
}

}  // namespace

LineSets derive_line_sets(const BoxStore& store, const PatchMesh& mesh, int threads) {
  const Hierarchy& h = store.hierarchy();
  LineSets sets;
  for (const SceneBox& b : h.boxes) {
    sets.depth.push_back(b.depth);
    sets.parent.push_back(b.parent);
  }
  const size_t faces = mesh.face_count();
  sets.face_slot.assign(faces + 1, 0);
  for (size_t f = 0; f < faces; ++f)
    sets.face_slot[f + 1] = sets.face_slot[f] + static_cast<uint32_t>(h.boxes[h.patch_box[mesh.face_patch[f]]].depth + 1);
  // A box's lines carry, at a face, the classes from the face's own box up to the box itself.
  sets.boxes.resize(store.box_count());
  for (size_t x = 0; x < store.box_count(); ++x) {
    const SceneBox& sb = h.boxes[x];
    const StoreBox& box = store.box(static_cast<int>(x));
    LineSetBox& out = sets.boxes[x];
    out.owner.resize(sb.patches.size());
    for (size_t k = 0; k < sb.patches.size(); ++k) out.owner[k] = h.patch_box[sb.patches[k]];
    out.entry.assign(box.face_global.size() + 1, 0);
    std::vector<int> face_owner(box.face_global.size());
    for (size_t k = 0; k < box.local_faces.size(); ++k)
      for (const int local : box.local_faces[k])
        if (local >= 0) face_owner[local] = out.owner[k];
    for (size_t f = 0; f < box.face_global.size(); ++f) {
      const int classes = h.boxes[face_owner[f]].depth - sb.depth + 1;
      out.entry[f + 1] = out.entry[f] + static_cast<uint32_t>(classes);
      for (int k = 0; k < classes; ++k) out.slot.push_back(sets.face_slot[box.face_global[f]] + k);
    }
  }
  SlotCounts counts;
  for (auto* v : {&counts.crossings, &counts.carriers}) v->assign(sets.slots(), 0.0);
  for (size_t x = 0; x < store.box_count(); ++x) count_box(store, sets, static_cast<int>(x), threads, counts);
  sets.density = box_densities(store, mesh, sets, counts);
  // A class's carriers are its own box and every box above it.
  sets.weight.assign(sets.slots(), 0.0);
  for (size_t f = 0; f < faces; ++f) {
    int b = h.patch_box[mesh.face_patch[f]];
    bool carried = false;
    for (uint32_t s = sets.face_slot[f]; s < sets.face_slot[f + 1]; ++s, b = h.boxes[b].parent) {
      double d = 0;
      for (int y = b; y >= 0; y = h.boxes[y].parent) d += sets.density[y];
      sets.weight[s] = d > 0 ? 1.0 / d : 0.0;
      carried |= counts.carriers[s] > 0 && d > 0;
    }
    if (!carried) sets.uncarried.push_back(static_cast<int>(f));
  }
  return sets;
}

namespace {

// Which lines each box's pass takes this iteration, and per face the sum
// of 1 / D over the carrying crossings of those lines (expected).
struct Plan {
  std::vector<double> fraction;               // per box: of its lines, the share this iteration takes
  std::vector<std::vector<ChunkPart>> parts;  // per box: which
  std::vector<double> z;                      // per mesh face
};

// What a pass reads of a face and of an entry (a face a box sees and a
// class it carries there), each in one record.
struct FaceIn {
  double quota[3] = {0, 0, 0};  // its unshot power, taken at the start of the pass
  double rho[3] = {0, 0, 0};
  double scale = 0;             // 1 / z: of the quota, what a crossing of weight 1 sends
};
struct EntryIn {
  double share;  // of the face's quota, what one crossing sends: (1 / D) / z
  double take;   // of what the face gathered, the share one crossing sends on: D_min / D
};
struct LocalFace {
  int face;        // mesh face
  uint32_t entry;  // its first entry in the box
};

// A shard's private accumulators for a pass.
struct alignas(64) FaceAcc {
  double gathered[3] = {0, 0, 0};  // received, sent on by its next carrying crossings
  double used = 0;                 // fraction of the quota sent
  double phi_gain[3] = {0, 0, 0};
};
struct alignas(128) SetShard {
  std::vector<FaceAcc> faces;      // per mesh face
  PassLineBuffers buffers;
  std::vector<double> allowance;   // per mesh face: of its quota, the shard's part (a part of the lines)
  std::vector<BoxPassStats> boxes;
  std::array<double, 3> absorbed{}, escaped{};
  struct Send {
    int from, dir;
    double power[3];
  };
  std::vector<Send> sends;
};

struct PassContext {
  const BoxStore* store;
  const LineSets* sets;
  std::vector<FaceIn> faces;                 // per mesh face
  std::vector<std::vector<EntryIn>> entries;  // per box, per entry
  std::vector<std::vector<LocalFace>> local;  // per box, per local face
  bool capped;  // a part of the lines: no shard sends more than its part of a quota
};

template <int CH>
void transport_set_line(const PassContext& in, int x, const Event* ev, int n, SetShard& shard) {
  constexpr int ch = CH;
  if (n == 0) return;
  const StoreBox& box = in.store->box(x);
  const LineSets& sets = *in.sets;
  const LineSetBox& lines = sets.boxes[x];
  const std::vector<EntryIn>& entries = in.entries[x];
  const std::vector<LocalFace>& local_faces = in.local[x];
  const bool root = x == 0;
  auto& sends = shard.sends;
  sends.clear();
  for (int i = 0; i < n; ++i)
    for (const int dir : {+1, -1}) {
      const int local = face_towards(box, ev[i], dir);
      if (local < 0) continue;
      const int k = pair_class(sets, lines, root, ev, n, i, i + dir);
      if (k < 0) continue;
      const LocalFace& lf = local_faces[local];
      const EntryIn& entry = entries[lf.entry + static_cast<uint32_t>(k)];
      const FaceIn& face = in.faces[lf.face];
      FaceAcc& acc = shard.faces[lf.face];
      double share = entry.share;
      if (in.capped) share = std::max(0.0, std::min(share, shard.allowance[lf.face] - acc.used));
      acc.used += share;
      SetShard::Send s{i, dir, {0, 0, 0}};
      bool any = false;
      for (int c = 0; c < ch; ++c) {
        const double on = acc.gathered[c] * entry.take;
        s.power[c] = face.quota[c] * share + on;
        acc.gathered[c] -= on;
        any |= s.power[c] != 0;
      }
      if (any) sends.push_back(s);
    }
  for (const SetShard::Send& s : sends) {
    const int j = s.from + s.dir;
    if (j < 0 || j >= n) {  // off the line: only the root sends there, out of the scene
      for (int c = 0; c < ch; ++c) shard.escaped[c] += s.power[c];
      continue;
    }
    const int local = face_towards(box, ev[j], -s.dir);  // turned towards the power
    if (local < 0) {
      for (int c = 0; c < ch; ++c) shard.absorbed[c] += s.power[c];
      continue;
    }
    const size_t face = static_cast<size_t>(box.face_global[local]);
    const FaceIn& f = in.faces[face];
    FaceAcc& acc = shard.faces[face];
    for (int c = 0; c < ch; ++c) {
      const double kept = f.rho[c] * s.power[c];
      acc.phi_gain[c] += kept;
      acc.gathered[c] += kept;
      shard.absorbed[c] += s.power[c] - kept;
    }
  }
}

struct SetResult {
  std::array<double, 3> absorbed{}, escaped{};
  std::vector<BoxPassStats> boxes;
};

// One pass over the lines of every box, interleaved (each box's parts spread
// evenly over the pass), so that what a face receives from any box's line is
// sent on in the same pass by the face's next carrying crossings, of any box.
SetResult set_pass(const BoxStore& store, const LineSets& sets, RadiosityState& state, const Plan& plan, int threads,
                   unsigned pass, Progress& progress) {
  const int ch = state.channels;
  const size_t boxes = store.box_count(), faces = state.faces;
  bool every_line = true;
  for (double f : plan.fraction) every_line &= f >= 1.0;
  PassContext in{&store, &sets, {}, {}, {}, !every_line};
  // Unshot power takes off: a crossing of class k sends (1 / D_k) / z of it.
  in.faces.resize(faces);
  for (size_t f = 0; f < faces; ++f) {
    FaceIn& face = in.faces[f];
    for (int c = 0; c < ch; ++c) face.rho[c] = state.rho[state.at(f, c)];
    if (!(plan.z[f] > 0)) continue;
    face.scale = 1.0 / plan.z[f];
    for (int c = 0; c < ch; ++c) {
      face.quota[c] = state.unshot[state.at(f, c)];
      state.unshot[state.at(f, c)] = 0;
    }
  }
  // Gathered power leaves by a crossing of class k with share D_min / D_k
  // (<= 1; D_min the least D of any class, the root's), so that it leaves by
  // each class in proportion to its crossings' weights 1 / D_k, as the quota
  // does.
  double most = 0;
  for (double w : sets.weight) most = std::max(most, w);
  in.entries.resize(boxes);
  in.local.resize(boxes);
  for (size_t x = 0; x < boxes; ++x) {
    const StoreBox& box = store.box(static_cast<int>(x));
    const LineSetBox& lines = sets.boxes[x];
    std::vector<EntryIn>& entries = in.entries[x];
    entries.resize(lines.slot.size());
    in.local[x].resize(box.face_global.size());
    for (size_t f = 0; f < box.face_global.size(); ++f) {
      const int g = box.face_global[f];
      in.local[x][f] = {g, lines.entry[f]};
      for (uint32_t e = lines.entry[f]; e < lines.entry[f + 1]; ++e) {
        const double w = sets.weight[lines.slot[e]];
        entries[e] = {w * in.faces[g].scale, most > 0 ? std::min(1.0, w / most) : 0.0};
      }
    }
  }
  // The pass's parts, every box's spread over it by its place in the box's run.
  struct Item {
    int box;
    uint64_t part;
    double place;
  };
  std::vector<Item> items;
  for (size_t x = 0; x < boxes; ++x) {
    const uint64_t n = plan.parts[x].size();
    for (uint64_t i = 0; i < n; ++i) items.push_back({static_cast<int>(x), i, (i + 0.5) / static_cast<double>(n)});
  }
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) { return a.place < b.place; });
  std::vector<uint64_t> pass_lines(boxes, 0);
  for (size_t x = 0; x < boxes; ++x) pass_lines[x] = part_lines(plan.parts[x], 0, plan.parts[x].size());
  const int shards = static_cast<int>(std::max<size_t>(1, std::min<size_t>(threads, items.size())));
  std::vector<SetShard> acc(shards);
  tbb::parallel_for(0, shards, [&](int s) {
    SetShard& a = acc[s];
    a.faces.assign(faces, FaceAcc{});
    a.boxes.assign(boxes, BoxPassStats{});
    const size_t lo = items.size() * s / shards, hi = items.size() * (s + 1) / shards;
    if (in.capped) {
      // Of a face's quota, the shard may send what its lines of each box
      // are expected to: their part of the box's pass, times the box's part
      // of the face's z.
      std::vector<double> part(boxes, 0.0);
      for (size_t i = lo; i < hi; ++i) part[items[i].box] += plan.parts[items[i].box][items[i].part].lines;
      a.allowance.assign(faces, 0.0);
      for (size_t x = 0; x < boxes; ++x) {
        if (!(part[x] > 0)) continue;
        const double share = part[x] / double(pass_lines[x]) * plan.fraction[x];
        const LineSetBox& lines = sets.boxes[x];
        for (size_t f = 0; f < in.local[x].size(); ++f)
          for (uint32_t e = lines.entry[f]; e < lines.entry[f + 1]; ++e)
            a.allowance[in.local[x][f].face] += share * lines.carried[e] * in.entries[x][e].share;
      }
    }
    for (size_t i = lo; i < hi; ++i) {
      const int x = items[i].box;
      const StoreBox& box = store.box(x);
      const auto start = std::chrono::steady_clock::now();
      BoxPassStats& stats = a.boxes[x];
      stream_pass_lines(
          store, x, plan.parts[x], items[i].part, items[i].part + 1, pass, progress,
          [&](const linestore::DecodedChunk& chunk, uint64_t c) { check_chunk(box, chunk, x, c); },
          [&](const linestore::DecodedChunk& chunk, uint32_t l) {
            const Event* ev = chunk.events.data() + chunk.first[l];
            const int m = static_cast<int>(chunk.first[l + 1] - chunk.first[l]);
            ++stats.lines;
            stats.hits += m;
            (ch == 1 ? transport_set_line<1> : transport_set_line<3>)(in, x, ev, m, a);
          },
          &a.buffers);
      stats.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  });
  // Merge in shard order: what the quota did not send (lines lost to damage;
  // rounding) and what was gathered and not sent on are unshot again.
  SetResult result;
  result.boxes.assign(boxes, BoxPassStats{});
  for (size_t f = 0; f < faces; ++f) {
    double used = 0;
    for (const SetShard& a : acc) used += a.faces[f].used;
    for (int c = 0; c < ch; ++c) {
      double back = in.faces[f].quota[c] * (1.0 - used);
      for (const SetShard& a : acc) {
        back += a.faces[f].gathered[c];
        state.phi[state.at(f, c)] += a.faces[f].phi_gain[c];
      }
      state.unshot[state.at(f, c)] += back;
    }
  }
  for (const SetShard& a : acc) {
    for (int c = 0; c < ch; ++c) {
      result.absorbed[c] += a.absorbed[c];
      result.escaped[c] += a.escaped[c];
    }
    for (size_t x = 0; x < boxes; ++x) {
      result.boxes[x].lines += a.boxes[x].lines;
      result.boxes[x].hits += a.boxes[x].hits;
      result.boxes[x].seconds += a.boxes[x].seconds;
    }
  }
  return result;
}

// Which lines each box takes this iteration: all, or (an adaptive pass) as
// many as carry about `power_per_line` each, at least the box's coverage;
// and each face's z over the lines taken.
Plan plan_iteration(const BoxStore& store, const LineSets& sets, const RadiosityState& state, double power_per_line,
                    unsigned pass) {
  const size_t boxes = store.box_count();
  Plan plan;
  plan.fraction.assign(boxes, 1.0);
  plan.parts.assign(boxes, {});
  const double power = state.unshot_total();
  for (size_t x = 0; x < boxes; ++x) {
    const StoreBox& box = store.box(static_cast<int>(x));
    if (power_per_line > 0 && box.lines > 0)
      plan.fraction[x] = std::clamp(power / (power_per_line * static_cast<double>(store.lines())), box.coverage, 1.0);
    plan.parts[x] = pass_parts(store, static_cast<int>(x), plan.fraction[x], pass);
    if (plan.fraction[x] < 1.0 && box.lines > 0) {
      uint64_t lines = 0;
      for (const ChunkPart& p : plan.parts[x]) lines += p.lines;
      plan.fraction[x] = static_cast<double>(lines) / static_cast<double>(box.lines);
    }
  }
  plan.z.assign(state.faces, 0.0);
  std::vector<bool> uncarried(state.faces, false);
  for (int f : sets.uncarried) uncarried[f] = true;
  for (size_t x = 0; x < boxes; ++x) {
    const StoreBox& box = store.box(static_cast<int>(x));
    const LineSetBox& lines = sets.boxes[x];
    for (size_t f = 0; f < box.face_global.size(); ++f)
      for (uint32_t e = lines.entry[f]; e < lines.entry[f + 1]; ++e)
        plan.z[box.face_global[f]] += plan.fraction[x] * lines.carried[e] * sets.weight[lines.slot[e]];
  }
  for (size_t f = 0; f < state.faces; ++f)
    if (uncarried[f]) plan.z[f] = 0;
  return plan;
}

}  // namespace

PassStats line_set_iteration(const PatchMesh& mesh, const Tracer& tracer, const BoxStore& store, const LineSets& sets,
                             RadiosityState& state, unsigned pass, int threads, double power_per_line,
                             unsigned long long seed, std::vector<BoxPassStats>* per_box, uint64_t* uncarried_lines) {
  const auto start = std::chrono::steady_clock::now();
  const int ch = state.channels;
  const Plan plan = plan_iteration(store, sets, state, power_per_line, pass);
  Progress progress(fmt::format("iteration {}", pass), store.lines(), "lines", true);
  const SetResult result = set_pass(store, sets, state, plan, threads, pass, progress);
  progress.finish();
  for (int c = 0; c < ch; ++c) {
    state.energy.absorbed[c] += result.absorbed[c];
    state.energy.escaped[c] += result.escaped[c];
  }
  PassStats stats;
  stats.pass = static_cast<int>(pass);
  for (const BoxPassStats& b : result.boxes) {
    stats.lines += b.lines;
    stats.hits += b.hits;
  }
  if (per_box) *per_box = result.boxes;
  std::vector<int> waiting;
  for (int f : sets.uncarried)
    for (int c = 0; c < ch; ++c)
      if (state.unshot[state.at(static_cast<size_t>(f), c)] != 0) {
        waiting.push_back(f);
        break;
      }
  const uint64_t shot = shoot_unshot(mesh, tracer, waiting, state, pass, seed, threads);
  if (uncarried_lines) *uncarried_lines += shot;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.unshot_fraction = state.remaining_fraction();
  return stats;
}

}  // namespace mpath
