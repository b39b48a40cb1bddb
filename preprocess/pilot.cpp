#include "pilot.h"

#include <algorithm>
#include <numbers>

#include "box_geometry.h"
#include "line_order.h"
#include "sampling.h"
#include "tracer.h"

namespace mpath {

namespace {
constexpr unsigned kPilotStream = 12;
}

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
  std::vector<double> reflected(faces, 0.0);  // W
  Rng rng = make_rng(seed, kPilotStream, 0);
  for (uint64_t k = 0; k < lines; ++k) {
    const double u = uniform(rng) * total;
    const size_t e = std::min<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin(),
                                      emitters.size() - 1);
    const int face = emitters[e];
    const int patch = mesh.face_patch[face];
    const Vec3 org = uniform_point(mesh, mesh.patches[patch], rng);
    const Vec3 dir = cosine_direction(mesh.face_normal(face), rng);
    const NearestHit hit = tracer.nearest_from(patch, org, dir, tfar);
    if (hit.patch < 0 || mesh.touching(patch, hit.patch)) continue;
    const int met = mesh.face_met(hit.patch, dir);
    if (met < 0) continue;
    reflected[met] += share * mean(scene.materials[mesh.patches[hit.patch].material].rho);
  }
  // What the global lines will carry: a face's estimate from its crossings
  // averages the radiosity of the faces it sees along them, so its variance
  // goes as rho^2 times the mean square of that radiosity over its
  // crossings. Sampled on as many global lines of the root box.
  std::vector<double> seen(faces, 0.0), crossings(faces, 0.0);
  auto radiosity = [&](int f) { return reflected[f] / mesh.patches[mesh.face_patch[f]].area; };
  const BoxLineSampler sampler(line_box(h.boxes[0].bounds));
  std::vector<LineHit> hits;
  for (uint64_t k = 0; k < lines; ++k) {
    const GlobalLine line = sampler.sample(rng);
    tracer.all_hits(line.org, line.dir, line.length, hits);
    for (size_t m = 0; m + 1 < hits.size(); ++m) {
      const int a = facing(mesh, hits[m]).forward, b = facing(mesh, hits[m + 1]).backward;
      if (a < 0 || b < 0 || mesh.touching(hits[m].patch, hits[m + 1].patch)) continue;
      seen[a] += radiosity(b) * radiosity(b);
      seen[b] += radiosity(a) * radiosity(a);
      crossings[a] += 1;
      crossings[b] += 1;
    }
  }
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
