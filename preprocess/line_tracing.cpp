#include "line_tracing.h"

#include <algorithm>
#include <utility>

#include "line_order.h"
#include "prefetch.h"

namespace mpath {

namespace {
constexpr unsigned kStoreLineStream = 5;
}  // namespace

// A stable least-significant-digit radix sort of 16-bit digits; a digit
// that every key shares is skipped. (A chunk's std::sort of (key, index)
// pairs was 6 % of a preprocess.)
void order_by_key(const std::vector<uint64_t>& key, std::vector<uint32_t>& order) {
  const size_t n = key.size();
  order.resize(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(i);
  if (n < 2) return;
  thread_local std::vector<uint32_t> moved, start;
  moved.resize(n);
  start.resize(1 << 16);
  for (int shift = 0; shift < 64; shift += 16) {
    const auto digit = [shift](uint64_t k) { return static_cast<uint32_t>((k >> shift) & 0xffff); };
    std::fill(start.begin(), start.end(), 0u);
    for (size_t i = 0; i < n; ++i) ++start[digit(key[i])];
    if (start[digit(key[0])] == n) continue;
    uint32_t sum = 0;
    for (uint32_t& c : start) sum += std::exchange(c, sum);
    for (size_t i = 0; i < n; ++i) moved[start[digit(key[order[i]])]++] = order[i];
    order.swap(moved);
  }
}

void BoxTally::merge_into(BoxTally& total) const {
  total.counts.add_counts(counts);
  for (const auto& [key, n] : first_met) total.first_met[key] += n;
}

ChunkTracer::ChunkTracer(const Options& options, const PatchMesh& mesh, const Hierarchy& hierarchy, int box,
                         uint64_t lines)
    : mesh_(mesh),
      hierarchy_(hierarchy),
      box_(hierarchy.boxes[box]),
      box_index_(box),
      tracer_(mesh, hierarchy.boxes[box].patches),
      sampler_(line_box(hierarchy.boxes[box].bounds)),
      sequence_(options.lines.sequence, options.lines.seed, static_cast<unsigned>(box)),
      seed_(options.lines.seed),
      total_(lines),
      chunk_lines_(static_cast<uint64_t>(options.store.chunk_lines)),
      chunks_((total_ + chunk_lines_ - 1) / chunk_lines_),
      order_([&] {
        Rng keys = make_rng(seed_, kStoreLineStream, (static_cast<unsigned long long>(box) << 40) | (1ull << 39));
        return IndexPermutation(total_, keys);
      }()) {
  uint32_t offset = 0;
  for (int c : box_.children) {
    child_offset_.push_back(offset);
    offset += hierarchy.boxes[c].ar_count();
  }
  child_offset_.push_back(offset);
  class_span_ = hierarchy.class_span(box);
  if (class_span_ > 0) {
    for (int p : box_.patches) {
      const auto& faces = mesh.patch_faces[static_cast<size_t>(p)];
      owner_.push_back({hierarchy.patch_box[static_cast<size_t>(p)],
                        static_cast<uint8_t>((faces[0] == kInvisibleSide ? 1 : 0) | (faces[1] == kInvisibleSide ? 2 : 0))});
    }
    tree_ = BoxTree(hierarchy);
  }
}

linestore::DecodedChunk TracedChunk::stored() const {
  linestore::DecodedChunk out;
  linestore::gather_lines(lines, order.data(), order.size(), out);
  return out;
}

uint64_t ChunkTracer::lines_in(uint64_t chunk) const { return std::min(chunk_lines_, total_ - first_line(chunk)); }

BoxTally ChunkTracer::empty_tally() const {
  BoxTally t;
  t.counts.resize(box_.patches.size(), box_.ar_count(), child_offset_.back(), static_cast<size_t>(class_span_));
  return t;
}

void ChunkTracer::count_classes(const linestore::Event* events, int n, linestore::BoxCounts& counts) const {
  // The pair of crossing i and the next it sees towards dir (next_seen) belongs to the smallest box holding
  // both patches (off the line: the outside, the root's); a subscene's line
  // leaving it carries no pair. Counted on the side of patch i that faces
  // crossing i + dir, as the solver's face_towards picks it.
  // A line's crossings: the box holding each patch and whether the side
  // towards either end is an invisible back, read once from owner_.
  thread_local std::vector<Owner> on_line;
  on_line.resize(static_cast<size_t>(n));
  bool invisible = false;
  // Whether some crossing is of a patch the root does not hold directly
  // (in the root's lines only those are counted here).
  const bool root = box_index_ == 0;
  bool counted = !root;
  for (int i = 0; i < n; ++i) {
    Owner o = owner_[events[i].id];
    // Bit 0: the side facing +1 (along the line) is invisible; bit 1: the side facing -1.
    if (!events[i].along) o.invisible = static_cast<uint8_t>(((o.invisible & 1) << 1) | (o.invisible >> 1));
    invisible |= o.invisible != 0;
    counted |= o.box != 0;
    on_line[static_cast<size_t>(i)] = o;
  }
  if (!counted) return;
  const auto seen_towards = [&](int x, int d) {
    return (on_line[static_cast<size_t>(x)].invisible >> (d > 0 ? 0 : 1)) & 1 ? kInvisibleSide : 0;
  };
  // The counters a line adds to are first found and brought into the caches,
  // then added to: added to as found, each waited for the one before
  // (the counters of a box's patches are megabytes, met at random).
  thread_local std::vector<uint32_t*> counters;
  counters.clear();
  for (int i = 0; i < n; ++i) {
    if (root && on_line[static_cast<size_t>(i)].box == 0) continue;  // finish_tally's
    for (const int dir : {+1, -1}) {
      // Without invisible backs on the line the next crossing seen is the next one.
      const int j = invisible ? next_seen(i, dir, n, seen_towards) : i + dir;
      const int k = tree_.pair_class(on_line[static_cast<size_t>(i)].box,
                                     j < 0 || j >= n ? -1 : on_line[static_cast<size_t>(j)].box, box_index_ == 0);
      if (k < 0) continue;
      const int side = (dir > 0) == events[i].along ? 0 : 1;
      uint32_t* c = &counts.class_crossings[linestore::class_slot(events[i].id, static_cast<size_t>(side),
                                                                   static_cast<size_t>(class_span_), static_cast<size_t>(k))];
      prefetch(c);
      counters.push_back(c);
    }
  }
  for (uint32_t* c : counters) ++*c;
}

void ChunkTracer::finish_tally(BoxTally& tally) const {
  if (class_span_ == 0 || box_index_ != 0) return;
  linestore::BoxCounts& counts = tally.counts;
  for (size_t k = 0; k < owner_.size(); ++k)
    if (owner_[k].box == 0)
      for (size_t side = 0; side < 2; ++side)
        counts.class_crossings[linestore::class_slot(k, side, static_cast<size_t>(class_span_), 0)] +=
            counts.patch_crossings[k];
}

void ChunkTracer::trace(uint64_t chunk, TracedChunk& out, BoxTally& tally) const {
  using linestore::Event;
  Rng rng = make_rng(seed_, kStoreLineStream, (static_cast<unsigned long long>(box_index_) << 40) + chunk);
  const uint64_t first = first_line(chunk), n = lines_in(chunk);
  // A subscene's lines end at its walls, where they cross its ARs, unless the
  // boxes are transparent (hierarchy.transport = "lines"): then a line of any
  // box records the patches inside it and nothing else.
  const bool walls = box_index_ != 0 && !hierarchy_.transparent;
  const size_t child_count = hierarchy_.transparent ? 0 : box_.children.size();
  // The lines are traced into one flat set of records (line i's events are
  // events[first[i] .. first[i + 1])), kept from chunk to chunk by the
  // caller: no allocation per line, and the memory is one chunk's whatever
  // lines.total is. Room for 16 events a line is reserved (untouched pages
  // cost no memory), so that growing does not hold the old and new lists.
  linestore::DecodedChunk& traced = out.lines;
  traced.clear();
  traced.first.reserve(n + 1);
  traced.entry_ar.reserve(n);
  traced.exit_ar.reserve(n);
  traced.events.reserve(16 * n);
  thread_local std::vector<LineHit> hits;
  struct ChildCrossing {
    double t_in, t_out;
    Event event;
  };
  std::vector<ChildCrossing> children;
  linestore::BoxCounts& counts = tally.counts;
  // (AR, patch met first) of every line end, tallied once per chunk: runs of
  // equal keys make one map update each.
  thread_local std::vector<uint64_t> met;
  met.clear();
  std::vector<Event>& events = traced.events;
  // Per crossing this reads the box's crossing counts and, with line sets,
  // its patches' owners, at the patch's place: fetched as Embree meets it.
  HitPrefetch per_crossing;
  per_crossing.add(counts.patch_crossings);
  if (class_span_ > 0) per_crossing.add(owner_);
  for (uint64_t i = 0; i < n; ++i) {
    double u[4];
    sequence_.point(order_(first + i), rng, u);
    const GlobalLine line = sampler_.sample(u);
    const size_t begin = events.size();
    traced.first.push_back(static_cast<uint32_t>(begin));
    uint32_t entry_ar = linestore::kNoAr, exit_ar = linestore::kNoAr;
    BoxCrossing wall{};
    // A subscene's line: its ends are where it crosses the box's walls.
    const bool crosses = !walls || cross_box(box_.bounds, line.org, line.dir, wall);
    if (walls && crosses) {
      entry_ar = box_.ar_at(wall.face_in, line.org + line.dir * wall.t_in, line.dir);
      exit_ar = box_.ar_at(wall.face_out, line.org + line.dir * wall.t_out, line.dir);
    }
    traced.entry_ar.push_back(entry_ar);
    traced.exit_ar.push_back(exit_ar);
    if (!crosses) continue;
    tracer_.all_hits(line.org, line.dir, line.length, hits, &per_crossing);
    order_ties(mesh_, tracer_.tie_epsilon(), hits, tracer_.live_faces());
    children.clear();
    for (size_t k = 0; k < child_count; ++k) {
      const SceneBox& child = hierarchy_.boxes[box_.children[k]];
      BoxCrossing c;
      if (!cross_box(child.bounds, line.org, line.dir, c)) continue;
      Event e;
      e.kind = Event::child_box;
      e.id = static_cast<uint32_t>(k);
      e.entry_ar = child.ar_at(c.face_in, line.org + line.dir * c.t_in, line.dir);
      e.exit_ar = child.ar_at(c.face_out, line.org + line.dir * c.t_out, line.dir);
      children.push_back({c.t_in, c.t_out, e});
      counts.child_crossings[child_offset_[k] + e.entry_ar]++;
      counts.child_crossings[child_offset_[k] + e.exit_ar]++;
    }
    std::sort(children.begin(), children.end(), [](const auto& a, const auto& b) { return a.t_in < b.t_in; });
    // No patch of this box is inside a child box (the hierarchy is built so),
    // so a patch is before a child crossing or after it; one lying on the
    // child's wall is outside the child.
    size_t next_child = 0;
    for (const LineHit& h : hits) {
      while (next_child < children.size() && h.t > 0.5 * (children[next_child].t_in + children[next_child].t_out))
        events.push_back(children[next_child++].event);
      const uint32_t local = static_cast<uint32_t>(h.traced);  // the tracer holds the box's patches alone
      events.push_back({Event::patch, local, h.along});
      counts.patch_crossings[local]++;
    }
    while (next_child < children.size()) events.push_back(children[next_child++].event);
    const Event* ev = events.data() + begin;
    const int m = static_cast<int>(events.size() - begin);
    if (class_span_ > 0) count_classes(ev, m, counts);
    if (walls) {
      counts.wall_lines[entry_ar]++;
      counts.wall_lines[exit_ar]++;
      if (m == 0) {
        counts.wall_open[entry_ar]++;
        counts.wall_open[exit_ar]++;
      } else {
        // Associated patches: what a line entering at either end meets first.
        // (Invisible backs let it through to the next.)
        const auto seen = [&](int x, int d) { return towards(ev[x], d); };
        const int a = next_seen(-1, +1, m, seen), b = next_seen(m, -1, m, seen);
        if (a < m && ev[a].kind == Event::patch) met.push_back(linestore::associated_key(entry_ar, ev[a].id));
        if (b >= 0 && ev[b].kind == Event::patch) met.push_back(linestore::associated_key(exit_ar, ev[b].id));
      }
    }
  }
  traced.first.push_back(static_cast<uint32_t>(events.size()));
  std::sort(met.begin(), met.end());
  for (size_t i = 0; i < met.size();) {
    size_t j = i;
    while (j < met.size() && met[j] == met[i]) ++j;
    tally.first_met[met[i]] += static_cast<uint32_t>(j - i);
    i = j;
  }
  // Lines in order of their first and last crossings: neighbouring records
  // start alike, which the delta coding and zstd turn into fewer bytes. Any
  // order of lines is a valid Multipath pass; this one is fixed by the content.
  thread_local std::vector<uint64_t> keys;  // (first + 1) << 32 | last
  keys.resize(n);
  for (uint64_t i = 0; i < n; ++i) {
    const uint32_t a = traced.first[i], b = traced.first[i + 1];
    keys[i] = a == b ? 0 : ((uint64_t{events[a].id} + 1) << 32) | events[b - 1].id;
  }
  order_by_key(keys, out.order);  // ties by line index: a stable order
}

}  // namespace mpath
