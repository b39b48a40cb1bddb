// Lines per box of the hierarchy (paper 3.3.1) and VP grids fitted to them.
#pragma once

#include <cstdint>
#include <vector>

#include "hierarchy.h"

namespace mpath {

// Lines traced for each box (paper 3.3.1): root_fraction of lines.total in
// the root, the rest shared by the subscenes in proportion to their grouping
// quotient (or object count), each box at least 4 lines per AR of its walls
// so that its transmittances are sampled. With no subscenes the root gets all.
// With lines.box_budget = "pilot" and `pilot` (per box, the sum of the
// squared reflected radiosities of its faces; solver/pilot.h), the root
// fraction and the subscenes' shares are chosen to make the pilot's error
// model least instead (docs/algorithm.md, "Pilot budget").
std::vector<uint64_t> box_line_budget(const Hierarchy& h, const LineOptions& lines,
                                      const std::vector<double>& pilot = {});

// The root fractions the pilot budget may choose among: at least the
// paper's 2/3 (the model, which counts only direct light, would give the
// subscenes more than pays; measured in docs/algorithm.md).
inline constexpr double kPilotRootFraction[2] = {2.0 / 3.0, 1.0};

// Coarsens the VP grids (vp_area_ratio) of boxes whose lines would cross
// each AR fewer than 8 times on average (a fine mesh and few lines), so that
// the floor of 4 lines per AR does not swell the store past lines.total.
// Fitted to the budget without the pilot whatever lines.box_budget is, so
// that the solver builds the same grids without running the pilot.
void fit_vp_grids(Hierarchy& h, const LineOptions& lines);

}  // namespace mpath
