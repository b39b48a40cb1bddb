#include "pilot.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <numbers>
#include <utility>

#include "box_geometry.h"
#include "line_order.h"
#include "sampling.h"
#include "tracer.h"

namespace mpath {

namespace {
constexpr unsigned kPilotStream = 12;
// Lines per block: each block draws from a stream of its own and keeps what
// it finds in a list, and the lists are summed in block order, so that the
// weights are the same, bit for bit, on any number of threads.
constexpr uint64_t kPilotBlock = 4096;

uint64_t block_count(uint64_t lines) { return (lines + kPilotBlock - 1) / kPilotBlock; }

// Runs `lines` lines in blocks of kPilotBlock on the threads there are:
// work(n, rng, out) runs n lines with the block's own stream and appends
// what they find to `out`; then add(pair) takes every block's pairs, in
// block order. The lists hold a pair per crossing of the pilot's lines
// (about 10 MB for 200,000 lines on OFFICE).
template <typename Pair, typename Work, typename Add>
void in_blocks(uint64_t lines, unsigned long long seed, unsigned long long first_stream, const Work& work,
               const Add& add) {
  const uint64_t blocks = block_count(lines);
  std::vector<std::vector<Pair>> found(blocks);
  tbb::parallel_for(uint64_t{0}, blocks, [&](uint64_t b) {
    Rng rng = make_rng(seed, kPilotStream, first_stream + b);
    const uint64_t n = std::min(kPilotBlock, lines - b * kPilotBlock);
    work(n, rng, found[b]);
  });
  for (const std::vector<Pair>& block : found)
    for (const Pair& p : block) add(p);
}
}  // namespace

std::vector<double> pilot_weights(const Scene& scene, const PatchMesh& mesh, const Hierarchy& h,
                                  unsigned long long seed, uint64_t lines) {
  const size_t faces = mesh.face_count();
  auto mean = [](const Rgb& c) { return (c[0] + c[1] + c[2]) / 3.0; };
  // Emitting faces and the power of each (W, mean of the channels).
  std::vector<int> emitters;
  std::vector<double> cumulative;
  double total = 0;
  for (size_t f = 0; f < faces; ++f) {
    const Patch& p = mesh.patches[mesh.face_patch[f]];
    const double power = std::numbers::pi * mean(scene.materials[p.material].emission) * p.area;
    if (!(power > 0)) continue;
    emitters.push_back(static_cast<int>(f));
    total += power;
    cumulative.push_back(total);
  }
  if (emitters.empty() || lines == 0) return {};
  const Tracer tracer(mesh);
  const double tfar = 4.0 * mesh.bounds.diagonal() + 1.0;
  const double share = total / static_cast<double>(lines);
  // Streams: the local lines' blocks first, then the global lines'.
  const unsigned long long global_streams = block_count(lines);
  std::vector<double> reflected(faces, 0.0);  // W
  in_blocks<std::pair<int, double>>(
      lines, seed, 0,
      [&](uint64_t n, Rng& rng, std::vector<std::pair<int, double>>& out) {
        for (uint64_t k = 0; k < n; ++k) {
          const double u = uniform(rng) * total;
          const size_t e = std::min<size_t>(
              std::upper_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin(), emitters.size() - 1);
          const int face = emitters[e];
          const int patch = mesh.face_patch[face];
          const Vec3 org = uniform_point(mesh, mesh.patches[patch], rng);
          const Vec3 dir = cosine_direction(mesh.face_normal(face), rng);
          const NearestHit hit = tracer.nearest_from(patch, org, dir, tfar);
          if (hit.patch < 0 || mesh.touching(patch, hit.patch)) continue;
          const int met = mesh.face_met(hit.patch, dir);
          if (met < 0) continue;
          out.emplace_back(met, share * mean(scene.materials[mesh.patches[hit.patch].material].rho));
        }
      },
      [&](const std::pair<int, double>& p) { reflected[static_cast<size_t>(p.first)] += p.second; });
  // What the global lines will carry: a face's estimate from its crossings
  // averages the radiosity of the faces it sees along them, so its variance
  // goes as rho^2 times the mean square of that radiosity over its
  // crossings. Sampled on as many global lines of the root box.
  std::vector<double> seen(faces, 0.0), crossings(faces, 0.0);
  auto radiosity = [&](int f) { return reflected[f] / mesh.patches[mesh.face_patch[f]].area; };
  const BoxLineSampler sampler(line_box(h.boxes[0].bounds));
  in_blocks<std::pair<int, int>>(
      lines, seed, global_streams,
      [&](uint64_t n, Rng& rng, std::vector<std::pair<int, int>>& out) {
        std::vector<LineHit> hits;
        for (uint64_t k = 0; k < n; ++k) {
          const GlobalLine line = sampler.sample(rng);
          tracer.all_hits(line.org, line.dir, line.length, hits);
          for (size_t m = 0; m + 1 < hits.size(); ++m) {
            const int a = facing(mesh, hits[m]).forward, b = facing(mesh, hits[m + 1]).backward;
            if (a < 0 || b < 0 || mesh.touching(hits[m].patch, hits[m + 1].patch)) continue;
            out.emplace_back(a, b);
          }
        }
      },
      [&](const std::pair<int, int>& p) {
        const auto [a, b] = p;
        seen[a] += radiosity(b) * radiosity(b);
        seen[b] += radiosity(a) * radiosity(a);
        crossings[a] += 1;
        crossings[b] += 1;
      });
  std::vector<double> weight(h.boxes.size(), 0.0);
  for (size_t f = 0; f < faces; ++f) {
    if (!(crossings[f] > 0)) continue;
    const int patch = mesh.face_patch[f];
    const double rho = mean(scene.materials[mesh.patches[patch].material].rho);
    weight[static_cast<size_t>(h.patch_box[static_cast<size_t>(patch)])] += rho * rho * seen[f] / crossings[f];
  }
  return weight;
}

}  // namespace mpath
