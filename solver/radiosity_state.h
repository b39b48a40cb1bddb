// Per-face radiosity state of a solve: accumulated power Phi, unshot power U,
// reflectance and emission per channel, and the energy bookkeeping.
#pragma once

#include <array>
#include <vector>

#include "mesh.h"
#include "scene.h"
#include "solution_ply.h"

namespace mpath {

// Power totals per channel (W).
struct EnergyTotals {
  std::array<double, 3> emitted{}, absorbed{}, escaped{};
};

struct RadiosityState {
  int channels = 3;  // 1 when the scene is grey
  size_t faces = 0;
  std::vector<double> rho;           // face * channels
  std::vector<double> exitance;      // face * channels, self-emitted W/m2
  std::vector<double> emitted_power; // face * channels, W
  std::vector<double> phi;           // face * channels, accumulated power W
  std::vector<double> unshot;        // face * channels, W
  // Power held in the ARs of subscene walls (docs/method.md, 7): entering
  // a box (In) and leaving it (Out), AR * channels, W; empty without subscenes.
  std::vector<double> ar_in, ar_out;
  // hierarchy.transport = "lines": unshot power already assigned to one of
  // the line sets (boxes) that carry a face's power, slot * channels, W
  // (docs/algorithm.md, "Line-set transport"); `unshot` holds what is not
  // assigned yet. Empty for the other transports.
  std::vector<double> pooled;
  EnergyTotals energy;

  size_t at(size_t face, int c) const { return face * channels + c; }
  // Unshot power, assigned or not, summed over channels.
  double unshot_total() const;
  // And per channel.
  std::array<double, 3> unshot_per_channel() const;
  // Power held in ARs, summed over channels.
  double held_total() const;
  // (unshot + held) / emitted: what the iterations have still to distribute.
  double remaining_fraction() const;
  double emitted_total() const;
  // emitted - absorbed - escaped - unshot - held, summed over channels.
  double energy_residual() const;
  // Radiosity B = Phi / A of a face in RGB (grey scenes replicate the channel).
  std::array<double, 3> radiosity(const PatchMesh& mesh, size_t face) const;
  std::array<double, 3> face_rho(size_t face) const;
  std::array<double, 3> face_exitance(size_t face) const;
  // Every face's reflectance, exitance and radiosity, as solution.ply holds them.
  std::vector<SolutionFace> solution_faces(const PatchMesh& mesh) const;
  // Per-channel sums, widened to RGB for grey scenes (each channel the same).
  std::array<double, 3> rgb(const std::array<double, 3>& per_channel) const;
};

// Sets up reflectance and emission of every face; Phi starts at the emitted
// power and U at zero (the first shot distributes the emission).
RadiosityState make_state(const Scene& scene, const PatchMesh& mesh);

}  // namespace mpath
