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

// The face of local patch `id` turned towards `dir` along the line.
inline int face_towards(const StoreBox& box, const Event& e, int dir) {
  const auto& f = box.local_faces[e.id];
  return (dir > 0) == e.along ? f[0] : f[1];
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
};

void count_box(const BoxStore& store, const LineSets& sets, int x, int threads, SlotCounts& counts) {
  const StoreBox& box = store.box(x);
  const LineSetBox& lines = sets.boxes[x];
  const uint64_t chunks = box.chunks.size();
  const int shards = static_cast<int>(std::max<uint64_t>(1, std::min<uint64_t>(threads, chunks)));
  const size_t slots = sets.slots();
  std::vector<SlotCounts> part(shards);
  tbb::parallel_for(0, shards, [&](int s) {
    SlotCounts& p = part[s];
    for (auto* v : {&p.crossings, &p.carriers}) v->assign(slots, 0.0);
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
          }
      }
    }
  });
  for (const SlotCounts& p : part)
    for (size_t i = 0; i < slots; ++i) {
      counts.crossings[i] += p.crossings[i];
      counts.carriers[i] += p.carriers[i];
    }
}

// The shares of a face's power among its classes (its own box first, the
// root last). A line of box Y at the face meets next a patch of class k (one
// not above Y) with probability alpha_k, so the carriers' crossings of class
// k over all crossings of the face by the carriers' lines estimate alpha_k
// from every line that can see it. False when no line carries any class.
bool face_shares(const SlotCounts& counts, uint32_t first, uint32_t end, double* alpha) {
  double sum = 0, seen = 0;
  for (uint32_t s = end; s-- > first;) {
    seen += counts.crossings[s];  // the crossings of every box from this class's up to the root
    alpha[s - first] = seen > 0 ? counts.carriers[s] / seen : 0.0;
    sum += alpha[s - first];
  }
  if (!(sum > 0)) return false;
  for (uint32_t s = first; s < end; ++s) alpha[s - first] /= sum;
  return true;
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
  sets.alpha.assign(sets.slots(), 0.0);
  for (size_t f = 0; f < faces; ++f)
    if (!face_shares(counts, sets.face_slot[f], sets.face_slot[f + 1], &sets.alpha[sets.face_slot[f]]))
      sets.uncarried.push_back(static_cast<int>(f));
  sets.carriers = std::move(counts.carriers);
  return sets;
}

namespace {

// The power of each class in flight during an iteration: taken from the
// pools at the start of the class's own box's pass, sent by that pass and
// those of the boxes above, what is left returned at the end.
struct Flight {
  std::vector<double> quota;  // slot * channels
  std::vector<double> used;   // per slot: fraction of the quota sent
};

// A shard's private accumulators for one box's pass, per entry of the box.
struct alignas(128) SetShard {
  std::vector<double> gathered;   // entry * channels: received, sent on along the next crossing of its class
  std::vector<double> used;       // per entry
  std::vector<double> phi_gain;   // local face * channels
  std::vector<double> later;      // local face * channels: received, for the classes of boxes above this one
  std::array<double, 3> absorbed{}, escaped{};
  uint64_t lines = 0, hits = 0;
  struct Send {
    int from, dir;
    double power[3];
  };
  std::vector<Send> sends;
};

struct PassContext {
  const StoreBox* box;
  const LineSetBox* lines;
  const LineSets* sets;
  const RadiosityState* state;
  const Flight* flight;
  bool root;
};

template <int CH>
void transport_set_line(const PassContext& in, const Event* ev, int n, SetShard& shard) {
  constexpr int ch = CH;
  ++shard.lines;
  shard.hits += n;
  if (n == 0) return;
  const StoreBox& box = *in.box;
  const LineSetBox& lines = *in.lines;
  const LineSets& sets = *in.sets;
  auto& sends = shard.sends;
  sends.clear();
  for (int i = 0; i < n; ++i)
    for (const int dir : {+1, -1}) {
      const int face = face_towards(box, ev[i], dir);
      if (face < 0) continue;
      const int k = pair_class(sets, lines, in.root, ev, n, i, i + dir);
      if (k < 0) continue;
      const uint32_t e = lines.entry[face] + static_cast<uint32_t>(k);
      const uint32_t slot = lines.slot[e];
      const double share = sets.carriers[slot] > 0 ? 1.0 / sets.carriers[slot] : 0.0;
      shard.used[e] += share;
      SetShard::Send s{i, dir, {0, 0, 0}};
      bool any = false;
      for (int c = 0; c < ch; ++c) {
        double& g = shard.gathered[size_t{e} * ch + c];
        s.power[c] = in.flight->quota[size_t{slot} * ch + c] * share + g;
        g = 0;
        any |= s.power[c] != 0;
      }
      if (any) sends.push_back(s);
    }
  const RadiosityState& state = *in.state;
  for (const SetShard::Send& s : sends) {
    const int j = s.from + s.dir;
    if (j < 0 || j >= n) {  // off the line: only the root sends there, out of the scene
      for (int c = 0; c < ch; ++c) shard.escaped[c] += s.power[c];
      continue;
    }
    const int face = face_towards(box, ev[j], -s.dir);  // turned towards the power
    if (face < 0) {
      for (int c = 0; c < ch; ++c) shard.absorbed[c] += s.power[c];
      continue;
    }
    // rho of it stays, shared by the face's classes: those this box carries
    // are sent on in this pass, the rest waits for the boxes above.
    const size_t g = static_cast<size_t>(box.face_global[face]);
    const uint32_t first = lines.entry[face], carried = lines.entry[face + 1] - first;
    const uint32_t slot0 = sets.face_slot[g], classes = sets.face_slot[g + 1] - slot0;
    for (int c = 0; c < ch; ++c) {
      const double kept = state.rho[state.at(g, c)] * s.power[c];
      shard.phi_gain[size_t(face) * ch + c] += kept;
      shard.absorbed[c] += s.power[c] - kept;
      double sent_on = 0;
      for (uint32_t k = 0; k < carried; ++k) {
        const double part = kept * sets.alpha[slot0 + k];
        shard.gathered[size_t{first + k} * ch + c] += part;
        sent_on += part;
      }
      if (carried < classes) shard.later[size_t(face) * ch + c] += kept - sent_on;
    }
  }
}

struct SetResult {
  std::array<double, 3> absorbed{}, escaped{};
  BoxPassStats stats;
};

// Adds `amount` to the pools of a face's classes from `from` on, in
// proportion to their shares (the last takes what rounding leaves).
void pool_classes(const LineSets& sets, size_t face, uint32_t from, int ch, int c, double amount,
                  std::vector<double>& pooled) {
  const uint32_t slot0 = sets.face_slot[face], end = sets.face_slot[face + 1];
  double total = 0;
  uint32_t last = end;
  for (uint32_t s = slot0 + from; s < end; ++s)
    if (sets.alpha[s] > 0) {
      total += sets.alpha[s];
      last = s;
    }
  if (last == end) last = end - 1;  // no share above: the root's class keeps it
  double given = 0;
  for (uint32_t s = slot0 + from; s < end; ++s) {
    if (s != last && !(sets.alpha[s] > 0)) continue;
    const double part = s == last ? amount - given : amount * sets.alpha[s] / total;
    pooled[size_t{s} * ch + c] += part;
    given += part;
  }
}

SetResult set_pass(const BoxStore& store, const LineSets& sets, int x, RadiosityState& state, Flight& flight,
                   int threads, unsigned pass, Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const StoreBox& box = store.box(x);
  const LineSetBox& lines = sets.boxes[x];
  const int ch = state.channels;
  const uint32_t entries = lines.entry.back();
  // This box's own class at every face it sees (the face's last entry) takes off now.
  for (size_t f = 0; f + 1 < lines.entry.size(); ++f) {
    const uint32_t slot = lines.slot[lines.entry[f + 1] - 1];
    for (int c = 0; c < ch; ++c) {
      flight.quota[size_t{slot} * ch + c] = state.pooled[size_t{slot} * ch + c];
      state.pooled[size_t{slot} * ch + c] = 0;
    }
    flight.used[slot] = 0;
  }
  const PassContext in{&box, &lines, &sets, &state, &flight, x == 0};
  const uint64_t chunks = box.chunks.size();
  const int shards = static_cast<int>(std::max<uint64_t>(1, std::min<uint64_t>(threads, chunks)));
  std::vector<SetShard> acc(shards);
  const size_t faces = box.face_global.size();
  tbb::parallel_for(0, shards, [&](int s) {
    SetShard& a = acc[s];
    a.gathered.assign(size_t{entries} * ch, 0.0);
    a.used.assign(entries, 0.0);
    a.phi_gain.assign(faces * ch, 0.0);
    a.later.assign(faces * ch, 0.0);
    linestore::DecodedChunk chunk;
    std::vector<uint32_t> order;
    for (uint64_t c = chunks * s / shards; c < chunks * (s + 1) / shards; ++c) {
      store.read(x, c, chunk);
      check_chunk(box, chunk, x, c);
      chunk_line_order(pass, x, c, chunk.lines(), order);
      for (const uint32_t l : order) {
        const Event* ev = chunk.events.data() + chunk.first[l];
        const int m = static_cast<int>(chunk.first[l + 1] - chunk.first[l]);
        (ch == 1 ? transport_set_line<1> : transport_set_line<3>)(in, ev, m, a);
      }
      progress.advance(chunk.lines());
    }
  });
  // Merge in shard order: the quota sent, what each class gathered and did
  // not send (back to its pool), what waits for the boxes above.
  SetResult result;
  for (size_t f = 0; f < faces; ++f) {
    const size_t g = static_cast<size_t>(box.face_global[f]);
    const uint32_t carried = lines.entry[f + 1] - lines.entry[f];
    for (uint32_t k = 0; k < carried; ++k) {
      const uint32_t e = lines.entry[f] + k, slot = lines.slot[e];
      for (const SetShard& a : acc) {
        flight.used[slot] += a.used[e];
        for (int c = 0; c < ch; ++c) state.pooled[size_t{slot} * ch + c] += a.gathered[size_t{e} * ch + c];
      }
    }
    for (int c = 0; c < ch; ++c) {
      double later = 0;
      for (const SetShard& a : acc) {
        state.phi[state.at(g, c)] += a.phi_gain[f * ch + c];
        later += a.later[f * ch + c];
      }
      if (later != 0) pool_classes(sets, g, carried, ch, c, later, state.pooled);
    }
  }
  for (const SetShard& a : acc) {
    for (int c = 0; c < ch; ++c) {
      result.absorbed[c] += a.absorbed[c];
      result.escaped[c] += a.escaped[c];
    }
    result.stats.lines += a.lines;
    result.stats.hits += a.hits;
  }
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

// New unshot power (the first shot's, local lines') goes to the pools of its
// face's classes in proportion to their shares; uncarried faces keep theirs.
void assign_unshot(const LineSets& sets, RadiosityState& state) {
  const int ch = state.channels;
  std::vector<bool> uncarried(state.faces, false);
  for (int f : sets.uncarried) uncarried[f] = true;
  for (size_t f = 0; f < state.faces; ++f) {
    if (uncarried[f]) continue;
    for (int c = 0; c < ch; ++c) {
      double& u = state.unshot[state.at(f, c)];
      if (u == 0) continue;
      pool_classes(sets, f, 0, ch, c, u, state.pooled);
      u = 0;
    }
  }
}

}  // namespace

PassStats line_set_iteration(const PatchMesh& mesh, const Tracer& tracer, const BoxStore& store, const LineSets& sets,
                             RadiosityState& state, unsigned pass, int threads, unsigned long long seed,
                             std::vector<BoxPassStats>* per_box, uint64_t* uncarried_lines) {
  const auto start = std::chrono::steady_clock::now();
  const Hierarchy& h = store.hierarchy();
  const int ch = state.channels;
  assign_unshot(sets, state);
  Flight flight;
  flight.quota.assign(sets.slots() * ch, 0.0);
  flight.used.assign(sets.slots(), 0.0);
  // Deepest boxes first, the root last. Boxes of one depth hold disjoint
  // faces and run in parallel.
  std::vector<std::vector<int>> at_depth(h.max_depth() + 1);
  for (int b : h.depth_order) at_depth[h.boxes[b].depth].push_back(b);
  Progress progress(fmt::format("iteration {}", pass), store.lines(), "lines", true);
  PassStats stats;
  stats.pass = static_cast<int>(pass);
  if (per_box) per_box->assign(h.boxes.size(), BoxPassStats{});
  for (int d = h.max_depth(); d >= 0; --d) {
    const std::vector<int>& boxes = at_depth[d];
    std::vector<SetResult> results(boxes.size());
    tbb::parallel_for(size_t{0}, boxes.size(), [&](size_t k) {
      results[k] = set_pass(store, sets, boxes[k], state, flight, threads, pass, progress);
    });
    for (size_t k = 0; k < boxes.size(); ++k) {
      for (int c = 0; c < ch; ++c) {
        state.energy.absorbed[c] += results[k].absorbed[c];
        state.energy.escaped[c] += results[k].escaped[c];
      }
      stats.lines += results[k].stats.lines;
      stats.hits += results[k].stats.hits;
      if (per_box) (*per_box)[boxes[k]] = results[k].stats;
    }
  }
  progress.finish();
  // What no crossing took (a class whose carriers lost lines to damage; rounding) goes back to its pool.
  for (size_t s = 0; s < sets.slots(); ++s)
    for (int c = 0; c < ch; ++c) state.pooled[s * ch + c] += flight.quota[s * ch + c] * (1.0 - flight.used[s]);
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
