// How many lines each box of the hierarchy gets, and VP grids fitted to them.
#include "line_budget.h"

#include <algorithm>
#include <cmath>

namespace mpath {

namespace {

// The pilot budget (docs/algorithm.md, "Pilot budget"): a face's share of
// the squared error is about B^2 / R, R the lines per unit of surface of
// every box whose lines cross it (the line sets: its own box's and every
// ancestor's), whatever its area. With W_b the sum of B^2 over box b's own
// faces, rho_b = L_b / S_b (S_b: the surface of the box its lines are drawn
// over) and R_b the sum of rho over b and its ancestors, the error
// sum_b W_b / R_b is least, for a given rho_0, where W_b / R_b^2 = lambda
// S_b (a box with lines of its own whose children have theirs), that is
// R_b = max(R_parent, sqrt(W_b / (lambda S_b))), lambda such that the lines
// add up; a child that would get no lines of its own (R_child = R_b) counts
// its subtree's W in its parent's W instead. rho_0 is scanned over the root
// fractions allowed. One level deep, this is rho_b = max(0, sqrt(W_b /
// (lambda S_b)) - rho_0).
std::vector<double> pilot_lines(const Hierarchy& h, double total, const std::vector<double>& w) {
  const size_t n = h.boxes.size();
  std::vector<double> area(n), subtree(w.begin(), w.end());
  for (size_t b = 0; b < n; ++b) area[b] = line_box(h.boxes[b].bounds).surface_area();
  for (size_t b = n; b-- > 1;) subtree[static_cast<size_t>(h.boxes[b].parent)] += subtree[b];  // parents come first
  std::vector<double> best;
  double best_error = INFINITY;
  std::vector<double> want(n), reach(n), weight(n);  // lines, R and the W each box's R is fitted to
  constexpr int kSteps = 200;
  // Given rho_0 and lambda: R of every box top-down (parents before children).
  auto fit = [&](double rho0, double lambda) {
    reach[0] = rho0;
    double used = 0;
    for (size_t b = 1; b < n; ++b) {
      const SceneBox& box = h.boxes[b];
      const double above = reach[static_cast<size_t>(box.parent)];
      auto r = [&](double x, size_t k) { return std::max(above, std::sqrt(x / (lambda * area[k]))); };
      // Own W, and the subtree of each child that would not rise above this box's R.
      weight[b] = w[b];
      double rb = r(w[b], b);
      for (int c : box.children)
        if (std::sqrt(subtree[c] / (lambda * area[c])) <= rb) weight[b] += subtree[c];
      rb = r(weight[b], b);
      reach[b] = rb;
      want[b] = area[b] * (rb - above);
      used += want[b];
    }
    return used;
  };
  for (int step = 0; step <= kSteps; ++step) {
    const double fraction = kPilotRootFraction[0] + (kPilotRootFraction[1] - kPilotRootFraction[0]) * step / kSteps;
    const double root = total * fraction, rho0 = root / area[0], rest = total - root;
    double lo = 1e-300, hi = 1e300;  // fit(lo) >= rest >= fit(hi), on a log scale
    for (int k = 0; k < 200; ++k) {
      const double mid = std::sqrt(lo * hi);
      (fit(rho0, mid) > rest ? lo : hi) = mid;
    }
    fit(rho0, hi);
    want[0] = root;
    double error = 0;
    for (size_t b = 0; b < n; ++b) error += w[b] / reach[b];
    if (error < best_error) {
      best_error = error;
      best = want;
    }
  }
  // What the scan left unspent (rounding of lambda) goes to the root.
  double spent = 0;
  for (double x : best) spent += x;
  best[0] += total - spent;
  return best;
}

// Lines each box would get before the floor of 4 lines per AR.
std::vector<double> wanted_lines(const Hierarchy& h, const LineOptions& lines, const std::vector<double>& pilot) {
  const double total = static_cast<double>(lines.total);
  if (h.boxes.size() == 1) return {total};
  if (lines.box_budget == "pilot" && pilot.size() == h.boxes.size()) {
    double sub = 0;
    for (size_t b = 1; b < pilot.size(); ++b) sub += pilot[b];
    if (sub > 0 && pilot[0] > 0) return pilot_lines(h, total, pilot);
  }
  // Paper 3.3.1: root_fraction in the root, the rest by quotient (or objects)...
  const double root = total * lines.root_fraction;
  double weights = 0;
  // ("pilot" without a pilot, as when nothing emits: by quotient.)
  auto weight = [&](const SceneBox& b) { return lines.box_budget == "objects" ? double(b.objects_total) : b.quotient; };
  for (size_t b = 1; b < h.boxes.size(); ++b) weights += weight(h.boxes[b]);
  // ...but no subscene sampled more thinly than min_density times the root's
  // density (lines per unit of box surface): with many subscenes the rest
  // spread thin left them with fewer lines per area than the root. When the
  // floors ask for more lines than there are, every box is scaled down alike.
  // Transparent boxes need no floor: the root's lines carry their pairs too,
  // a subscene's lines only add to them (docs/algorithm.md).
  const double floor = h.transparent ? 0.0 : lines.min_density;
  const double root_density = root / line_box(h.boxes[0].bounds).surface_area();
  std::vector<double> want(h.boxes.size(), 0.0);
  want[0] = root;
  double sum = root;
  for (size_t b = 1; b < h.boxes.size(); ++b) {
    const double share = weights > 0 ? (total - root) * weight(h.boxes[b]) / weights : 0.0;
    want[b] = std::max(share, floor * root_density * line_box(h.boxes[b].bounds).surface_area());
    sum += want[b];
  }
  const double scale = sum > total ? total / sum : 1.0;
  for (double& w : want) w *= scale;
  return want;
}

}  // namespace

std::vector<uint64_t> box_line_budget(const Hierarchy& h, const LineOptions& lines, const std::vector<double>& pilot) {
  const std::vector<double> want = wanted_lines(h, lines, pilot);
  std::vector<uint64_t> out(h.boxes.size(), 0);
  out[0] = std::max<uint64_t>(1, static_cast<uint64_t>(std::llround(want[0])));
  for (size_t b = 1; b < h.boxes.size(); ++b)
    out[b] = std::max<uint64_t>(static_cast<uint64_t>(std::llround(want[b])), 4ull * h.boxes[b].ar_count());
  return out;
}

void fit_vp_grids(Hierarchy& h, const LineOptions& lines) {
  const std::vector<double> want = wanted_lines(h, lines, {});
  for (size_t b = 1; b < h.boxes.size(); ++b) {
    SceneBox& box = h.boxes[b];
    // Halve the finest grid until the box's lines cross each AR 8 times on average.
    while (4.0 * box.ar_count() > want[b]) {
      int finest = 0;
      for (int f = 1; f < 6; ++f)
        if (box.grid[f] > box.grid[finest]) finest = f;
      if (box.grid[finest] <= 1) break;
      const int n = box.grid[finest] / 2;
      for (int f = 0; f < 6; ++f) box.grid[f] = std::min(box.grid[f], n);
      box.set_ar_offsets();
    }
  }
}

}  // namespace mpath
