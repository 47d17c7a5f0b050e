#include "gen/pack.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

#include "gen/placement_grid.hpp"
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
// Each overlap is removed 1.8 times over (successive over-relaxation): with 1.0 a sand's sieve curve
// jammed at porosity 0.375 after 6000 sweeps, with 1.8 it reached 0.36 in 177 (3117 balls).
constexpr double kPush = 1.8;

// Where the balls go: the START box or periodic space cut by the range's x, y, z intervals. On a
// bounded axis (the box's, or one the range cuts) balls lie wholly inside; on a periodic one the
// centres anywhere in the period.
struct Region {
  std::array<double, 3> lo{}, hi{};
  std::array<bool, 3> bounded{};
  double volume() const { return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]); }
};

Region region_of(const Space& s, const Range& range, bool box_only) {
  Region g;
  g.lo = s.lo;
  g.hi = s.hi;
  for (int a = 0; a < 3; ++a) g.bounded[a] = !s.wraps(a);
  for (const auto& e : range) {
    using K = RangeElement::Kind;
    const int a = e.kind == K::X ? 0 : e.kind == K::Y ? 1 : e.kind == K::Z ? 2 : -1;
    if (a < 0 || e.negate) {
      if (box_only)
        throw std::runtime_error("GEN porosity: the region must be a box, given by `range x x0 x1 y y0 y1 z z0 z1` "
                                 "(or the whole space); other range kinds have no volume to fill");
      continue;
    }
    g.lo[a] = std::max(g.lo[a], e.v[0]);
    g.hi[a] = std::min(g.hi[a], e.v[1]);
    g.bounded[a] = true;
  }
  for (int a = 0; a < 3; ++a)
    if (!(g.hi[a] > g.lo[a]))
      throw std::runtime_error(fmt::format("GEN: the range leaves no room along {} ([{:g}, {:g}])", "xyz"[a], g.lo[a], g.hi[a]));
  return g;
}

// n radii, one from each of n equal slices of the number distribution (stratified: the sample's
// grading follows the distribution far closer than n independent draws), largest first.
std::vector<double> draw_radii(const SizeTable& table, std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> r(n);
  for (std::size_t k = 0; k < n; ++k)
    r[n - 1 - k] = table.radius((static_cast<double>(k) + unit(rng)) / static_cast<double>(n));
  return r;
}

bool is_inside(const Region& g, const Model& m, std::size_t k) {
  const double p[3] = {m.balls.x[k], m.balls.y[k], m.balls.z[k]};
  for (int a = 0; a < 3; ++a)
    if (g.bounded[a] && (p[a] < g.lo[a] || p[a] > g.hi[a])) return false;
  return true;
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
      if ((++tries & 4095) == 0 && interrupt_requested().load()) {
        interrupt_requested() = false;
        interrupted = true;
        return k;
      }
      double p[3];
      for (int a = 0; a < 3; ++a) {
        const double lo = g.lo[a] + (g.bounded[a] ? r : 0), hi = g.hi[a] - (g.bounded[a] ? r : 0);
        p[a] = lo + (hi - lo) * unit(rng);
      }
      if (!holds(model, q.range, {0, q.type, p[0], p[1], p[2]}) || grid.overlaps(p[0], p[1], p[2], r)) continue;
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

// Radius expansion's relaxation: the new balls (radii scale * r) are moved apart, pair by pair in a
// fixed order (Gauss-Seidel: each pair's overlap removed, shared in inverse proportion to the
// balls' volumes; the model's balls do not move), until no overlap is more than kOverlapTolerance
// of the smaller radius. Returns the sweeps taken, or -1 if the stage did not relax in `most`.
class Relaxation {
 public:
  Relaxation(const Model& model, const Region& g, std::vector<std::array<double, 4>>& balls)
      : model_(model), g_(g), balls_(balls) {
    for (std::size_t k = 0; k < model.balls.size(); ++k) fixed_rmax_ = std::max(fixed_rmax_, model.balls.rad[k]);
  }

  int relax(double scale, int most) {
    scale_ = scale;
    build();
    for (int sweep = 1; sweep <= most; ++sweep) {
      if ((sweep & 15) == 0 && interrupt_requested().load()) return -1;
      const double worst = sweep_once();
      if (worst <= kOverlapTolerance) return sweep;
      if (moved_too_far()) build();
    }
    return -1;
  }

 private:
  struct Pair { std::uint32_t i, j; double sx, sy, sz; };   // j < 0 side: fixed ball (index in model)
  void wrap() {
    const Space& s = model_.space;
    for (auto& b : balls_)
      for (int a = 0; a < 3; ++a)
        if (s.wraps(a)) {
          const double L = s.hi[a] - s.lo[a];
          b[a] -= L * std::floor((b[a] - s.lo[a]) / L);
          if (b[a] >= s.hi[a]) b[a] = s.lo[a];
        }
  }
  void build() {
    wrap();
    const std::size_t n = balls_.size(), nf = model_.balls.size();
    double rmax = fixed_rmax_, rmin = INFINITY;
    for (const auto& b : balls_) {
      rmax = std::max(rmax, scale_ * b[3]);
      rmin = std::min(rmin, scale_ * b[3]);
    }
    skin_ = 1.0 * rmin;
    // The balls counted into cells of edge >= 2 rmax + skin (so each ball's partners lie in the 27
    // cells around it), in cell order, contiguous.
    const Space& s = model_.space;
    const auto L = s.length();
    const std::size_t total = n + nf;
    double edge = (2 * rmax + skin_) * (1 + 1e-9);
    long nc[3];
    double cw[3];
    for (;;) {
      double cells = 1;
      for (int a = 0; a < 3; ++a) {
        nc[a] = std::max(1L, static_cast<long>(std::floor(L[a] / edge)) + (s.wraps(a) ? 0 : 1));
        cw[a] = s.wraps(a) ? L[a] / static_cast<double>(nc[a]) : edge;
        cells *= static_cast<double>(nc[a]);
      }
      if (cells <= 4.0 * static_cast<double>(total) + 4096) break;
      edge *= 1.25;
    }
    const Balls& fb = model_.balls;
    std::vector<std::array<double, 7>> at(total);   // wrapped x y z, r, raw - wrapped x y z
    std::vector<std::uint32_t> cell(total);
    std::vector<std::uint32_t> start(static_cast<std::size_t>(nc[0] * nc[1] * nc[2]) + 1, 0);
    auto cell_index = [&](int a, double w) {
      return std::clamp(static_cast<long>(std::floor((w - s.lo[a]) / cw[a])), 0L, nc[a] - 1);
    };
    for (std::size_t q = 0; q < total; ++q) {
      const bool fixed = q < nf;
      const double p[3] = {fixed ? fb.x[q] : balls_[q - nf][0], fixed ? fb.y[q] : balls_[q - nf][1],
                           fixed ? fb.z[q] : balls_[q - nf][2]};
      auto& e = at[q];
      e[3] = fixed ? fb.rad[q] : scale_ * balls_[q - nf][3];
      long c[3];
      for (int a = 0; a < 3; ++a) {
        double w = p[a];
        if (s.wraps(a)) {
          w -= L[a] * std::floor((w - s.lo[a]) / L[a]);
          if (w >= s.hi[a]) w = s.lo[a];
        }
        e[a] = w;
        e[4 + a] = p[a] - w;
        c[a] = cell_index(a, w);
      }
      cell[q] = static_cast<std::uint32_t>((c[2] * nc[1] + c[1]) * nc[0] + c[0]);
      ++start[cell[q] + 1];
    }
    for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
    std::vector<std::uint32_t> order(total);
    {
      std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
      for (std::size_t q = 0; q < total; ++q) order[fill[cell[q]]++] = static_cast<std::uint32_t>(q);
    }
    std::vector<std::array<double, 7>> sorted(total);
    for (std::size_t k = 0; k < total; ++k) sorted[k] = at[order[k]];
    pairs_.clear();
    fixed_pairs_.clear();
    // Each pair once: a cell's balls with the later balls of their own cell and with the 13 cells
    // after it (a half shell), the images across periodic faces included.
    auto record = [&](std::uint32_t qa, std::uint32_t qb, const std::array<double, 7>& ea,
                      const std::array<double, 7>& eb, double hx, double hy, double hz) {
      const bool fa = qa < nf, fb = qb < nf;
      if (fa && fb) return;
      // The sweep measures from each ball's own (raw) position: offsets less the periods to the image.
      if (!fa) {
        pairs_or_fixed(fb).push_back({qa - static_cast<std::uint32_t>(nf), fb ? qb : qb - static_cast<std::uint32_t>(nf),
                                      eb[4] - hx - ea[4], eb[5] - hy - ea[5], eb[6] - hz - ea[6]});
      } else {
        fixed_pairs_.push_back({qb - static_cast<std::uint32_t>(nf), qa, ea[4] + hx - eb[4], ea[5] + hy - eb[5],
                                ea[6] + hz - eb[6]});
      }
    };
    for (long z = 0; z < nc[2]; ++z)
      for (long y = 0; y < nc[1]; ++y)
        for (long x = 0; x < nc[0]; ++x) {
          const std::size_t here = static_cast<std::size_t>((z * nc[1] + y) * nc[0] + x);
          for (std::uint32_t ka = start[here]; ka < start[here + 1]; ++ka) {
            const auto& ea = sorted[ka];
            for (int o = 0; o < 14; ++o) {   // o = 0: the own cell; then the half shell
              const long oz = o == 0 ? 0 : (o - 1) < 9 ? 1 : 0;
              const long oy = o == 0 ? 0 : (o - 1) < 9 ? (o - 1) / 3 - 1 : (o - 1) < 12 ? 1 : 0;
              const long ox = o == 0 ? 0 : (o - 1) < 9 ? (o - 1) % 3 - 1 : (o - 1) < 12 ? (o - 10) - 1 : 1;
              long cz = z + oz, cy = y + oy, cx = x + ox, kz = 0, ky = 0, kx = 0;
              if (s.wraps(2)) { kz = cz >= nc[2] ? 1 : 0; cz -= kz * nc[2]; }
              else if (cz >= nc[2]) continue;
              if (s.wraps(1)) { ky = cy < 0 ? -1 : cy >= nc[1] ? 1 : 0; cy -= ky * nc[1]; }
              else if (cy < 0 || cy >= nc[1]) continue;
              if (s.wraps(0)) { kx = cx < 0 ? -1 : cx >= nc[0] ? 1 : 0; cx -= kx * nc[0]; }
              else if (cx < 0 || cx >= nc[0]) continue;
              const double hx = static_cast<double>(kx) * L[0], hy = static_cast<double>(ky) * L[1],
                           hz = static_cast<double>(kz) * L[2];
              const std::size_t slot = static_cast<std::size_t>((cz * nc[1] + cy) * nc[0] + cx);
              for (std::uint32_t kb = o == 0 ? ka + 1 : start[slot]; kb < start[slot + 1]; ++kb) {
                if (o != 0 && kb == ka) continue;   // a ball and its own image: never within reach
                const auto& eb = sorted[kb];
                const double dx = eb[0] + hx - ea[0], dy = eb[1] + hy - ea[1], dz = eb[2] + hz - ea[2];
                const double reach = ea[3] + eb[3] + skin_;
                if (dx * dx + dy * dy + dz * dz >= reach * reach) continue;
                record(order[ka], order[kb], ea, eb, hx, hy, hz);
              }
            }
          }
        }
    at_build_.resize(n);
    for (std::size_t i = 0; i < n; ++i) at_build_[i] = {balls_[i][0], balls_[i][1], balls_[i][2]};
  }
  bool moved_too_far() const {
    const double most = 0.25 * skin_ * skin_;
    for (std::size_t i = 0; i < balls_.size(); ++i) {
      const double dx = balls_[i][0] - at_build_[i][0], dy = balls_[i][1] - at_build_[i][1],
                   dz = balls_[i][2] - at_build_[i][2];
      if (dx * dx + dy * dy + dz * dz > most) return true;
    }
    return false;
  }
  // One pass over the pairs; returns the largest overlap met, over the smaller radius.
  double sweep_once() {
    double worst = 0;
    const Balls& fb = model_.balls;
    for (const auto& p : pairs_) {
      auto& a = balls_[p.i];
      auto& b = balls_[p.j];
      const double ra = scale_ * a[3], rb = scale_ * b[3];
      double dx = b[0] - p.sx - a[0], dy = b[1] - p.sy - a[1], dz = b[2] - p.sz - a[2];
      const double d2 = dx * dx + dy * dy + dz * dz, reach = ra + rb;
      if (d2 >= reach * reach) continue;
      double d = std::sqrt(d2);
      if (d == 0) { dx = 1; d = 1; dy = dz = 0; }   // one centre: apart along x
      const double overlap = reach - (d2 == 0 ? 0 : d);
      worst = std::max(worst, overlap / std::min(ra, rb));
      const double va = ra * ra * ra, vb = rb * rb * rb, push = kPush * overlap / d;
      const double move_a = push * vb / (va + vb), move_b = push * va / (va + vb);
      a[0] -= move_a * dx; a[1] -= move_a * dy; a[2] -= move_a * dz;
      b[0] += move_b * dx; b[1] += move_b * dy; b[2] += move_b * dz;
    }
    for (const auto& p : fixed_pairs_) {
      auto& a = balls_[p.i];
      const double ra = scale_ * a[3], rb = fb.rad[p.j];
      double dx = fb.x[p.j] - p.sx - a[0], dy = fb.y[p.j] - p.sy - a[1], dz = fb.z[p.j] - p.sz - a[2];
      const double d2 = dx * dx + dy * dy + dz * dz, reach = ra + rb;
      if (d2 >= reach * reach) continue;
      double d = std::sqrt(d2);
      if (d == 0) { dx = 1; d = 1; dy = dz = 0; }
      const double overlap = reach - (d2 == 0 ? 0 : d);
      worst = std::max(worst, overlap / std::min(ra, rb));
      const double move = kPush * overlap / d;
      a[0] -= move * dx; a[1] -= move * dy; a[2] -= move * dz;
    }
    // Whole balls inside the region's bounded faces, a face's overlap over-relaxed as a pair's (a plain
    // clamp left boxes of a sand stalling at porosity 0.42, where the periodic cell reached 0.38).
    for (auto& b : balls_) {
      const double r = scale_ * b[3];
      for (int a = 0; a < 3; ++a) {
        if (!g_.bounded[a]) continue;
        const double lo = g_.lo[a] + r, hi = g_.hi[a] - r;
        if (b[a] < lo) b[a] = lo + (kPush - 1) * (lo - b[a]);
        else if (b[a] > hi) b[a] = hi - (kPush - 1) * (b[a] - hi);
        b[a] = std::clamp(b[a], lo, hi);
      }
    }
    return worst;
  }

  std::vector<Pair>& pairs_or_fixed(bool fixed) { return fixed ? fixed_pairs_ : pairs_; }
  const Model& model_;
  const Region& g_;
  std::vector<std::array<double, 4>>& balls_;
  double fixed_rmax_ = 0, scale_ = 1, skin_ = 0;
  std::vector<Pair> pairs_, fixed_pairs_;
  std::vector<std::array<double, 3>> at_build_;
};

}  // namespace

PackResult pack(const Model& model, const PackRequest& q) {
  PackResult out;
  const SizeTable table(q.sizes);
  std::mt19937_64 rng(q.seed);
  const Space& s = model.space;
  const bool target = q.count == 0;
  const Region g = region_of(s, q.range, target);
  double fixed_volume = 0;   // of the model's balls in the region
  double rmax_fixed = 0;
  for (std::size_t k = 0; k < model.balls.size(); ++k) {
    rmax_fixed = std::max(rmax_fixed, model.balls.rad[k]);
    if (is_inside(g, model, k)) fixed_volume += kFourThirdsPi * std::pow(model.balls.rad[k], 3);
  }
  std::size_t n = q.count;
  double solid = 0;   // volume the new balls must have (porosity)
  if (target) {
    if (!(q.porosity > 0 && q.porosity < 1))
      throw std::runtime_error(fmt::format("GEN: porosity {:g} is not between 0 and 1", q.porosity));
    out.volume = g.volume();
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
    if (sum > kDensestEqual * g.volume())
      throw std::runtime_error(fmt::format("GEN: {} balls of these sizes (solid volume {:.4g}) cannot fit in the region "
                                           "(volume {:.4g}): their porosity would be {:.4g}",
                                           n, sum, g.volume(), 1 - sum / g.volume()));
  }
  const double rmax = radii.front();
  for (int a = 0; a < 3; ++a) {
    const double L = g.hi[a] - g.lo[a];
    if (g.bounded[a] && 2 * rmax > L)
      throw std::runtime_error(fmt::format("GEN: a ball of diameter {:g} does not fit in the region along {} ({:g})",
                                           2 * rmax, "xyz"[a], L));
    if (!g.bounded[a] && target && 4 * rmax > L)
      throw std::runtime_error(fmt::format("GEN: the periodic edge {} = {:g} is less than twice the largest diameter "
                                           "{:g} (CYCLE would refuse the cell)", "xyz"[a], L, 2 * rmax));
  }
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
    if (interrupt_requested().load()) {
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
  out.porosity = 1 - (fixed_volume + new_volume) / out.volume;
  return out;
}

}  // namespace trubal
