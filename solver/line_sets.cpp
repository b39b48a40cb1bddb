#include "line_sets.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <mutex>
#include <utility>

#include "error.h"
#include "first_shot.h"
#include "line_order.h"
#include "prefetch.h"
#include "progress.h"

namespace mpath {

using linestore::Event;

namespace {

// The class of the pair of crossings i and j of a line of box `box`, as the
// offset of its slot from face's first slot; -1 when the box does not carry
// it (j off the line of a subscene: the pair's other end is outside the box).
inline int pair_class(const LineSets& sets, const LineSetBox& lines, bool root, const Event* ev, int n, int i,
                      int j) {
  return sets.tree.pair_class(lines.owner[ev[i].id], j < 0 || j >= n ? -1 : lines.owner[ev[j].id], root);
}


// A line-set pass's events name only patches of the box, and each patch
// event's AR fields (which only child-box events use) hold the faces it
// turns towards along the line and against it (face_towards), written by
// the decoder from the box's table (linestore::EventSides) as it decodes
// the chunk (a second walk over the decoded events to look them up was a
// few per cent of a pass where the records fit the caches), so that a
// line's transport and its prefetches start from the faces instead of
// waiting for each patch's record first. The chunk is the thread's own
// decoded copy.
linestore::EventSides event_sides(const StoreBox& box) {
  static_assert(offsetof(LocalPatch, faces) == 0 && sizeof(LocalPatch::faces) == 2 * sizeof(int));
  return {box.local_faces.data(), sizeof(LocalPatch), box.local_faces.size()};
}

// Throws naming the chunk where it names anything but the box's patches.
void check_chunk_faces(const linestore::DecodedChunk& chunk, int x, uint64_t c) {
  if (chunk.foreign_events)
    throw InputError(fmt::format("store: box {} chunk {} names patches the box does not have (damaged or "
                                 "foreign store); run mpath-preprocess again", x, c));
}

// face_towards(box, e, dir) of an event decoded with event_sides.
inline int towards(const Event& e, int dir) { return static_cast<int>(dir > 0 ? e.entry_ar : e.exit_ar); }

// Per slot: what the lines of the slot's own box do at the face, and the
// crossings of every carrier of the slot's class.
struct SlotCounts {
  std::vector<double> crossings;  // by the slot's box: crossings of the face in the direction it faces
  std::vector<double> carriers;   // by any box: crossings that carry the slot's class
};

// Box x's part of the counts, from the class crossings its store files hold
// (counted by mpath-preprocess while tracing; a face meets the box's lines as
// often as its patch does).
void count_box(const BoxStore& store, const Hierarchy& h, LineSets& sets, int x, SlotCounts& counts) {
  const StoreBox& box = store.box(x);
  LineSetBox& lines = sets.boxes[x];
  const size_t span = static_cast<size_t>(h.class_span(x));
  lines.carried.assign(lines.slot.size(), 0.0);
  for (size_t k = 0; k < box.local_faces.size(); ++k)
    for (size_t side = 0; side < 2; ++side) {
      const int face = box.local_faces[k][side];
      if (face < 0) continue;
      const uint32_t first = lines.entry[face], end = lines.entry[face + 1];
      counts.crossings[lines.slot[end - 1]] += box.counts.patch_crossings[k];  // this box's own class at the face
      for (uint32_t e = first; e < end; ++e) {
        const double n = box.counts.class_crossings[linestore::class_slot(k, side, span, e - first)];
        lines.carried[e] = n;
        counts.carriers[lines.slot[e]] += n;
      }
    }
  lines.distinct = lines.carried;
  std::sort(lines.distinct.begin(), lines.distinct.end());
  lines.distinct.erase(std::unique(lines.distinct.begin(), lines.distinct.end()), lines.distinct.end());
  lines.rank.resize(lines.carried.size());
  for (size_t e = 0; e < lines.carried.size(); ++e)
    lines.rank[e] = static_cast<uint32_t>(std::lower_bound(lines.distinct.begin(), lines.distinct.end(), lines.carried[e]) -
                                          lines.distinct.begin());
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

LineSets derive_line_sets(const BoxStore& store, const PatchMesh& mesh) {
  const Hierarchy& h = store.hierarchy();
  LineSets sets;
  sets.tree = BoxTree(h);
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
  for (size_t x = 0; x < store.box_count(); ++x) count_box(store, h, sets, static_cast<int>(x), counts);
  sets.alpha.assign(sets.slots(), 0.0);
  for (size_t f = 0; f < faces; ++f)
    if (!face_shares(counts, sets.face_slot[f], sets.face_slot[f + 1], &sets.alpha[sets.face_slot[f]]))
      sets.uncarried.push_back(static_cast<int>(f));
  sets.pool = std::make_shared<SetShardPool>();
  return sets;
}

namespace {

// The power of each class in flight during an iteration: taken from the
// pools at the start of the class's own box's pass, sent by that pass and
// those of the boxes above, what is left returned at the end.
struct Flight {
  std::vector<double> quota;  // slot * channels
  std::vector<double> used;   // per slot: fraction of the quota sent
  std::vector<double> share;  // per slot: of the quota, what one carrying crossing sends
  std::vector<double> fraction;             // per box: of its lines, the share this iteration takes
  std::vector<std::vector<ChunkPart>> parts;  // per box: which
};

// What a pass reads of an entry (a face and one of the classes the box
// carries there) and of a face, each in one record of a cache line's half.
struct alignas(32) EntryInput {
  double quota[3] = {0, 0, 0};  // the class's power in flight
  double share = 0;             // of it, what one carrying crossing sends
};
struct alignas(32) FaceIn {
  double rho[3] = {0, 0, 0};
  uint32_t entry = 0;  // its first entry
  // The shares of the classes the box carries at the face, summed (1 when
  // none is above the box); its sign bit set when the box carries one class.
  float signed_share = 1;
  float carried_share() const { return std::fabs(signed_share); }
  bool single() const { return std::signbit(signed_share); }
};
static_assert(sizeof(EntryInput) == 32 && sizeof(FaceIn) == 32);

// A shard's private accumulators for one box's pass.
struct EntryAcc {
  double used = 0;  // fraction of the quota sent
};
struct FaceAcc {
  double phi_gain[3] = {0, 0, 0};
  double gathered[3] = {0, 0, 0};  // received, for the classes the box carries: sent on along the next crossing
};
// Received, for the classes of boxes above this one (a subscene's faces).
struct FaceLater {
  double later[3] = {0, 0, 0};
};
// All are summed over ranks as arrays of doubles.
static_assert(sizeof(EntryAcc) == sizeof(double) && sizeof(FaceAcc) == 6 * sizeof(double) &&
              sizeof(FaceLater) == 3 * sizeof(double));
// Taken from the pool (SetShardPool) for a pass, all zero, with at least
// as many records as the box has entries and faces (`later` too where some
// face's classes wait for a box above; not in the root's pass); the pass
// uses the first `used_entries` / `used_faces` / `used_later` and its merge
// sets them to zero again.
struct alignas(128) SetShard {
  std::vector<EntryAcc> entries;
  std::vector<FaceAcc> faces;
  std::vector<FaceLater> later;
  size_t used_entries = 0, used_faces = 0, used_later = 0;
  double allowance = 0;  // a part of the lines: of each entry's expected share, the most this shard may send
  std::array<double, 3> absorbed{}, escaped{};
  uint64_t lines = 0, hits = 0;
  struct Send {
    int to, dir;  // the crossing it reaches (-1 or n: off the line), and its way
    double power[3];
  };
  std::vector<Send> sends;

  // How many zero records it lacks for a pass of these extents.
  size_t lacking(size_t e, size_t f, size_t l) const {
    const auto short_of = [](size_t have, size_t want) { return want > have ? want - have : 0; };
    return short_of(entries.size(), e) * sizeof(EntryAcc) + short_of(faces.size(), f) * sizeof(FaceAcc) +
           short_of(later.size(), l) * sizeof(FaceLater);
  }
  void sum_over_ranks() {
    Ranks::sum_records(entries.data(), used_entries);
    Ranks::sum_records(faces.data(), used_faces);
    Ranks::sum_records(later.data(), used_later);
    sum_totals_over_ranks(absorbed, escaped, lines, hits);
  }
};

}  // namespace

// A pass's shards come from here and go back after its merge, all zero, so
// that a pass neither allocates nor clears them (on soda's 107k-face root
// 8 shards of about 12 MB were allocated and cleared every pass: the
// clearing loops, and fresh pages, were a visible part of a short kept-store
// solve's profile; docs/performance.md, "Shard accumulators"). A shard grows
// to the largest box it serves and stays so; boxes of one depth take theirs
// side by side, so the pool holds about as many as the passes running at
// once need.
struct SetShardPool {
  // `n` shards for a pass of these extents: of the pooled ones, those that
  // lack the fewest bytes (the smallest that fit), grown where they must be.
  std::vector<SetShard> take(int n, size_t entries, size_t faces, size_t later) {
    std::vector<SetShard> out;
    out.reserve(static_cast<size_t>(n));
    {
      const std::lock_guard<std::mutex> lock(mutex);
      for (int k = 0; k < n && !free.empty(); ++k) {
        size_t best = 0;
        for (size_t i = 1; i < free.size(); ++i) {
          const size_t li = free[i].lacking(entries, faces, later), lb = free[best].lacking(entries, faces, later);
          if (li < lb || (li == lb && free[i].faces.size() < free[best].faces.size())) best = i;
        }
        out.push_back(std::move(free[best]));
        free.erase(free.begin() + static_cast<std::ptrdiff_t>(best));
      }
    }
    out.resize(static_cast<size_t>(n));
    for (SetShard& a : out) {
      if (a.entries.size() < entries) a.entries.resize(entries);
      if (a.faces.size() < faces) a.faces.resize(faces);
      if (a.later.size() < later) a.later.resize(later);
      a.used_entries = entries;
      a.used_faces = faces;
      a.used_later = later;
    }
    return out;
  }
  // Back to the pool; the caller has set every record the pass used to zero.
  void give(std::vector<SetShard>& shards) {
    const std::lock_guard<std::mutex> lock(mutex);
    for (SetShard& a : shards) {
      a.absorbed = {};
      a.escaped = {};
      a.lines = a.hits = 0;
      free.push_back(std::move(a));
    }
    shards.clear();
  }

  void release() {
    const std::lock_guard<std::mutex> lock(mutex);
    std::vector<SetShard>().swap(free);
  }

  std::mutex mutex;
  std::vector<SetShard> free;
};

void release_pass_memory(const LineSets& sets) {
  if (sets.pool) sets.pool->release();
}

namespace {

// Power `kept` at `face` for channel c, held for sending on: the share of
// it the box's own classes carry goes along the face's next crossing in
// this pass, the rest waits for the boxes above.
inline void hold(const FaceIn& f, FaceAcc& fa, std::vector<FaceLater>& later, int face, int c, double kept) {
  if (const double share = f.carried_share(); share < 1) {
    const double now = kept * share;
    fa.gathered[c] += now;
    later[face].later[c] += kept - now;
  } else {
    fa.gathered[c] += kept;
  }
}

struct PassContext {
  const StoreBox* box;
  const LineSetBox* lines;
  const LineSets* sets;
  std::vector<EntryInput> entries;
  std::vector<FaceIn> faces;
  bool root;
  bool capped;  // a part of the lines: no shard sends more than its part of an entry's expected share
  std::vector<double> expected;  // where capped, per entry: its expected share over the pass's lines
};

// Brings into the caches what transport_set_line will touch for a line
// `distance` lines ahead, in stages that each read what an earlier one
// brought: the faces' records and the patches' (4 lines ahead; the faces
// come with the events, event_sides), their first entries' records (2).
// (Measured on OFFICE before the faces came with the events, when a line's
// patches were brought 4 lines ahead, their faces 2 and the entries 1:
// 3/2/1 and 6/3/1 were no faster.)
void prefetch_set_line(const PassContext& in, const SetShard& shard, const Event* ev, int n, size_t distance) {
  switch (distance) {
    case 4:
      for (int i = 0; i < n; ++i) {
        prefetch(&in.box->local_faces[ev[i].id]);  // its contact plane (touching)
        for (const int face : {towards(ev[i], +1), towards(ev[i], -1)})
          if (face >= 0) {
            prefetch(&in.faces[face]);
            const char* acc = reinterpret_cast<const char*>(&shard.faces[face]);
            prefetch(acc);
            prefetch(acc + sizeof(FaceAcc) - 1);
          }
      }
      break;
    case 2:
      for (int i = 0; i < n; ++i)
        for (const int face : {towards(ev[i], +1), towards(ev[i], -1)})
          if (face >= 0) {
            const FaceIn& f = in.faces[face];
            prefetch(&in.entries[f.entry]);
            prefetch(&shard.entries[f.entry]);
            if (in.capped) prefetch(&in.expected[f.entry]);
          }
      break;
    default:
      break;
  }
}

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
  const auto face_at = [&](int j, int d) { return towards(ev[j], d); };
  for (int i = 0; i < n; ++i)
    for (const int dir : {+1, -1}) {
      const int face = towards(ev[i], dir);
      if (face < 0) continue;
      const FaceIn& from = in.faces[face];
      const int j = next_seen(i, dir, n, face_at);
      // A face of the box's own (one class here) needs no look-up of its partner's box.
      const int k = from.single() ? (in.root || (j >= 0 && j < n) ? 0 : -1)
                                      : pair_class(sets, lines, in.root, ev, n, i, j);
      if (k < 0) continue;
      const uint32_t e = from.entry + static_cast<uint32_t>(k);
      const EntryInput& input = in.entries[e];
      EntryAcc& acc = shard.entries[e];
      FaceAcc& fa = shard.faces[face];
      double share = input.share;
      if (in.capped) share = std::max(0.0, std::min(share, in.expected[e] * shard.allowance - acc.used));
      acc.used += share;
      if (j >= 0 && j < n && touching(box, ev[i], ev[j])) {
        // Pressed against the next surface: the share stays with the face,
        // as what it gathers does (docs/scene-formats.md, "Surfaces in contact").
        for (int c = 0; c < ch; ++c) hold(from, fa, shard.later, face, c, input.quota[c] * share);
        continue;
      }
      SetShard::Send s{j, dir, {0, 0, 0}};
      bool any = false;
      for (int c = 0; c < ch; ++c) {
        s.power[c] = input.quota[c] * share + fa.gathered[c];
        fa.gathered[c] = 0;
        any |= s.power[c] != 0;
      }
      if (any) sends.push_back(s);
    }
  for (const SetShard::Send& s : sends) {
    const int j = s.to;
    if (j < 0 || j >= n) {  // off the line: only the root sends there, out of the scene
      for (int c = 0; c < ch; ++c) shard.escaped[c] += s.power[c];
      continue;
    }
    const int face = towards(ev[j], -s.dir);  // turned towards the power
    if (face < 0) {
      for (int c = 0; c < ch; ++c) shard.absorbed[c] += s.power[c];
      continue;
    }
    // rho of it stays, shared by the face's classes: those this box carries
    // go on together along the face's next crossing in this pass (any of
    // them: the box's lines sample the face's partners in the box as its
    // form factor does), the rest waits for the boxes above.
    const FaceIn& f = in.faces[face];
    FaceAcc& fa = shard.faces[face];
    for (int c = 0; c < ch; ++c) {
      const double kept = f.rho[c] * s.power[c];
      fa.phi_gain[c] += kept;
      shard.absorbed[c] += s.power[c] - kept;
      hold(f, fa, shard.later, face, c, kept);
    }
  }
}

struct SetResult {
  std::array<double, 3> absorbed{}, escaped{};
  BoxPassStats stats;
};

// Adds `amount` to the pools of a face's classes [from, to) (to = -1: up to
// the root's), in proportion to their shares (the last takes what rounding
// leaves, and all of it when none has a share).
void pool_classes(const LineSets& sets, size_t face, uint32_t from, int to, int ch, int c, double amount,
                  std::vector<double>& pooled) {
  const uint32_t slot0 = sets.face_slot[face];
  const uint32_t end = to < 0 ? sets.face_slot[face + 1] : slot0 + static_cast<uint32_t>(to);
  double total = 0;
  uint32_t last = end;
  for (uint32_t s = slot0 + from; s < end; ++s)
    if (sets.alpha[s] > 0) {
      total += sets.alpha[s];
      last = s;
    }
  if (last == end) last = end - 1;
  double given = 0;
  for (uint32_t s = slot0 + from; s < end; ++s) {
    if (s != last && !(sets.alpha[s] > 0)) continue;
    const double part = s == last ? amount - given : amount * sets.alpha[s] / total;
    pooled[size_t{s} * ch + c] += part;
    given += part;
  }
}

SetResult set_pass(const BoxStore& store, const LineSets& sets, int x, RadiosityState& state, Flight& flight,
                   SetShardPool& pool, int shards_wanted, unsigned pass, Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const StoreBox& box = store.box(x);
  const LineSetBox& lines = sets.boxes[x];
  const int ch = state.channels;
  const uint32_t entries = lines.entry.back();
  // This box's own class at every face it sees (the face's last entry) takes off now.
  for_each_record(lines.entry.size() - 1, [&](size_t f) {
    const uint32_t slot = lines.slot[lines.entry[f + 1] - 1];
    for (int c = 0; c < ch; ++c) {
      flight.quota[size_t{slot} * ch + c] = state.pooled[size_t{slot} * ch + c];
      state.pooled[size_t{slot} * ch + c] = 0;
    }
    flight.used[slot] = 0;
  });
  const std::vector<ChunkPart>& parts = flight.parts[x];
  SetResult result;
  if (parts.empty()) return result;  // the boxes above carry this box's classes in this pass
  const bool every_line = flight.fraction[x] >= 1.0;
  PassContext in{&box, &lines, &sets, {}, {}, x == 0, !every_line, {}};
  const size_t faces = box.face_global.size();
  in.entries.resize(entries);
  for_each_record(entries, [&](size_t e) {
    EntryInput& input = in.entries[e];
    const uint32_t slot = lines.slot[e];
    for (int c = 0; c < ch; ++c) input.quota[c] = flight.quota[size_t{slot} * ch + c];
    input.share = flight.share[slot];
  });
  // A part of the lines: each shard may send at most its part (its
  // allowance) of an entry's expected share.
  if (in.capped) {
    in.expected.resize(entries);
    for_each_record(entries, [&](size_t e) {
      in.expected[e] = flight.fraction[x] * lines.carried[e] * flight.share[lines.slot[e]];
    });
  }
  in.faces.resize(faces);
  std::atomic<bool> waits = false;  // some face keeps a part of what it receives for the classes of boxes above
  for_each_record(faces, [&](size_t f) {
    const size_t g = static_cast<size_t>(box.face_global[f]);
    FaceIn& face = in.faces[f];
    for (int c = 0; c < ch; ++c) face.rho[c] = state.rho[state.at(g, c)];
    const uint32_t carried = lines.entry[f + 1] - lines.entry[f];
    face.entry = lines.entry[f];
    double share = 1;
    if (carried < sets.face_slot[g + 1] - sets.face_slot[g]) {
      share = 0;
      for (uint32_t k = 0; k < carried; ++k) share += sets.alpha[sets.face_slot[g] + k];
    }
    face.signed_share = static_cast<float>(carried == 1 ? -share : share);
    if (face.carried_share() < 1) waits.store(true, std::memory_order_relaxed);
  });
  const uint64_t chunks = parts.size();
  const uint64_t pass_lines = part_lines(parts, 0, chunks);
  const int shards = pass_shards(shards_wanted, chunks);
  const size_t later_faces = waits ? faces : 0;
  const linestore::EventSides sides = event_sides(box);
  const auto run_shard = [&](int s, SetShard& a) {
    const uint64_t lo = chunks * s / shards, hi = chunks * (s + 1) / shards;
    if (in.capped) a.allowance = pass_lines ? double(part_lines(parts, lo, hi)) / double(pass_lines) : 0.0;
    stream_pass_lines(
        store, x, parts, lo, hi, pass, progress, &sides,
        [&](const linestore::DecodedChunk& chunk, uint64_t c) { check_chunk_faces(chunk, x, c); },
        [&](const linestore::DecodedChunk& chunk, uint32_t l) {
          const Event* ev = chunk.events.data() + chunk.first[l];
          const int m = static_cast<int>(chunk.first[l + 1] - chunk.first[l]);
          (ch == 1 ? transport_set_line<1> : transport_set_line<3>)(in, ev, m, a);
        },
        [&](const linestore::DecodedChunk& chunk, uint32_t l, size_t distance) {
          prefetch_set_line(in, a, chunk.events.data() + chunk.first[l],
                            static_cast<int>(chunk.first[l + 1] - chunk.first[l]), distance);
        });
  };
  // The shards are merged in shard order: the quota each sent, the power it
  // left on the faces, and into `total` what the faces gathered and did not
  // send and what waits for the boxes above. Shard by shard, each face's sums
  // are the same additions in the same order on any number of threads; what
  // is read is set to zero again for the shard's next pass.
  std::vector<SetShard> total = pool.take(1, 0, faces, later_faces);
  SetShard& sum = total[0];
  const auto merge_face = [&](SetShard& a, size_t f) {
    const size_t g = static_cast<size_t>(box.face_global[f]);
    for (uint32_t e = lines.entry[f]; e < lines.entry[f + 1]; ++e) {
      flight.used[lines.slot[e]] += a.entries[e].used;
      a.entries[e] = EntryAcc{};
    }
    for (int c = 0; c < ch; ++c) {
      state.phi[state.at(g, c)] += a.faces[f].phi_gain[c];
      sum.faces[f].gathered[c] += a.faces[f].gathered[c];
      if (waits) sum.later[f].later[c] += a.later[f].later[c];
    }
    a.faces[f] = FaceAcc{};
    if (waits) a.later[f] = FaceLater{};
  };
  const auto merge_totals = [&](const SetShard& a) {
    for (int c = 0; c < ch; ++c) {
      result.absorbed[c] += a.absorbed[c];
      result.escaped[c] += a.escaped[c];
    }
    result.stats.lines += a.lines;
    result.stats.hits += a.hits;
  };
  if (Ranks::size() > 1) {
    // Every shard's accumulators are summed over the ranks before any is
    // merged (ranks.h): all of them at once, merged face by face in parallel.
    std::vector<SetShard> acc = pool.take(shards, entries, faces, later_faces);
    run_shards(acc, [](int) {}, [&](int s) { run_shard(s, acc[s]); });
    for_each_record(faces, [&](size_t f) {
      for (SetShard& a : acc) merge_face(a, f);
    });
    for (const SetShard& a : acc) merge_totals(a);
    pool.give(acc);
  } else {
    // One rank: the threads take shards in order, and whoever finishes the
    // next shard to merge merges it (and any after it that are done) while
    // the others go on, so that only about as many shards' accumulators as
    // threads are alive at once, not every shard's (8 on any machine; on a
    // root box of a million faces, 8 x 80 MB), and the merge overlaps the
    // transport.
    std::mutex mutex;
    std::vector<SetShard> finished(static_cast<size_t>(shards));
    std::vector<char> ready(static_cast<size_t>(shards), 0);
    int next_merge = 0;
    bool merging = false;
    std::atomic<int> next_shard = 0;
    const int workers = std::min(shards, tbb::this_task_arena::max_concurrency());
    for_each_shard(workers, [&](int) {
      for (int s; (s = next_shard.fetch_add(1)) < shards;) {
        std::vector<SetShard> mine = pool.take(1, entries, faces, later_faces);
        run_shard(s, mine[0]);
        {
          const std::lock_guard<std::mutex> lock(mutex);
          finished[static_cast<size_t>(s)] = std::move(mine[0]);
          ready[static_cast<size_t>(s)] = 1;
          if (merging) continue;
          merging = true;
        }
        for (;;) {
          SetShard* a = nullptr;
          {
            const std::lock_guard<std::mutex> lock(mutex);
            if (next_merge < shards && ready[static_cast<size_t>(next_merge)]) {
              a = &finished[static_cast<size_t>(next_merge)];
            } else {
              merging = false;
              break;
            }
          }
          for (size_t f = 0; f < faces; ++f) merge_face(*a, f);
          merge_totals(*a);
          std::vector<SetShard> done(1);
          done[0] = std::move(*a);
          pool.give(done);
          const std::lock_guard<std::mutex> lock(mutex);
          ++next_merge;
        }
      }
    });
  }
  // What the faces gathered and did not send goes to the pools of the
  // classes this box carries, what waits for the boxes above to theirs.
  // Faces write only their own slots: in parallel.
  for_each_record(faces, [&](size_t f) {
    const size_t g = static_cast<size_t>(box.face_global[f]);
    const uint32_t carried = lines.entry[f + 1] - lines.entry[f];
    for (int c = 0; c < ch; ++c) {
      const double gathered = sum.faces[f].gathered[c], later = waits ? sum.later[f].later[c] : 0.0;
      if (gathered != 0) pool_classes(sets, g, 0, static_cast<int>(carried), ch, c, gathered, state.pooled);
      if (later != 0) pool_classes(sets, g, carried, -1, ch, c, later, state.pooled);
    }
    sum.faces[f] = FaceAcc{};
    if (waits) sum.later[f] = FaceLater{};
  });
  pool.give(total);
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

// New unshot power (the first shot's, local lines') goes to the pools of its
// face's classes in proportion to their shares; uncarried faces keep theirs.
void assign_unshot(const LineSets& sets, RadiosityState& state) {
  const int ch = state.channels;
  std::vector<bool> uncarried(state.faces, false);
  for (int f : sets.uncarried) uncarried[f] = true;
  for_each_record(state.faces, [&](size_t f) {
    if (uncarried[f]) return;
    for (int c = 0; c < ch; ++c) {
      double& u = state.unshot[state.at(f, c)];
      if (u == 0) continue;
      pool_classes(sets, f, 0, -1, ch, c, u, state.pooled);
      u = 0;
    }
  });
}

// Of a Poisson count X of mean mu, E[min(X, mu)] / mu: what a shard of a
// partial pass expects to send of an entry's quota (each crossing sends
// 1 / mu of its part, and the shard stops at its part), where mu is the
// entry's expected crossings in the shard's lines. 1 - e^-mu below one
// crossing, 0.73 at two, 0.90 at sixteen. Tabulated on a geometric grid
// and interpolated; above the table, the normal tail 1 - 1 / sqrt(2 pi mu).
double capped_share(double mu) {
  constexpr double kLow = 1e-3, kStep = 1.05;
  constexpr int kPoints = 240;  // up to about 1.2e2
  static const std::vector<double> table = [] {
    std::vector<double> t(kPoints);
    for (int i = 0; i < kPoints; ++i) {
      const double m = kLow * std::pow(kStep, i);
      double p = std::exp(-m), cdf = 0, below = 0;
      for (int k = 0; k <= static_cast<int>(m); ++k) {
        cdf += p;
        below += k * p;
        p *= m / (k + 1);
      }
      t[static_cast<size_t>(i)] = (below + m * std::max(0.0, 1 - cdf)) / m;
    }
    return t;
  }();
  if (!(mu > kLow)) return mu > 0 ? 1 - std::exp(-mu) : 0.0;
  const double x = std::log(mu / kLow) / std::log(kStep);
  if (x >= kPoints - 1) return 1 - 1 / std::sqrt(2 * M_PI * mu);
  const int i = static_cast<int>(x);
  const double t = x - i;
  return table[static_cast<size_t>(i)] * (1 - t) + table[static_cast<size_t>(i) + 1] * t;
}

// Of the power pooled in the slots some box's lines carry (`carriable`),
// the share a pass with these fractions of the boxes' lines is expected to
// send: capped_share at each box's entries, one for a box that takes every
// line, none for a slot no box taking lines carries.
double expected_sent(const LineSets& sets, const std::vector<double>& slot_power, const std::vector<char>& carriable,
                     const std::vector<double>& fraction, const std::vector<int>& shards) {
  // Kept from call to call (the plan weighs several passes an iteration, on
  // one thread): allocating them was a fresh, zeroed page a slot.
  thread_local std::vector<double> taken, sent, sent_at;
  taken.assign(sets.slots(), 0.0);
  sent.assign(sets.slots(), 0.0);
  for (size_t x = 0; x < sets.boxes.size(); ++x) {
    if (!(fraction[x] > 0)) continue;
    const LineSetBox& lines = sets.boxes[x];
    const bool all = fraction[x] >= 1.0;
    // What an entry with each distinct count sends, once per count (a log
    // and two divisions an entry were most of the plan's time); the sums
    // get the same terms in the same order as entry by entry.
    sent_at.resize(lines.distinct.size());
    if (!all)
      for (size_t k = 0; k < lines.distinct.size(); ++k) {
        const double m = fraction[x] * lines.distinct[k];
        sent_at[k] = m * capped_share(m / shards[x]);
      }
    for (size_t e = 0; e < lines.slot.size(); ++e) {
      const double m = fraction[x] * lines.carried[e];
      taken[lines.slot[e]] += m;
      sent[lines.slot[e]] += all ? m : sent_at[lines.rank[e]];
    }
  }
  double power = 0, expected = 0;
  for (size_t s = 0; s < sets.slots(); ++s)
    if (carriable[s]) {
      power += slot_power[s];
      if (taken[s] > 0) expected += slot_power[s] * sent[s] / taken[s];
    }
  return power > 0 ? expected / power : 1.0;
}

}  // namespace

// Which lines each box takes this iteration, and what one carrying crossing
// of a class sends: 1 / (the carriers' crossings this iteration takes).
void plan_iteration(const BoxStore& store, const LineSets& sets, const RadiosityState& state, double power_per_line,
                    unsigned pass, int shards_wanted, Flight& flight) {
  const size_t boxes = store.box_count();
  flight.fraction.assign(boxes, 1.0);
  flight.parts.assign(boxes, {});
  const int ch = state.channels;
  std::vector<double> slot_power(sets.slots(), 0.0);
  double power = 0;
  for (size_t s = 0; s < sets.slots(); ++s)
    for (int c = 0; c < ch; ++c) slot_power[s] += state.pooled[s * ch + c];
  for (double p : slot_power) power += p;
  // The root's lines carry every class too, so a subscene needs no floor of
  // its own: the root takes at least its coverage, and a subscene whose share
  // falls below that takes no line (the root's lines carry its classes).
  const double coverage = store.box(0).coverage;
  const auto plan = [&](double wanted) {
    for (size_t x = 0; x < boxes; ++x) {
      const StoreBox& box = store.box(static_cast<int>(x));
      flight.fraction[x] = 1.0;
      flight.parts[x].clear();
      if (power_per_line > 0 && box.lines > 0)
        flight.fraction[x] = x == 0 ? std::max(wanted, coverage) : (wanted < coverage ? 0.0 : wanted);
      if (flight.fraction[x] > 0) flight.parts[x] = pass_parts(store, static_cast<int>(x), flight.fraction[x], pass);
      if (flight.fraction[x] < 1.0 && box.lines > 0) {
        uint64_t lines = 0;
        for (const ChunkPart& p : flight.parts[x]) lines += p.lines;
        flight.fraction[x] = static_cast<double>(lines) / static_cast<double>(box.lines);
      }
    }
  };
  double wanted = power_per_line > 0 ? std::min(1.0, power / (power_per_line * static_cast<double>(store.lines()))) : 1.0;
  plan(wanted);
  // A partial pass sends an entry's power only up to each shard's part, so
  // the entries few of its lines cross keep most of theirs for later passes
  // (1 - e^-mu of it a pass at mu expected crossings a shard), while a pass
  // of every line sends all: on a finely meshed office (667k faces, 2M
  // lines) such passes sent a few per cent of the power left each and the
  // solve stalled. A subscene below the root's coverage takes no line, and
  // the classes only its lines carry wait (on ROOM meshed to 63k faces with
  // 300k lines, 0.35 % of the emitted power waited there for good). Of the
  // passes that take `wanted` of the lines, twice that, four times, ... and
  // all of them, the one expected to send the most power per line taken
  // (the fewest lines among equals).
  std::vector<char> carriable(sets.slots(), 0);
  for (const LineSetBox& lines : sets.boxes)
    for (size_t e = 0; e < lines.slot.size(); ++e) carriable[lines.slot[e]] |= lines.carried[e] > 0;
  const auto cost = [&] {  // lines taken per power sent, both as shares
    std::vector<int> shards(boxes, 1);
    uint64_t taken = 0;
    for (size_t x = 0; x < boxes; ++x) {
      shards[x] = pass_shards(shards_wanted, flight.parts[x].size());
      for (const ChunkPart& p : flight.parts[x]) taken += p.lines;
    }
    const double sent = expected_sent(sets, slot_power, carriable, flight.fraction, shards);
    return sent > 0 ? static_cast<double>(taken) / static_cast<double>(store.lines()) / sent : INFINITY;
  };
  if (wanted < 1.0) {
    double best = wanted, best_cost = cost();
    for (double w = wanted; w < 1.0;) {
      w = w > 0 ? std::min(1.0, 2 * w) : 1.0;
      plan(w);
      if (const double c = cost(); c < best_cost) {
        best = w;
        best_cost = c;
      }
    }
    if (best < 1.0) plan(best);
  }
  std::vector<double> taken(sets.slots(), 0.0);
  for (size_t x = 0; x < boxes; ++x) {
    const LineSetBox& lines = sets.boxes[x];
    for (size_t e = 0; e < lines.slot.size(); ++e) taken[lines.slot[e]] += flight.fraction[x] * lines.carried[e];
  }
  flight.share.assign(sets.slots(), 0.0);
  for (size_t s = 0; s < sets.slots(); ++s) flight.share[s] = taken[s] > 0 ? 1.0 / taken[s] : 0.0;
}

PassStats line_set_iteration(const PatchMesh& mesh, const TracerOnDemand& tracer, const BoxStore& store,
                             const LineSets& sets, RadiosityState& state, unsigned pass, int shards_wanted,
                             double power_per_line, unsigned long long seed, std::vector<BoxPassStats>* per_box,
                             uint64_t* uncarried_lines) {
  const auto start = std::chrono::steady_clock::now();
  const Hierarchy& h = store.hierarchy();
  const int ch = state.channels;
  assign_unshot(sets, state);
  SetShardPool own;  // for line sets made without one: kept for this iteration alone
  SetShardPool& pool = sets.pool ? *sets.pool : own;
  Flight flight;
  flight.quota.assign(sets.slots() * ch, 0.0);
  flight.used.assign(sets.slots(), 0.0);
  // Lines in the order of stored-line Multipath's pass (its rotation 2 pass):
  // with no line in the subscenes, the two transports are the same sums.
  const unsigned rotation = 2 * pass;
  plan_iteration(store, sets, state, power_per_line, rotation, shards_wanted, flight);
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
    for_each_box(boxes.size(), [&](size_t k) {
      results[k] = set_pass(store, sets, boxes[k], state, flight, pool, shards_wanted, rotation, progress);
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
  for_each_record(sets.slots(), [&](size_t s) {
    for (int c = 0; c < ch; ++c) state.pooled[s * ch + c] += flight.quota[s * ch + c] * (1.0 - flight.used[s]);
  });
  std::vector<int> waiting;
  for (int f : sets.uncarried)
    for (int c = 0; c < ch; ++c)
      if (state.unshot[state.at(static_cast<size_t>(f), c)] != 0) {
        waiting.push_back(f);
        break;
      }
  const uint64_t shot = shoot_unshot(mesh, tracer, std::move(waiting), state, pass, seed, shards_wanted);
  if (uncarried_lines) *uncarried_lines += shot;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.unshot_fraction = state.remaining_fraction();
  return stats;
}

}  // namespace mpath
