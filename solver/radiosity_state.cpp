#include "radiosity_state.h"

#include <numbers>

namespace mpath {

RadiosityState make_state(const Scene& scene, const PatchMesh& mesh) {
  RadiosityState s;
  s.channels = scene.is_grey() ? 1 : 3;
  s.faces = mesh.face_count();
  const size_t n = s.faces * s.channels;
  s.rho.assign(n, 0.0);
  s.exitance.assign(n, 0.0);
  s.emitted_power.assign(n, 0.0);
  s.unshot.assign(n, 0.0);
  for (size_t f = 0; f < s.faces; ++f) {
    const Patch& p = mesh.patches[mesh.face_patch[f]];
    const Material& m = scene.materials[p.material];
    for (int c = 0; c < s.channels; ++c) {
      s.rho[s.at(f, c)] = m.rho[c];
      s.exitance[s.at(f, c)] = std::numbers::pi * m.emission[c];
      s.emitted_power[s.at(f, c)] = s.exitance[s.at(f, c)] * p.area;
      s.energy.emitted[c] += s.emitted_power[s.at(f, c)];
    }
  }
  s.phi = s.emitted_power;
  return s;
}

double RadiosityState::unshot_total() const {
  double sum = 0;
  for (double u : unshot) sum += u;
  for (double u : pooled) sum += u;
  return sum;
}

std::array<double, 3> RadiosityState::unshot_per_channel() const {
  std::array<double, 3> sum{};
  for (size_t i = 0; i < unshot.size(); ++i) sum[i % channels] += unshot[i];
  for (size_t i = 0; i < pooled.size(); ++i) sum[i % channels] += pooled[i];
  return sum;
}

double RadiosityState::held_total() const {
  double sum = 0;
  for (double u : ar_in) sum += u;
  for (double u : ar_out) sum += u;
  return sum;
}

double RadiosityState::remaining_fraction() const {
  const double e = emitted_total();
  return e > 0 ? (unshot_total() + held_total()) / e : 0.0;
}

double RadiosityState::emitted_total() const {
  return energy.emitted[0] + energy.emitted[1] + energy.emitted[2];
}

double RadiosityState::energy_residual() const {
  double r = unshot_total() + held_total();
  for (int c = 0; c < 3; ++c) r += energy.absorbed[c] + energy.escaped[c];
  return emitted_total() - r;
}

std::array<double, 3> RadiosityState::radiosity(const PatchMesh& mesh, size_t face) const {
  std::array<double, 3> b{};
  const double area = mesh.face_area(static_cast<int>(face));
  for (int c = 0; c < 3; ++c) b[c] = phi[at(face, channels == 1 ? 0 : c)] / area;
  return b;
}

std::array<double, 3> RadiosityState::face_rho(size_t face) const {
  return {rho[at(face, 0)], rho[at(face, channels == 1 ? 0 : 1)], rho[at(face, channels == 1 ? 0 : 2)]};
}

std::array<double, 3> RadiosityState::face_exitance(size_t face) const {
  return {exitance[at(face, 0)], exitance[at(face, channels == 1 ? 0 : 1)], exitance[at(face, channels == 1 ? 0 : 2)]};
}

std::array<double, 3> RadiosityState::rgb(const std::array<double, 3>& v) const {
  if (channels == 1) return {v[0], v[0], v[0]};
  return v;
}

std::vector<SolutionFace> RadiosityState::solution_faces(const PatchMesh& mesh) const {
  std::vector<SolutionFace> out(faces);
  for (size_t f = 0; f < faces; ++f) out[f] = {face_rho(f), face_exitance(f), radiosity(mesh, f)};
  return out;
}

}  // namespace mpath
