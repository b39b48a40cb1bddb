#include "hierarchical.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <utility>

#include "error.h"
#include "first_shot.h"
#include "line_sets.h"
#include "prefetch.h"
#include "progress.h"
#include "sampling.h"

namespace mpath {

using linestore::Event;
using linestore::kNoAr;

namespace {
constexpr unsigned kLineOrderPurpose = 8;  // the order of a pass through a chunk
}  // namespace

void add_ar_state(const BoxStore& store, RadiosityState& state) {
  state.ar_in.assign(store.ar_total() * state.channels, 0.0);
  state.ar_out.assign(store.ar_total() * state.channels, 0.0);
  state.pooled.assign(store.line_sets() ? store.line_sets()->slots() * state.channels : 0, 0.0);
}

namespace {


// An AR's power to send in a pass: its quota and the share of it one line carries.
struct ArInput {
  double quota[3] = {0, 0, 0};
  double share = 0;
};

// What one box's pass reads and never writes.
struct BoxInputs {
  const StoreBox* box = nullptr;
  int channels = 3;
  std::vector<FaceInput> faces;       // local faces
  std::vector<ArInput> wall;          // per wall AR: In, sent inwards
  std::vector<ArInput> child;         // per child AR: Out, sent outwards
  std::vector<const double*> child_t; // per child: transmittances of its ARs
  std::vector<uint32_t> child_base;   // per child: first of its ARs in `child`
  uint32_t patches = 0, children = 0, wall_ars = 0;
  std::vector<uint32_t> child_ars;
  double fraction = 1;                // of the box's lines this pass takes
  std::vector<ChunkPart> parts;       // which
};

// A shard's private accumulators for one box's pass.
struct alignas(128) BoxShard {
  ShardAccumulator faces;
  std::vector<double> wall_out;    // power reaching the box's walls: its Out
  std::vector<double> child_in;    // power entering the children: their In
  std::vector<double> wall_used;   // fraction of each wall AR's quota sent
  std::vector<double> child_used;  // and of each child AR's
  // Scratch of a line: its sends, taken before its receives.
  struct Send {
    int from;  // node index; -1 and m are the line's ends
    int dir;   // +1 along the line, -1 against it
    double power[3];
  };
  std::vector<Send> sends;

  void sum_over_ranks() {
    faces.sum_over_ranks();
    for (std::vector<double>* v : {&wall_out, &child_in, &wall_used, &child_used}) Ranks::sum_records(*v);
  }
};

// Moves the power held in a box's ARs (from `base` in `held`) into the
// quotas, each AR's into its target's; an AR with no target keeps its power.
void move_held(std::vector<double>& held, size_t base, const std::vector<uint32_t>& target, int ch, ArInput* quota) {
  for (size_t r = 0; r < target.size(); ++r) {
    if (target[r] == kNoTarget) continue;
    for (int c = 0; c < ch; ++c) {
      double& h = held[(base + r) * ch + c];
      quota[target[r]].quota[c] += h;
      h = 0;
    }
  }
}

BoxInputs start_box(const BoxStore& store, int b, RadiosityState& state, double power_per_line, unsigned pass) {
  const StoreBox& box = store.box(b);
  const SceneBox& sb = store.hierarchy().boxes[b];
  const int ch = state.channels;
  BoxInputs in;
  in.box = &box;
  in.channels = ch;
  in.patches = static_cast<uint32_t>(box.local_faces.size());
  in.children = static_cast<uint32_t>(sb.children.size());
  in.wall_ars = sb.ar_count();
  double power = 0;  // what the pass has to send, W
  // Faces: their unshot power becomes this pass's quota.
  in.faces.resize(box.face_global.size());
  for (size_t f = 0; f < in.faces.size(); ++f) {
    const size_t g = static_cast<size_t>(box.face_global[f]);
    FaceInput& face = in.faces[f];
    for (int c = 0; c < ch; ++c) {
      face.quota[c] = state.unshot[state.at(g, c)];
      face.rho[c] = state.rho[state.at(g, c)];
      state.unshot[state.at(g, c)] = 0;
      power += face.quota[c];
    }
  }
  // Walls: In is sent inwards along the lines that meet something inside.
  in.wall.assign(in.wall_ars, ArInput{});
  if (b > 0) move_held(state.ar_in, box.ar_base, box.in_target, ch, in.wall.data());
  // Children: Out is sent outwards along this box's lines that cross it.
  uint32_t total = 0;
  for (int child : sb.children) {
    in.child_base.push_back(total);
    in.child_ars.push_back(store.hierarchy().boxes[child].ar_count());
    total += store.hierarchy().boxes[child].ar_count();
  }
  in.child.assign(total, ArInput{});
  for (uint32_t k = 0; k < in.children; ++k) {
    const StoreBox& child = store.box(sb.children[k]);
    move_held(state.ar_out, child.ar_base, child.out_target, ch, &in.child[in.child_base[k]]);
    in.child_t.push_back(child.transmittance.data());
  }
  for (const auto* ars : {&in.wall, &in.child})
    for (const ArInput& a : *ars)
      for (int c = 0; c < ch; ++c) power += a.quota[c];

  // How many lines: all of them, or as many as carry `power_per_line` each,
  // at least the box's coverage.
  if (power_per_line > 0 && box.lines > 0) {
    const double wanted = power / (power_per_line * static_cast<double>(box.lines));
    in.fraction = std::clamp(wanted, box.coverage, 1.0);
  }
  in.parts = pass_parts(store, b, in.fraction, pass);
  if (in.fraction < 1.0) {
    uint64_t lines = 0;
    for (const ChunkPart& p : in.parts) lines += p.lines;
    in.fraction = static_cast<double>(lines) / static_cast<double>(box.lines);
  }
  // What a line carries: the quota over the crossings expected in this pass
  // (all of them when the pass takes every line).
  auto share = [&](double crossings) { return crossings > 0 ? 1.0 / (crossings * in.fraction) : 0.0; };
  for (size_t f = 0; f < in.faces.size(); ++f) in.faces[f].share = share(box.face_crossings[f]);
  // A face no line crosses hands its quota to its proxy.
  for (size_t f = 0; f < in.faces.size(); ++f) {
    const int p = box.face_proxy[f];
    if (p < 0 || p == static_cast<int>(f)) continue;
    for (int c = 0; c < ch; ++c) {
      in.faces[p].quota[c] += in.faces[f].quota[c];
      in.faces[f].quota[c] = 0;
    }
  }
  if (b > 0)
    for (uint32_t r = 0; r < in.wall_ars; ++r)
      in.wall[r].share = share(double(box.counts.wall_lines[r]) - double(box.counts.wall_open[r]));
  for (uint32_t k = 0; k < in.children; ++k)
    for (uint32_t r = 0; r < in.child_ars[k]; ++r)
      in.child[in.child_base[k] + r].share = share(box.counts.child_crossings[box.child_ar_base[k] + r]);
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

// Brings into the caches what transport_box_line will touch at the patches
// of a line `distance` lines ahead: the patches' faces (4 lines ahead), then
// the faces' pass records (2), as prefetch_set_line does for line sets.
void prefetch_box_line(const BoxInputs& in, const BoxShard& shard, const Event* ev, size_t n, size_t distance) {
  const auto& local = in.box->local_faces;
  if (distance == 4) {
    for (size_t i = 0; i < n; ++i)
      if (ev[i].kind == Event::patch) prefetch(&local[ev[i].id]);
  } else if (distance == 2) {
    for (size_t i = 0; i < n; ++i)
      if (ev[i].kind == Event::patch)
        for (const int face : local[ev[i].id])
          if (face >= 0) {
            prefetch(&in.faces[face]);
            prefetch(&shard.faces.faces[face]);
          }
  }
}

// One line of the box in both directions (docs/method.md, 7): every face,
// wall AR and child box on it sends before anything is received.
// CH: the channel count (1 or 3), fixed at compile time so the per-channel
// loops unroll.
template <int CH>
void transport_box_line(const BoxInputs& in, const Event* ev, size_t m, uint32_t entry, uint32_t exit, BoxShard& shard,
                        double allowance) {
  ShardAccumulator& acc = shard.faces;
  constexpr int ch = CH;
  ++acc.lines;
  acc.hits += m;
  if (m == 0) return;  // a line meeting nothing carries nothing
  using Send = BoxShard::Send;
  std::vector<Send>& sends = shard.sends;
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
  // An AR sends its share of its quota, never more in all than the shard's allowance.
  auto send_ar = [&](const ArInput& input, double& used, int from, int dir) {
    double fraction = std::min(input.share, allowance - used);
    if (!(fraction > 0)) return;
    used += fraction;
    double power[3];
    for (int c = 0; c < ch; ++c) power[c] = input.quota[c] * fraction;
    send_power(from, dir, power);
  };
  auto send_face = [&](int face, int from, int dir) {
    if (face < 0) return;
    double power[3];
    face_send(in.faces[face], acc.faces[face], allowance, ch, power);
    send_power(from, dir, power);
  };
  const int n = static_cast<int>(m);
  // A face pressed against the next crossing it sees keeps its share (face_keep).
  auto send_or_keep = [&](int face, int from, int dir) {
    if (face < 0) return;
    const int j = next_seen(from, dir, n, [&](int x, int d) {
      return ev[x].kind == Event::patch ? face_towards(*in.box, ev[x], d) : 0;
    });
    if (j >= 0 && j < n && ev[j].kind == Event::patch && touching(*in.box, ev[from], ev[j]))
      face_keep(in.faces[face], acc.faces[face], allowance, ch);
    else
      send_face(face, from, dir);
  };
  if (entry != kNoAr) send_ar(in.wall[entry], shard.wall_used[entry], -1, +1);
  for (int i = 0; i < n; ++i) {
    const Event& e = ev[i];
    if (e.kind == Event::patch) {
      send_or_keep(face_towards(*in.box, e, +1), i, +1);
      send_or_keep(face_towards(*in.box, e, -1), i, -1);
    } else {
      const uint32_t base = in.child_base[e.id];
      send_ar(in.child[base + e.exit_ar], shard.child_used[base + e.exit_ar], i, +1);
      send_ar(in.child[base + e.entry_ar], shard.child_used[base + e.entry_ar], i, -1);
    }
  }
  if (exit != kNoAr) send_ar(in.wall[exit], shard.wall_used[exit], n, -1);

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
        // The face turned towards the power: the back when it travels along the line.
        const int face = face_towards(*in.box, e, -s.dir);
        if (face == kInvisibleSide) continue;  // passes it from behind
        if (face < 0) {
          for (int c = 0; c < ch; ++c) acc.absorbed[c] += p[c];
          break;
        }
        face_receive(in.faces[face], acc.faces[face], p, ch, acc.absorbed.data());
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

struct BoxResult {
  std::array<double, 3> absorbed{}, escaped{};
  BoxPassStats stats;
};

BoxResult box_pass(const BoxStore& store, int b, RadiosityState& state, int shards_wanted, double power_per_line,
                   unsigned pass, Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const BoxInputs in = start_box(store, b, state, power_per_line, pass);
  const StoreBox& box = store.box(b);
  const int ch = state.channels;
  const uint64_t chunks = in.parts.size();
  const bool every_line = in.fraction >= 1.0;
  const uint64_t pass_lines = part_lines(in.parts, 0, chunks);
  const int shards = pass_shards(shards_wanted, chunks);
  std::vector<BoxShard> acc(shards);
  run_shards(acc, [&](int s) {
    BoxShard& a = acc[s];
    a.faces.reset(in.faces.size());
    a.wall_out.assign(size_t{in.wall_ars} * ch, 0.0);
    a.child_in.assign(in.child.size() * ch, 0.0);
    a.wall_used.assign(in.wall.size(), 0.0);
    a.child_used.assign(in.child.size(), 0.0);
  }, [&](int s) {
    BoxShard& a = acc[s];
    // With every line, the exact crossing counts make the shares add up to
    // each quota; with a part of them, each shard may send its part only.
    const uint64_t lo = chunks * s / shards, hi = chunks * (s + 1) / shards;
    const double allowance =
        every_line || pass_lines == 0 ? 1.0 : double(part_lines(in.parts, lo, hi)) / double(pass_lines);
    stream_pass_lines(
        store, b, in.parts, lo, hi, pass, progress, nullptr,
        [&](const linestore::DecodedChunk& chunk, uint64_t c) {
          if (!chunk_fits(in, chunk))
            throw InputError(fmt::format("store: box {} chunk {} names patches, boxes or ARs the box does not have "
                                         "(damaged or foreign store); run mpath-preprocess again", b, c));
        },
        [&](const linestore::DecodedChunk& chunk, uint32_t l) {
          (ch == 1 ? transport_box_line<1> : transport_box_line<3>)(
              in, chunk.events.data() + chunk.first[l], chunk.first[l + 1] - chunk.first[l], chunk.entry_ar[l],
              chunk.exit_ar[l], a, allowance);
        },
        [&](const linestore::DecodedChunk& chunk, uint32_t l, size_t distance) {
          prefetch_box_line(in, a, chunk.events.data() + chunk.first[l], chunk.first[l + 1] - chunk.first[l], distance);
        });
  });
  // Merge in shard order: faces, the box's Out, the children's In, and what
  // no line took back where it was held.
  BoxResult result;
  for_each_record(in.faces.size(), [&](size_t f) {  // each face its own records: on the threads
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
  });
  const auto& children = store.hierarchy().boxes[b].children;
  auto unsent = [&](const std::vector<double> BoxShard::*used, size_t i) {
    double u = 1.0;
    for (const BoxShard& a : acc) u -= (a.*used)[i];
    return u;
  };
  for (uint32_t r = 0; r < in.wall_ars; ++r) {
    const double u = unsent(&BoxShard::wall_used, r);
    for (int c = 0; c < ch; ++c) state.ar_in[(box.ar_base + r) * ch + c] += in.wall[r].quota[c] * u;
  }
  for (size_t k = 0; k < children.size(); ++k) {
    const StoreBox& child = store.box(children[k]);
    for (uint32_t r = 0; r < in.child_ars[k]; ++r) {
      const double u = unsent(&BoxShard::child_used, in.child_base[k] + r);
      for (int c = 0; c < ch; ++c) state.ar_out[(child.ar_base + r) * ch + c] += in.child[in.child_base[k] + r].quota[c] * u;
    }
  }
  for (const BoxShard& a : acc) {
    for (size_t i = 0; i < a.wall_out.size(); ++i) state.ar_out[box.ar_base * ch + i] += a.wall_out[i];
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

// The lines a pass over `fraction` of a box's lines takes: a run of whole
// chunks (each holds lines spread over the whole box) from a place that
// moves from pass to pass, and the first lines, in stride order, of the
// last. Every line when `fraction` is 1.
std::vector<ChunkPart> pass_parts(const BoxStore& store, int b, double fraction, unsigned pass) {
  const StoreBox& box = store.box(b);
  const uint64_t chunks = box.chunks.size();
  std::vector<ChunkPart> out;
  if (chunks == 0) return out;
  if (fraction >= 1.0) {
    for (uint64_t c = 0; c < chunks; ++c) out.push_back({c, box.chunk_lines[c]});
    return out;
  }
  uint64_t need = std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(fraction * static_cast<double>(box.lines))));
  const uint64_t first = static_cast<uint64_t>(std::fmod(pass * 0.6180339887498949, 1.0) * static_cast<double>(chunks));
  for (uint64_t i = 0; i < chunks && need > 0; ++i) {
    const uint64_t c = (first + i) % chunks;
    const uint64_t take = std::min(need, box.chunk_lines[c]);
    out.push_back({c, take});
    need -= take;
  }
  return out;
}

Remaining remaining_power(const BoxStore& store, const RadiosityState& state) {
  Remaining r;
  const int ch = state.channels;
  for (size_t b = 0; b < store.box_count(); ++b) {
    const StoreBox& box = store.box(static_cast<int>(b));
    double here = 0;
    for (size_t f = 0; f < box.face_global.size(); ++f)
      for (int c = 0; c < ch; ++c) {
        const double u = state.unshot[state.at(static_cast<size_t>(box.face_global[f]), c)];
        r.unshot += u;
        here += u;
        if (box.face_proxy[f] < 0) r.stuck_faces += u;
      }
    for (size_t a = 0; a < box.in_target.size(); ++a)
      for (int c = 0; c < ch; ++c) {
        const double in = state.ar_in[(box.ar_base + a) * ch + c], out = state.ar_out[(box.ar_base + a) * ch + c];
        r.in += in;
        r.out += out;
        here += in + out;
        if (box.in_target[a] == kNoTarget) r.stuck_in += in;
        if (box.out_target[a] == kNoTarget) r.stuck_out += out;
      }
    if (here > r.deepest_power) {
      r.deepest_power = here;
      r.deepest_box = static_cast<int>(b);
    }
  }
  return r;
}

uint64_t shoot_uncarried(const PatchMesh& mesh, const TracerOnDemand& tracer, const BoxStore& store,
                         RadiosityState& state, unsigned pass, unsigned long long seed, int shards_wanted) {
  const int ch = state.channels;
  std::vector<int> faces;
  for (size_t b = 0; b < store.box_count(); ++b) {
    const StoreBox& box = store.box(static_cast<int>(b));
    for (size_t f = 0; f < box.face_global.size(); ++f) {
      if (box.face_proxy[f] >= 0) continue;
      const int g = box.face_global[f];
      bool any = false;
      for (int c = 0; c < ch; ++c) any |= state.unshot[state.at(static_cast<size_t>(g), c)] > 0;
      if (any) faces.push_back(g);
    }
  }
  return shoot_unshot(mesh, tracer, std::move(faces), state, pass, seed, shards_wanted);
}

PassStats stored_iteration(const Options& options, const PatchMesh& mesh, const TracerOnDemand& tracer,
                           const BoxStore& store, RadiosityState& state, const IterationLog& log, unsigned pass,
                           int shards_wanted, std::vector<BoxPassStats>* per_box, uint64_t* uncarried) {
  if (const LineSets* sets = store.line_sets()) {
    double power_per_line = line_power(options, store, log);
    const int passes_left = options.solver.iterations - static_cast<int>(log.passes.size());
    if (power_per_line > 0 && full_pass_pays(log, store.lines(), state.emitted_total(), mesh.face_count(),
                                             options.solver.tolerance, passes_left))
      power_per_line = 0;
    return line_set_iteration(mesh, tracer, store, *sets, state, pass, shards_wanted, power_per_line,
                              options.lines.seed, per_box, uncarried);
  }
  PassStats p = hierarchical_iteration(store, state, pass, shards_wanted, line_power(options, store, log),
                                       options.solver.schedule == "v-cycle", per_box);
  const uint64_t shot = shoot_uncarried(mesh, tracer, store, state, pass, options.lines.seed, shards_wanted);
  if (uncarried) *uncarried += shot;
  p.unshot_fraction = state.remaining_fraction();
  return p;
}

bool full_pass_pays(const IterationLog& log, uint64_t store_lines, double emitted, size_t faces, double tolerance,
                    int passes_left) {
  if (log.passes.size() < 2 || !(emitted > 0) || log.first_unshot <= 0) return false;
  const PassStats& first = log.passes.front();
  const PassStats& last = log.passes.back();
  if (first.lines < store_lines || last.lines >= store_lines) return false;  // a full pass to weigh a partial one against
  const double left = last.unshot_fraction, before_last = log.passes[log.passes.size() - 2].unshot_fraction;
  const double need = std::log(left / tolerance);  // the factor still to go, as a logarithm
  if (!(need > 0)) return false;
  // Passes of either kind to get there, at the factor each took last, and
  // their cost in crossings: a pass's own, and about 16 for every face of
  // the scene for the work around it (its inputs, the merge, the pools:
  // measured as 13 to 17 on ROOM, BIG ROOM and OFFICE from the seconds of
  // full and partial passes of one solve).
  const auto passes = [&](double before, double after) {
    const double factor = std::log(before / after);
    return factor > 0 ? std::ceil(need / factor) : static_cast<double>(INFINITY);
  };
  const double overhead = 16.0 * static_cast<double>(faces);
  const double partial = passes(before_last, left), full = passes(log.first_unshot / emitted, first.unshot_fraction);
  if (partial > passes_left && full <= passes_left) return true;
  return full * (static_cast<double>(first.hits) + overhead) < partial * (static_cast<double>(last.hits) + overhead);
}

double line_power(const Options& options, const BoxStore& store, const IterationLog& log) {
  if (!options.solver.adaptive_lines || log.passes.empty() || log.first_unshot <= 0 || store.lines() == 0) return 0.0;
  return log.first_unshot / static_cast<double>(store.lines());
}

void chunk_line_order(unsigned long long seed, unsigned pass, int box, uint64_t chunk, size_t n,
                      std::vector<uint32_t>& order) {
  order.resize(n);
  std::iota(order.begin(), order.end(), 0u);
  Rng rng = make_rng(derived_seed(seed, pass, static_cast<unsigned long long>(box)), kLineOrderPurpose, chunk);
  std::shuffle(order.begin(), order.end(), rng);
}

PassStats hierarchical_iteration(const BoxStore& store, RadiosityState& state, unsigned pass, int shards_wanted,
                                 double power_per_line, bool v_cycle, std::vector<BoxPassStats>* per_box) {
  const auto start = std::chrono::steady_clock::now();
  const Hierarchy& h = store.hierarchy();
  if (state.ar_in.size() != store.ar_total() * state.channels) add_ar_state(store, state);
  // The passes of the iteration, depth by depth: a box's pass needs its
  // parent's (the power entering it). The V-cycle runs the subscenes deepest
  // first before the root, so that what they send out crosses every level
  // up in the same iteration, then top-down as MP(root) does.
  const int depth = h.max_depth();
  std::vector<int> levels;
  if (v_cycle)
    for (int d = depth; d >= 1; --d) levels.push_back(d);
  for (int d = 0; d <= depth; ++d) levels.push_back(d);
  std::vector<std::vector<int>> at_depth(depth + 1);
  for (int b : h.depth_order) at_depth[h.boxes[b].depth].push_back(b);

  uint64_t most_lines = 0;  // every box's lines in every pass: how many a box takes is known at its start
  for (int level : levels)
    for (int b : at_depth[level]) most_lines += store.box(b).lines;
  Progress progress(fmt::format("iteration {}", pass), most_lines, "lines", true);
  std::vector<std::vector<BoxResult>> results(levels.size());
  for (size_t i = 0; i < levels.size(); ++i) {
    const std::vector<int>& boxes = at_depth[levels[i]];
    const unsigned rotation = pass * 2 + (i < levels.size() - depth - 1 ? 1 : 0);  // the up-sweep takes other lines
    results[i].resize(boxes.size());
    for_each_box(boxes.size(), [&](size_t k) {
      results[i][k] = box_pass(store, boxes[k], state, shards_wanted, power_per_line, rotation, progress);
    });
  }
  progress.finish();
  PassStats stats;
  stats.pass = static_cast<int>(pass);
  if (per_box) per_box->assign(h.boxes.size(), BoxPassStats{});
  for (size_t i = 0; i < levels.size(); ++i)
    for (size_t k = 0; k < results[i].size(); ++k) {
      const BoxResult& r = results[i][k];
      for (int c = 0; c < state.channels; ++c) {
        state.energy.absorbed[c] += r.absorbed[c];
        state.energy.escaped[c] += r.escaped[c];
      }
      stats.lines += r.stats.lines;
      stats.hits += r.stats.hits;
      if (per_box) {
        BoxPassStats& p = (*per_box)[at_depth[levels[i]][k]];
        p.lines += r.stats.lines;
        p.hits += r.stats.hits;
        p.seconds += r.stats.seconds;
      }
    }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.unshot_fraction = state.remaining_fraction();
  return stats;
}

}  // namespace mpath
