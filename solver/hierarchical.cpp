#include "hierarchical.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <numeric>

#include "error.h"
#include "progress.h"

namespace mpath {

using linestore::Event;
using linestore::kNoAr;

void add_ar_state(const BoxStore& store, RadiosityState& state) {
  state.ar_in.assign(store.ar_total() * state.channels, 0.0);
  state.ar_out.assign(store.ar_total() * state.channels, 0.0);
}

namespace {

// What one box's pass reads and never writes.
struct BoxInputs {
  const StoreBox* box = nullptr;
  int channels = 3;
  std::vector<FaceInput> faces;       // local faces
  std::vector<double> wall_send;      // per wall AR and channel: power per line sent inwards
  std::vector<double> child_send;     // per child AR and channel: Out power per line sent outwards
  std::vector<const double*> child_t; // per child: transmittances of its ARs
  std::vector<uint32_t> child_base;   // per child: first of its ARs in child_send
  uint32_t patches = 0, children = 0, wall_ars = 0;
  std::vector<uint32_t> child_ars;
};

// A shard's private accumulators for one box's pass.
struct alignas(128) BoxShard {
  ShardAccumulator faces;
  std::vector<double> wall_out;  // power reaching the box's walls: its Out
  std::vector<double> child_in;  // power entering the children: their In
};

// Moves the power held in a box's ARs (from `base` in `held`) into `quota`,
// each AR's into its target's slot; an AR with no target keeps its power.
void move_held(std::vector<double>& held, size_t base, const std::vector<uint32_t>& target, int ch,
               std::vector<double>& quota) {
  for (size_t r = 0; r < target.size(); ++r) {
    if (target[r] == kNoTarget) continue;
    for (int c = 0; c < ch; ++c) {
      double& h = held[(base + r) * ch + c];
      quota[target[r] * ch + c] += h;
      h = 0;
    }
  }
}

BoxInputs start_box(const BoxStore& store, int b, RadiosityState& state) {
  const StoreBox& box = store.box(b);
  const SceneBox& sb = store.hierarchy().boxes[b];
  const int ch = state.channels;
  BoxInputs in;
  in.box = &box;
  in.channels = ch;
  in.patches = static_cast<uint32_t>(box.local_faces.size());
  in.children = static_cast<uint32_t>(sb.children.size());
  in.wall_ars = sb.ar_count();
  // Faces: their unshot power becomes this pass's quota.
  in.faces.resize(box.face_global.size());
  for (size_t f = 0; f < in.faces.size(); ++f) {
    const size_t g = static_cast<size_t>(box.face_global[f]);
    FaceInput& face = in.faces[f];
    for (int c = 0; c < ch; ++c) {
      face.quota[c] = state.unshot[state.at(g, c)];
      face.rho[c] = state.rho[state.at(g, c)];
      state.unshot[state.at(g, c)] = 0;
    }
    face.share = box.face_crossings[f] > 0 ? 1.0 / box.face_crossings[f] : 0.0;
  }
  // Walls: In is sent inwards along the lines that meet something inside.
  in.wall_send.assign(size_t{in.wall_ars} * ch, 0.0);
  if (b > 0) {
    move_held(state.ar_in, box.ar_base, box.in_target, ch, in.wall_send);
    for (uint32_t r = 0; r < in.wall_ars; ++r) {
      const double carriers = double(box.counts.wall_lines[r]) - double(box.counts.wall_open[r]);
      for (int c = 0; c < ch; ++c) in.wall_send[r * ch + c] = carriers > 0 ? in.wall_send[r * ch + c] / carriers : 0.0;
    }
  }
  // Children: Out is sent outwards along this box's lines that cross it.
  uint32_t total = 0;
  for (int child : sb.children) {
    in.child_base.push_back(total);
    in.child_ars.push_back(store.hierarchy().boxes[child].ar_count());
    total += store.hierarchy().boxes[child].ar_count();
  }
  in.child_send.assign(size_t{total} * ch, 0.0);
  for (uint32_t k = 0; k < in.children; ++k) {
    const StoreBox& child = store.box(sb.children[k]);
    std::vector<double> quota(size_t{in.child_ars[k]} * ch, 0.0);
    move_held(state.ar_out, child.ar_base, child.out_target, ch, quota);
    for (uint32_t r = 0; r < in.child_ars[k]; ++r) {
      const double crossings = box.counts.child_crossings[box.child_ar_base[k] + r];
      for (int c = 0; c < ch; ++c)
        in.child_send[(in.child_base[k] + r) * ch + c] = crossings > 0 ? quota[r * ch + c] / crossings : 0.0;
    }
    in.child_t.push_back(child.transmittance.data());
  }
  return in;
}

// A decoded chunk names only patches, children and ARs of its box.
bool chunk_fits(const BoxInputs& in, const linestore::DecodedChunk& chunk) {
  for (size_t l = 0; l < chunk.lines(); ++l) {
    const bool walls = in.wall_ars > 0;
    if (walls != (chunk.entry_ar[l] != kNoAr) && chunk.first[l + 1] > chunk.first[l]) return false;
    if (chunk.entry_ar[l] != kNoAr && chunk.entry_ar[l] >= in.wall_ars) return false;
    if (chunk.exit_ar[l] != kNoAr && chunk.exit_ar[l] >= in.wall_ars) return false;
    if (walls && chunk.first[l + 1] > chunk.first[l] && chunk.exit_ar[l] == kNoAr) return false;
  }
  for (const Event& e : chunk.events) {
    if (e.kind == Event::patch) {
      if (e.id >= in.patches) return false;
    } else if (e.id >= in.children || e.entry_ar >= in.child_ars[e.id] || e.exit_ar >= in.child_ars[e.id]) {
      return false;
    }
  }
  return true;
}

// One line of the box in both directions (design.md section 7): every face,
// wall AR and child box on it sends before anything is received.
void transport_box_line(const BoxInputs& in, const Event* ev, size_t m, uint32_t entry, uint32_t exit, BoxShard& shard) {
  ShardAccumulator& acc = shard.faces;
  const int ch = in.channels;
  ++acc.lines;
  acc.hits += m;
  if (m == 0) return;  // a line meeting nothing carries nothing
  struct Send {
    int from;  // node index; -1 and m are the line's ends
    int dir;   // +1 along the line, -1 against it
    double power[3];
  };
  thread_local std::vector<Send> sends;
  sends.clear();
  auto send_power = [&](int from, int dir, const double* power) {
    Send s{from, dir, {0, 0, 0}};
    bool any = false;
    for (int c = 0; c < ch; ++c) {
      s.power[c] = power[c];
      any |= power[c] != 0;
    }
    if (any) sends.push_back(s);
  };
  auto send_face = [&](int face, int from, int dir) {
    if (face < 0) return;
    const FaceInput& input = in.faces[face];
    FaceAccumulator& a = acc.faces[face];
    double fraction = std::min(input.share, 1.0 - a.quota_used);
    if (fraction < 0) fraction = 0;
    a.quota_used += fraction;
    double power[3];
    for (int c = 0; c < ch; ++c) {
      power[c] = input.quota[c] * fraction + a.gathered[c];
      a.gathered[c] = 0;
    }
    send_power(from, dir, power);
  };
  const int n = static_cast<int>(m);
  if (entry != kNoAr) send_power(-1, +1, &in.wall_send[size_t{entry} * ch]);
  for (int i = 0; i < n; ++i) {
    const Event& e = ev[i];
    if (e.kind == Event::patch) {
      const auto& f = in.box->local_faces[e.id];
      send_face(e.along ? f[0] : f[1], i, +1);
      send_face(e.along ? f[1] : f[0], i, -1);
    } else {
      const uint32_t base = in.child_base[e.id];
      send_power(i, +1, &in.child_send[size_t{base + e.exit_ar} * ch]);
      send_power(i, -1, &in.child_send[size_t{base + e.entry_ar} * ch]);
    }
  }
  if (exit != kNoAr) send_power(n, -1, &in.wall_send[size_t{exit} * ch]);

  for (Send& s : sends) {
    double* p = s.power;
    for (int j = s.from + s.dir;; j += s.dir) {
      if (j < 0 || j >= n) {  // an end of the line: the box's wall, or out of the scene
        const uint32_t ar = j < 0 ? entry : exit;
        if (ar == kNoAr) {
          for (int c = 0; c < ch; ++c) acc.escaped[c] += p[c];
        } else {
          for (int c = 0; c < ch; ++c) shard.wall_out[size_t{ar} * ch + c] += p[c];
        }
        break;
      }
      const Event& e = ev[j];
      if (e.kind == Event::patch) {
        const auto& f = in.box->local_faces[e.id];
        // The face turned towards the power: the back when it travels along the line.
        const int face = (s.dir > 0) == e.along ? f[1] : f[0];
        if (face < 0) {
          for (int c = 0; c < ch; ++c) acc.absorbed[c] += p[c];
          break;
        }
        const FaceInput& input = in.faces[face];
        FaceAccumulator& a = acc.faces[face];
        for (int c = 0; c < ch; ++c) {
          const double kept = input.rho[c] * p[c];
          a.phi_gain[c] += kept;
          a.gathered[c] += kept;
          acc.absorbed[c] += p[c] - kept;
        }
        break;
      }
      // A child box: what it stops enters it, the rest goes on.
      const uint32_t ar = s.dir > 0 ? e.entry_ar : e.exit_ar;
      const double t = in.child_t[e.id][ar];
      double* held = &shard.child_in[size_t{in.child_base[e.id] + ar} * ch];
      for (int c = 0; c < ch; ++c) {
        const double through = p[c] * t;
        held[c] += p[c] - through;
        p[c] = through;
      }
    }
  }
}

}  // namespace

namespace {

struct BoxResult {
  std::array<double, 3> absorbed{}, escaped{};
  BoxPassStats stats;
};

BoxResult box_pass(const BoxStore& store, int b, RadiosityState& state, int threads, Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const BoxInputs in = start_box(store, b, state);
  const StoreBox& box = store.box(b);
  const int ch = state.channels;
  const uint64_t chunks = box.chunks.size();
  const int shards = static_cast<int>(std::max<uint64_t>(1, std::min<uint64_t>(threads, chunks)));
  std::vector<BoxShard> acc(shards);
  tbb::parallel_for(0, shards, [&](int s) {
    BoxShard& a = acc[s];
    a.faces.reset(in.faces.size());
    a.wall_out.assign(size_t{in.wall_ars} * ch, 0.0);
    a.child_in.assign(in.child_send.size(), 0.0);
    BoxStore::Cursor cursor = store.cursor();
    linestore::DecodedChunk chunk;
    for (uint64_t c = chunks * s / shards; c < chunks * (s + 1) / shards; ++c) {
      store.read(b, c, cursor, chunk);
      if (!chunk_fits(in, chunk))
        throw InputError(fmt::format("store: box {} chunk {} names patches, boxes or ARs the box does not have "
                                     "(damaged or foreign store); run mpath-preprocess again", b, c));
      // Stored chunks keep lines sorted by what they meet (it compresses
      // them); taken in that order, power a face gathers from one line would
      // leave on the next, nearly the same line, back where it came from,
      // and pile up in concave parts. A fixed stride through the chunk takes
      // them in an order unrelated to their geometry (docs/algorithm.md).
      const size_t n = chunk.lines();
      const size_t stride = line_stride(n);
      for (size_t i = 0, l = 0; i < n; ++i, l = (l + stride) % n)
        transport_box_line(in, chunk.events.data() + chunk.first[l], chunk.first[l + 1] - chunk.first[l],
                           chunk.entry_ar[l], chunk.exit_ar[l], a);
      progress.advance(chunk.lines());
    }
  });
  // Merge in shard order: faces, the box's Out, the children's In.
  BoxResult result;
  for (size_t f = 0; f < in.faces.size(); ++f) {
    const size_t g = static_cast<size_t>(box.face_global[f]);
    double unsent = 1.0;
    for (const BoxShard& a : acc) unsent -= a.faces.faces[f].quota_used;
    for (int c = 0; c < ch; ++c) {
      double& u = state.unshot[state.at(g, c)];
      u = in.faces[f].quota[c] * unsent;
      for (const BoxShard& a : acc) {
        u += a.faces.faces[f].gathered[c];
        state.phi[state.at(g, c)] += a.faces.faces[f].phi_gain[c];
      }
    }
  }
  for (const BoxShard& a : acc) {
    for (size_t i = 0; i < a.wall_out.size(); ++i) state.ar_out[box.ar_base * ch + i] += a.wall_out[i];
    const auto& children = store.hierarchy().boxes[b].children;
    for (size_t k = 0; k < children.size(); ++k) {
      const StoreBox& child = store.box(children[k]);
      for (size_t i = 0; i < size_t{in.child_ars[k]} * ch; ++i)
        state.ar_in[child.ar_base * ch + i] += a.child_in[size_t{in.child_base[k]} * ch + i];
    }
    for (int c = 0; c < ch; ++c) {
      result.absorbed[c] += a.faces.absorbed[c];
      result.escaped[c] += a.faces.escaped[c];
    }
    result.stats.lines += a.faces.lines;
    result.stats.hits += a.faces.hits;
  }
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace

size_t line_stride(size_t n) {
  if (n < 3) return 1;
  size_t s = static_cast<size_t>(0.6180339887498949 * static_cast<double>(n)) | 1;
  while (std::gcd(s, n) != 1) s += 2;
  return s % n;
}

PassStats hierarchical_iteration(const BoxStore& store, RadiosityState& state, unsigned pass, int threads,
                                 std::vector<BoxPassStats>* per_box) {
  const auto start = std::chrono::steady_clock::now();
  const Hierarchy& h = store.hierarchy();
  if (state.ar_in.size() != store.ar_total() * state.channels) add_ar_state(store, state);
  std::vector<BoxResult> results(h.boxes.size());
  Progress progress(fmt::format("iteration {}", pass), store.lines(), "lines", true);
  // Depth by depth: a box's pass needs its parent's (the power entering it).
  const auto& order = h.depth_order;
  for (size_t lo = 0; lo < order.size();) {
    size_t hi = lo;
    while (hi < order.size() && h.boxes[order[hi]].depth == h.boxes[order[lo]].depth) ++hi;
    tbb::parallel_for(lo, hi, [&](size_t i) { results[order[i]] = box_pass(store, order[i], state, threads, progress); });
    lo = hi;
  }
  progress.finish();
  PassStats stats;
  stats.pass = static_cast<int>(pass);
  for (size_t b = 0; b < results.size(); ++b) {
    for (int c = 0; c < state.channels; ++c) {
      state.energy.absorbed[c] += results[b].absorbed[c];
      state.energy.escaped[c] += results[b].escaped[c];
    }
    stats.lines += results[b].stats.lines;
    stats.hits += results[b].stats.hits;
  }
  if (per_box) {
    per_box->resize(results.size());
    for (size_t b = 0; b < results.size(); ++b) (*per_box)[b] = results[b].stats;
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.unshot_fraction = state.remaining_fraction();
  return stats;
}

}  // namespace mpath
