#include "pilot.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>

#include "box_geometry.h"
#include "first_shot.h"
#include "line_order.h"
#include "sampling.h"
#include "tracer.h"

#include <spdlog/spdlog.h>

namespace mpath {

namespace {
constexpr unsigned kPilotStream = 12;
// Lines per block: each block draws from a stream of its own and keeps what
// it finds in a list, and the lists are summed in block order, so that the
// weights are the same, bit for bit, on any number of threads.
constexpr uint64_t kPilotBlock = 4096;
// Stratified first shots: replicas, and the fewest lines an emitter shoots
// in each for its points to be worth stratifying.
constexpr uint64_t kPilotReplicas = 8;
constexpr uint64_t kStratifiedLines = 4;
constexpr unsigned long long kShiftIndex = 1ULL << 40;  // the replicas' shifts: past the blocks' streams

uint64_t block_count(uint64_t lines) { return (lines + kPilotBlock - 1) / kPilotBlock; }

// Runs `lines` lines in blocks of kPilotBlock on the threads there are:
// work(first, n, rng, out) runs lines [first, first + n) with the block's
// own stream and appends what they find to `out`; then add(pair) takes
// every block's pairs, in block order. The lists hold a pair per crossing
// of the pilot's lines (about 10 MB for 200,000 lines on OFFICE).
template <typename Pair, typename Work, typename Add>
void in_blocks(uint64_t lines, unsigned long long seed, unsigned long long first_stream, const Work& work,
               const Add& add) {
  const uint64_t blocks = block_count(lines);
  std::vector<std::vector<Pair>> found(blocks);
  tbb::parallel_for(uint64_t{0}, blocks, [&](uint64_t b) {
    Rng rng = make_rng(seed, kPilotStream, first_stream + b);
    const uint64_t n = std::min(kPilotBlock, lines - b * kPilotBlock);
    work(b * kPilotBlock, n, rng, found[b]);
  });
  for (const std::vector<Pair>& block : found)
    for (const Pair& p : block) add(p);
}
}  // namespace

Pilot run_pilot(const Scene& scene, const PatchMesh& mesh, const Hierarchy* h, unsigned long long seed,
                uint64_t lines, bool stratified, const Tracer* given, const std::vector<PointLight>& lights) {
  const size_t faces = mesh.face_count();
  auto mean = [](const Rgb& c) { return (c[0] + c[1] + c[2]) / 3.0; };
  // Emitting faces, then the point sources (-1 - light), and the power of
  // each (W, mean of the channels; a light's is the same in every channel).
  std::vector<int> emitters;
  std::vector<double> powers, cumulative;
  double total = 0;
  const auto add = [&](int emitter, double power) {
    if (!(power > 0)) return;
    emitters.push_back(emitter);
    powers.push_back(power);
    total += power;
    cumulative.push_back(total);
  };
  for (size_t f = 0; f < faces; ++f) {
    const Patch& p = mesh.patches[mesh.face_patch[f]];
    add(static_cast<int>(f), std::numbers::pi * mean(scene.materials[p.material].emission) * p.area);
  }
  for (size_t l = 0; l < lights.size(); ++l) add(-1 - static_cast<int>(l), lights[l].power());
  if (emitters.empty() || lines == 0) return {};
  Pilot pilot;
  std::optional<Tracer> own;
  const Tracer& tracer = given ? *given : own.emplace(mesh);
  const double tfar = 4.0 * mesh.bounds.diagonal() + 1.0;
  const double share = total / static_cast<double>(lines);
  const auto rho_of = [&](int f) { return mean(scene.materials[mesh.patches[mesh.face_patch[f]].material].rho); };
  // The face a local line of emitter `emitter` (a face, or -1 - light) meets
  // first, or -1.
  const auto met_from = [&](int emitter, const Vec3& org, const Vec3& dir) {
    const NearestHit hit =
        emitter < 0 ? tracer.nearest(org, dir, 0.0, tfar) : tracer.nearest_from(mesh.face_patch[emitter], org, dir, tfar);
    if (hit.patch < 0 || (emitter >= 0 && mesh.touching(mesh.face_patch[emitter], hit.patch))) return -1;
    return mesh.face_met(hit.patch, dir);
  };
  // Streams: the local lines' blocks first, then the global lines'.
  const unsigned long long global_streams = block_count(lines);
  std::vector<double> reflected(faces, 0.0);  // W
  // Lines in a replica of a stratified first shot.
  const uint64_t per_replica = std::max<uint64_t>(1, lines / kPilotReplicas);
  if (stratified && per_replica >= kStratifiedLines * emitters.size()) {
    // As the first shot shoots them (first_shot.sequence = "halton"): each
    // emitter its lines by power, on the Halton points of a shift of its
    // own; kPilotReplicas such shots of lines / kPilotReplicas lines with
    // independent shifts. Each gives every face its reflected power; their
    // mean is the face's, their spread the variance of such a shot.
    const std::vector<uint64_t> counts = lines_by_power(powers, static_cast<long long>(per_replica));
    std::vector<uint64_t> first{0};
    for (uint64_t n : counts) first.push_back(first.back() + n);
    const uint64_t m = first.back();
    std::vector<double> replica(kPilotReplicas * faces, 0.0);
    in_blocks<std::pair<uint64_t, double>>(
        kPilotReplicas * m, seed, 0,
        [&](uint64_t from, uint64_t n, Rng&, std::vector<std::pair<uint64_t, double>>& out) {
          uint64_t shifted = ~uint64_t{0};  // the replica and emitter of `points`
          std::optional<ShiftedHalton> points;
          std::optional<PatchSampler> sampler;  // the emitter's, when it is a face
          double u[4];
          for (uint64_t i = from; i < from + n; ++i) {
            const uint64_t r = i / m, j = i % m;
            const size_t e = static_cast<size_t>(std::upper_bound(first.begin(), first.end(), j) - first.begin() - 1);
            if (r * emitters.size() + e != shifted) {
              shifted = r * emitters.size() + e;
              points.emplace(make_rng(seed, kPilotStream, kShiftIndex + shifted));
              if (const int f = emitters[e]; f >= 0)
                sampler.emplace(mesh, mesh.patches[mesh.face_patch[f]], mesh.face_normal(f));
            }
            points->point(j - first[e], u);
            const int emitter = emitters[e];
            Vec3 org, dir;
            if (emitter < 0) {
              const PointLight& light = lights[static_cast<size_t>(-1 - emitter)];
              org = light.options.position;
              dir = light.sample(u[0], u[1], u[2]);
            } else {
              org = sampler->point(u[0], u[1]);
              dir = sampler->direction(u[2], u[3]);
            }
            const int met = met_from(emitter, org, dir);
            if (met < 0) continue;
            out.emplace_back(r * faces + static_cast<uint64_t>(met),
                             powers[e] / static_cast<double>(counts[e]) * rho_of(met));
          }
        },
        [&](const std::pair<uint64_t, double>& p) { replica[p.first] += p.second; });
    for (size_t f = 0; f < faces; ++f) {
      double sum = 0, square = 0;
      for (uint64_t r = 0; r < kPilotReplicas; ++r) sum += replica[r * faces + f];
      reflected[f] = sum / kPilotReplicas;
      for (uint64_t r = 0; r < kPilotReplicas; ++r) square += std::pow(replica[r * faces + f] - reflected[f], 2);
      // A replica's variance of the radiosity, in area x radiosity^2.
      pilot.first_shot_variance += square / (kPilotReplicas - 1) / mesh.patches[mesh.face_patch[f]].area;
    }
    pilot.first_shot_variance *= static_cast<double>(m);
    pilot.first_shot_stratified = true;
  } else {
    in_blocks<std::pair<int, double>>(
        lines, seed, 0,
        [&](uint64_t, uint64_t n, Rng& rng, std::vector<std::pair<int, double>>& out) {
          for (uint64_t k = 0; k < n; ++k) {
            const double u = uniform(rng) * total;
            const size_t e = std::min<size_t>(
                std::upper_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin(), emitters.size() - 1);
            const int emitter = emitters[e];
            Vec3 org, dir;
            if (emitter < 0) {  // a point source, as shoot_light draws its lines
              const PointLight& light = lights[static_cast<size_t>(-1 - emitter)];
              double v[3];
              for (double& x : v) x = uniform(rng);
              org = light.options.position;
              dir = light.sample(v[0], v[1], v[2]);
            } else {
              org = uniform_point(mesh, mesh.patches[mesh.face_patch[emitter]], rng);
              dir = cosine_direction(mesh.face_normal(emitter), rng);
            }
            const int met = met_from(emitter, org, dir);
            if (met < 0) continue;
            out.emplace_back(met, share * rho_of(met));
          }
        },
        [&](const std::pair<int, double>& p) { reflected[static_cast<size_t>(p.first)] += p.second; });
    // A local line brings a face the reflected power share * rho, so a
    // face's reflected power, a sum of such, has the variance share * rho *
    // its mean: in area x radiosity^2, share * rho * reflected / area.
    for (size_t f = 0; f < faces; ++f)
      pilot.first_shot_variance += share * rho_of(static_cast<int>(f)) * reflected[f] / mesh.patches[mesh.face_patch[f]].area;
    pilot.first_shot_variance *= static_cast<double>(lines);
  }
  // What the global lines will carry: a face's estimate from its crossings
  // averages the radiosity of the faces it sees along them, so its variance
  // goes as rho^2 times the mean square of that radiosity over its
  // crossings. Sampled on as many global lines of the root box. (A line's
  // crossing count comes as the pair (-1, count).)
  std::vector<double> seen(faces, 0.0), seen_sum(faces, 0.0), crossings(faces, 0.0);
  double line_hits = 0;
  auto radiosity = [&](int f) { return reflected[f] / mesh.patches[mesh.face_patch[f]].area; };
  const BoxLineSampler sampler(line_box(mesh.bounds));  // the root box's, where there is a hierarchy
  in_blocks<std::pair<int, int>>(
      lines, seed, global_streams,
      [&](uint64_t, uint64_t n, Rng& rng, std::vector<std::pair<int, int>>& out) {
        std::vector<LineHit> hits;
        for (uint64_t k = 0; k < n; ++k) {
          const GlobalLine line = sampler.sample(rng);
          tracer.all_hits(line.org, line.dir, line.length, hits);
          out.emplace_back(-1, static_cast<int>(hits.size()));
          for (size_t m = 0; m + 1 < hits.size(); ++m) {
            const int a = facing(mesh, hits[m]).forward, b = facing(mesh, hits[m + 1]).backward;
            if (a < 0 || b < 0 || mesh.touching(hits[m].patch, hits[m + 1].patch)) continue;
            out.emplace_back(a, b);
          }
        }
      },
      [&](const std::pair<int, int>& p) {
        const auto [a, b] = p;
        if (a < 0) {
          line_hits += b;
          return;
        }
        seen[a] += radiosity(b) * radiosity(b);
        seen[b] += radiosity(a) * radiosity(a);
        seen_sum[a] += radiosity(b);
        seen_sum[b] += radiosity(a);
        crossings[a] += 1;
        crossings[b] += 1;
      });
  pilot.box_weights.assign(h ? h->boxes.size() : 1, 0.0);
  // The global lines' part, face by face: rho^2 times the variance of the
  // radiosity seen over a face's crossings, over its crossings n, in area x
  // radiosity^2; with n its expected crossings, area times the crossings per
  // unit area k, the area cancels: rho^2 variance / k. The variance over a
  // face's c pilot crossings is estimated without bias (c / (c - 1) times
  // the spread about their mean); a face crossed once or not at all shows
  // none and takes the mean variance of the others. (Counting such
  // faces as certain, or leaving the faces no pilot line crossed out, put
  // the global variance of RenderPark's office3 at half its value with the
  // pilot of 100,000 lines that 2M-line runs have.)
  double area_sum = 0, total_crossings = 0, known = 0;
  size_t known_faces = 0;
  std::vector<double> variance(faces, -1.0);  // -1: not known
  for (size_t f = 0; f < faces; ++f) {
    const int patch = mesh.face_patch[f];
    const double area = mesh.patches[patch].area;
    const double rho = mean(scene.materials[mesh.patches[patch].material].rho);
    area_sum += area;
    total_crossings += crossings[f];
    if (!(crossings[f] > 0)) continue;
    pilot.box_weights[h ? static_cast<size_t>(h->patch_box[static_cast<size_t>(patch)]) : 0] +=
        rho * rho * seen[f] / crossings[f];
    if (crossings[f] < 2) continue;
    const double c = crossings[f], mean_seen = seen_sum[f] / c;
    variance[f] = std::max(0.0, seen[f] / c - mean_seen * mean_seen) * c / (c - 1);
    known += variance[f];
    ++known_faces;
  }
  const double imputed = known_faces > 0 ? known / static_cast<double>(known_faces) : 0.0;
  const double per_area = total_crossings / area_sum;  // crossings per unit area, k
  for (size_t f = 0; f < faces; ++f) {
    const double rho = mean(scene.materials[mesh.patches[mesh.face_patch[f]].material].rho);
    pilot.global_variance += rho * rho * (variance[f] >= 0 ? variance[f] : imputed);
    if (crossings[f] > 0) pilot.global_mean_square += rho * rho * seen[f] / crossings[f];
  }
  if (per_area > 0) {
    pilot.global_variance /= per_area;
    pilot.global_mean_square /= per_area;
  }
  // Per line: the variances fall as one over the lines.
  pilot.global_variance *= static_cast<double>(lines);
  pilot.global_mean_square *= static_cast<double>(lines);
  pilot.hits_per_line = line_hits / static_cast<double>(lines);
  return pilot;
}

std::vector<double> pilot_weights(const Scene& scene, const PatchMesh& mesh, const Hierarchy& h,
                                  unsigned long long seed, uint64_t lines) {
  return run_pilot(scene, mesh, &h, seed, lines, true).box_weights;
}

double first_shot_share(const Pilot& pilot) {
  if (pilot.empty() || !(pilot.first_shot_variance > 0)) return 0;
  if (!(pilot.global_variance > 0)) return 4.0;  // the global lines carry nothing uncertain
  const double cost = std::max(1.0, pilot.hits_per_line);
  return std::clamp(std::sqrt(cost * pilot.first_shot_variance / pilot.global_variance), 0.125, 4.0);
}

void log_first_shot_choice(const Pilot& pilot, long long first_shot_lines, long long total_lines) {
  if (pilot.empty()) {
    spdlog::info("first shot: {} local lines (half of lines.total: nothing emits for the pilot to weigh)", first_shot_lines);
    return;
  }
  spdlog::info("first shot: {} local lines, {:.3g} per line of lines.total (pilot: first-shot variance {:.3g}, "
               "global {:.3g} per line, {:.2f} crossings per global line)",
               first_shot_lines, static_cast<double>(first_shot_lines) / static_cast<double>(total_lines),
               pilot.first_shot_variance, pilot.global_variance, pilot.hits_per_line);
}

}  // namespace mpath
