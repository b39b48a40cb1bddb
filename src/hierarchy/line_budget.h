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
std::vector<uint64_t> box_line_budget(const Hierarchy& h, const LineOptions& lines);

// Coarsens the VP grids (vp_area_ratio) of boxes whose lines would cross
// each AR fewer than 8 times on average (a fine mesh and few lines), so that
// the floor of 4 lines per AR does not swell the store past lines.total.
void fit_vp_grids(Hierarchy& h, const LineOptions& lines);

}  // namespace mpath
