#include "gen/pack.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

#include "gen/placement_grid.hpp"
#include "gen/region.hpp"
#include "gen/relaxation.hpp"
#include "interp/signals.hpp"

namespace trubal {

namespace {

constexpr double kFourThirdsPi = 4.0 / 3.0 * std::numbers::pi;
// As GEN n rlo rhi: give up on a ball after this many failed tries in a row.
constexpr std::size_t kFailuresInARow = 200000;
// Random sequential placing fills a space to a solid fraction of about 0.38 for equal spheres;
// radius expansion starts the balls well below that.
constexpr double kStartFraction = 0.25;
// The densest packing of equal spheres, pi / sqrt(18) (Hales).
constexpr double kDensestEqual = 0.74048;

// n radii, one from each of n equal slices of the number distribution (stratified: the sample's
// grading follows the distribution far closer than n independent draws), largest first.
std::vector<double> draw_radii(const SizeTable& table, std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> r(n);
  for (std::size_t k = 0; k < n; ++k)
    r[n - 1 - k] = table.radius((static_cast<double>(k) + unit(rng)) / static_cast<double>(n));
  return r;
}

// Places balls of radii scale * r (largest first) at random where they overlap nothing in the grid
// (which holds the model's balls). Stops at a ball that finds no room in kFailuresInARow tries.
std::size_t place(const Model& model, const Region& g, const PackRequest& q, PlacementGrid& grid, double scale,
                  std::vector<std::array<double, 4>>& balls, std::mt19937_64& rng, bool& interrupted) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::size_t tries = 0;
  for (std::size_t k = 0; k < balls.size(); ++k) {
    const double r = scale * balls[k][3];
    bool placed = false;
    for (std::size_t failures = 0; failures < kFailuresInARow; ++failures) {
      if ((++tries & 4095) == 0 && interrupt_now()) {
        interrupt_requested() = false;
        interrupted = true;
        return k;
      }
      double p[3];
      for (int a = 0; a < 3; ++a) {
        const double lo = g.lo[a] + (g.bounded[a] ? r : 0), hi = g.hi[a] - (g.bounded[a] ? r : 0);
        p[a] = lo + (hi - lo) * unit(rng);
      }
      if (!holds(model, q.range, {0, q.type, p[0], p[1], p[2]}) || !g.admits({p[0], p[1], p[2]}, r) ||
          grid.overlaps(p[0], p[1], p[2], r))
        continue;
      grid.insert(p[0], p[1], p[2], r);
      balls[k][0] = p[0];
      balls[k][1] = p[1];
      balls[k][2] = p[2];
      placed = true;
      break;
    }
    if (!placed) return k;
  }
  return balls.size();
}


}  // namespace

PackResult pack(const Model& model, const PackRequest& q) {
  PackResult out;
  const SizeTable table(q.sizes);
  std::mt19937_64 rng(q.seed);
  const Space& s = model.space;
  const bool target = q.count == 0;
  const Region g = region_of(s, q.range, model.walls, target);
  double fixed_volume = 0;   // of the model's balls in the region
  double rmax_fixed = 0;
  for (std::size_t k = 0; k < model.balls.size(); ++k) {
    rmax_fixed = std::max(rmax_fixed, model.balls.rad[k]);
    if (g.holds_centre({model.balls.x[k], model.balls.y[k], model.balls.z[k]})) fixed_volume += kFourThirdsPi * std::pow(model.balls.rad[k], 3);
  }
  std::size_t n = q.count;
  double solid = 0;   // volume the new balls must have (porosity)
  if (target) {
    if (!(q.porosity > 0 && q.porosity < 1))
      throw std::runtime_error(fmt::format("GEN: porosity {:g} is not between 0 and 1", q.porosity));
    out.volume = g.volume();
    if (!(out.volume > 0))
      throw std::runtime_error("GEN: the region has no volume on the walls' side (the balls' side of every plane, "
                               "inside a container cylinder, outside an outside one)");
    solid = (1 - q.porosity) * out.volume - fixed_volume;
    if (!(solid > 0))
      throw std::runtime_error(fmt::format("GEN: the region's balls already leave a porosity of {:.4g}, below {:g}",
                                           1 - fixed_volume / out.volume, q.porosity));
    if (table.largest() <= table.smallest() * (1 + 1e-9) && 1 - q.porosity > kDensestEqual)
      throw std::runtime_error(fmt::format(
          "GEN: porosity {:g} cannot be reached with balls of one size: the densest packing of equal spheres has "
          "porosity 0.2595", q.porosity));
    const double count = std::round(solid / table.mean_volume());
    if (count < 1)
      throw std::runtime_error(fmt::format("GEN: the region (volume {:.4g}) is too small for porosity {:g}: it needs "
                                           "a solid volume of {:.4g}, less than one ball of mean volume {:.4g}",
                                           out.volume, q.porosity, solid, table.mean_volume()));
    if (count > 1e8)
      throw std::runtime_error(fmt::format("GEN: porosity {:g} needs {:.3g} balls, more than 100,000,000", q.porosity, count));
    n = static_cast<std::size_t>(count);
  }
  out.asked = n;
  std::vector<double> radii = draw_radii(table, n, rng);
  if (target) {   // the solid volume exactly: every radius scaled alike (by about 1 +- 1e-3)
    double sum = 0;
    for (double r : radii) sum += kFourThirdsPi * r * r * r;
    const double f = std::cbrt(solid / sum);
    for (double& r : radii) r *= f;
  } else {
    double sum = 0;
    for (double r : radii) sum += kFourThirdsPi * r * r * r;
    const double volume = g.volume();
    if (sum > kDensestEqual * volume)
      throw std::runtime_error(fmt::format("GEN: {} balls of these sizes (solid volume {:.4g}) cannot fit in the region "
                                           "(volume {:.4g}{}): their porosity would be {:.4g}",
                                           n, sum, volume, g.walls.empty() ? "" : ", on the walls' side",
                                           1 - sum / volume));
  }
  const double rmax = radii.front();
  for (int a = 0; a < 3; ++a) {
    const double L = g.hi[a] - g.lo[a];
    if (g.bounded[a] && 2 * rmax > L)
      throw std::runtime_error(fmt::format("GEN: a ball of diameter {:g} does not fit in the region along {} ({:g})",
                                           2 * rmax, "xyz"[a], L));
    if (!g.bounded[a] && 4 * rmax > L)
      throw std::runtime_error(fmt::format("GEN: the periodic edge {} = {:g} is less than twice the largest diameter "
                                           "{:g} (CYCLE would refuse the cell)", "xyz"[a], L, 2 * rmax));
  }
  for (const auto& c : g.cylinders)
    if (rmax > c[2])
      throw std::runtime_error(fmt::format("GEN: a ball of diameter {:g} does not fit in the range's cylinder (diameter "
                                           "{:g})", 2 * rmax, 2 * c[2]));
  for (const Wall& w : g.walls)
    if (w.kind == WallKind::Cylinder && w.inside && rmax > w.radius)
      throw std::runtime_error(fmt::format("GEN: a ball of diameter {:g} does not fit in cylinder wall {} (diameter {:g})",
                                           2 * rmax, w.id, 2 * w.radius));
  out.balls.resize(n);
  for (std::size_t k = 0; k < n; ++k) out.balls[k] = {0, 0, 0, radii[k]};

  // Placed small: at a solid fraction of kStartFraction at most (full size when the target is looser).
  double fraction = 1;   // the new balls' volume now over their final volume: the scale cubed
  if (target) fraction = std::min(1.0, kStartFraction * out.volume / solid);
  PlacementGrid grid(s, std::max(rmax_fixed, std::cbrt(fraction) * rmax), model.balls.size() + n);
  for (std::size_t k = 0; k < model.balls.size(); ++k)
    grid.insert(model.balls.x[k], model.balls.y[k], model.balls.z[k], model.balls.rad[k]);
  const std::size_t placed = place(model, g, q, grid, std::cbrt(fraction), out.balls, rng, out.interrupted);
  if (placed < n) {
    out.balls.resize(placed);
    if (target && !out.interrupted)
      throw std::runtime_error(fmt::format("GEN: no room to place the balls of porosity {:g} even at {:.0f}% of their "
                                           "volume ({} of {} placed): the region is too full",
                                           q.porosity, 100 * fraction, placed, n));
  }
  if (!target || out.interrupted) {
    if (target) for (auto& b : out.balls) b[3] *= std::cbrt(fraction);
    return out;
  }

  // Relaxed in space order (cells of the largest diameter, z slowest), so that a ball's partners lie
  // near it in memory (largest first, 200,000 balls relaxed 4x slower); put back after.
  std::vector<std::size_t> order(out.balls.size());
  {
    const double cell = 2 * rmax;
    std::vector<std::array<std::int64_t, 3>> key(out.balls.size());
    for (std::size_t k = 0; k < out.balls.size(); ++k) {
      for (int a = 0; a < 3; ++a)
        key[k][2 - a] = static_cast<std::int64_t>(std::floor((out.balls[k][a] - s.lo[a]) / cell));
      order[k] = k;
    }
    std::stable_sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) { return key[p] < key[q]; });
    std::vector<std::array<double, 4>> spatial(out.balls.size());
    for (std::size_t k = 0; k < order.size(); ++k) spatial[k] = out.balls[order[k]];
    out.balls.swap(spatial);
  }
  // Grown in stages of the volume fraction, each relaxed; a stage that does not relax is taken back
  // and retried with half the step.
  Relaxation relaxation(model, g, out.balls);
  double step = 0.1;
  std::vector<std::array<double, 4>> good = out.balls;
  while (fraction < 1) {
    const double next = std::min(1.0, fraction + step);
    const int most = static_cast<int>(std::min<std::int64_t>(kStageSweeps, kTotalSweeps - out.sweeps));
    const int took = most > 0 ? relaxation.relax(std::cbrt(next), most) : -1;
    ++out.stages;
    out.sweeps += took > 0 ? took : most;
    if (interrupt_now()) {
      interrupt_requested() = false;
      out.interrupted = true;
      out.balls = good;
      break;
    }
    if (took > 0) {
      fraction = next;
      good = out.balls;
      step = std::min(0.1, 1.5 * step);
      continue;
    }
    out.balls = good;
    step *= 0.5;
    if (step < 1e-3 || out.sweeps >= kTotalSweeps) {
      out.reached = false;
      break;
    }
  }
  {
    std::vector<std::array<double, 4>> largest_first(out.balls.size());
    for (std::size_t k = 0; k < order.size(); ++k) largest_first[order[k]] = out.balls[k];
    out.balls.swap(largest_first);
  }
  const double scale = std::cbrt(fraction);
  double new_volume = 0;
  for (auto& b : out.balls) {
    for (int a = 0; a < 3; ++a)   // into the period, as CYCLE keeps centres
      if (s.wraps(a)) {
        const double L = s.hi[a] - s.lo[a];
        b[a] -= L * std::floor((b[a] - s.lo[a]) / L);
        if (b[a] >= s.hi[a]) b[a] = s.lo[a];
      }
    b[3] *= scale;
    new_volume += kFourThirdsPi * b[3] * b[3] * b[3];
  }
  // The last stage left a ball across a cylinder or wall by at most kOverlapTolerance of its radius:
  // moved clear, a hair inside, so that none starts across one.
  if (g.curved())
    for (auto& b : out.balls)
      for (int k = 0; k < 100 && g.excess(b, b[3]) > 0; ++k) g.push_inside(b, b[3] * (1 + 1e-9), 1.0);
  out.porosity = 1 - (fixed_volume + new_volume) / out.volume;
  return out;
}

}  // namespace trubal
