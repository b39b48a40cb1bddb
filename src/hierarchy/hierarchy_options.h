// Settings of the hierarchy of subscenes and of the lines traced in its boxes
// (config sections [hierarchy] and [lines]; docs/user-guide.md lists the keys).
#pragma once

#include <algorithm>
#include <string>

namespace mpath {

struct HierarchyOptions {
  double group_threshold = 0.4;  // docs/algorithm.md: a table and its legs group at about 0.4
  double vp_area_ratio = 16.0;
  int vp_grid = 0;  // 0: derived from vp_area_ratio
  // Largest subscene box, as a share of the scene box's surface area.
  double max_share = 0.5;
  int max_depth = 1;  // docs/algorithm.md: one level measured best
  // How power crosses between boxes (docs/algorithm.md): "transmittance" (the
  // paper's: lines of a box stop at its children's walls, whose virtual
  // patches and angular regions hold power with a transmittance per AR) or
  // "lines" (a box's lines see every patch inside it, children included; each
  // pair of patches is carried by the lines of the smallest box holding both).
  std::string transport = "lines";  // docs/algorithm.md: unbiased where "transmittance" is not
};

struct LineOptions {
  long long total = 1'000'000;
  double root_fraction = 0.8;  // docs/algorithm.md (the paper: 2/3)
  // How the lines are shared: root_fraction in the root and the rest by the
  // subscenes' grouping "quotient" or "objects" count (paper 3.3.1), or
  // "pilot" (solver/pilot.h, docs/algorithm.md, "Pilot budget").
  // "pilot" is the default: at equal lines it errs less than the paper's rule
  // on every measured scene with subscenes (docs/algorithm.md).
  std::string box_budget = "pilot";
  long long pilot = 0;  // local and global lines of the "pilot" budget (solver/pilot.h); 0: pilot_lines()'s default
  // The pilot's lines: `pilot` where set, but never more than a quarter of
  // the run's; by default a twentieth of the run's, at least 50,000 and at
  // most 200,000 (or a quarter of the run's, if less). A smaller pilot set
  // budgets as good as one of 200k at 250k to 2M lines on ROOM, BIG ROOM,
  // OFFICE and office2, and a first run spends its pilot's time only once
  // (docs/algorithm.md, "Pilot budget").
  long long pilot_lines() const {
    const long long quarter = std::max(1LL, total / 4);
    if (pilot > 0) return std::min(pilot, quarter);
    return std::min(quarter, std::clamp(total / 20, 50'000LL, 200'000LL));
  }
  // No subscene gets fewer lines per unit of box surface than this times
  // the root's (docs/algorithm.md).
  double min_density = 1.0;
  unsigned long long seed = 1;
  std::string sequence = "halton";  // "random" or "halton" (docs/algorithm.md)
};

}  // namespace mpath
