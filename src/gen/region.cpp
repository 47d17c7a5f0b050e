#include "gen/region.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace trubal {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// volume(): lines per side of the grid (see region.hpp for the accuracy).
constexpr int kLines = 2048;

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

struct Interval {
  double lo = -kInf, hi = kInf;
  bool empty() const { return !(hi > lo); }
  void cut(const Interval& o) { lo = std::max(lo, o.lo); hi = std::min(hi, o.hi); }
};

// Where lo <= s0 + t ds <= hi along t.
Interval slab(double s0, double ds, double lo, double hi) {
  if (ds == 0) return s0 >= lo && s0 <= hi ? Interval{} : Interval{0, 0};
  double a = (lo - s0) / ds, b = (hi - s0) / ds;
  if (a > b) std::swap(a, b);
  return {a, b};
}

// Where A t^2 + 2 B t + C <= 0 along t (A >= 0): the roots taken in the form that keeps its digits.
Interval within_quadratic(double A, double B, double C) {
  if (A < 1e-30) return C <= 0 ? Interval{} : Interval{0, 0};
  const double disc = B * B - A * C;
  if (disc < 0) return {0, 0};
  const double q = -(B + std::copysign(std::sqrt(disc), B));
  if (q == 0) return {0, 0};
  double a = q / A, b = C / q;
  if (a > b) std::swap(a, b);
  return {a, b};
}

// A cylinder wall's solid (within its radius, along its length) on the line at + t e_axis.
Interval cylinder_on_line(const Wall& w, int axis, const Vec3& at) {
  const Vec3 rel = {at[0] - w.point[0], at[1] - w.point[1], at[2] - w.point[2]};
  const Vec3& d = w.normal;
  const double s0 = dot(rel, d), ds = d[axis];
  Interval in = slab(s0, ds, 0, w.length);
  if (in.empty()) return in;
  // |w0 + t u|^2 <= R^2, w0 the part of rel across the axis, u that of e_axis.
  const Vec3 w0 = {rel[0] - s0 * d[0], rel[1] - s0 * d[1], rel[2] - s0 * d[2]};
  Vec3 u = {-ds * d[0], -ds * d[1], -ds * d[2]};
  u[axis] += 1;
  in.cut(within_quadratic(dot(u, u), dot(w0, u), dot(w0, w0) - w.radius * w.radius));
  return in;
}

// The length of the line at + t e_axis, t in [lo, hi] of the axis, inside the region.
double line_length(const Region& g, int axis, const Vec3& at, const Vec3& lo, const Vec3& hi,
                   std::vector<Interval>& excluded) {
  Interval in{lo[axis], hi[axis]};
  for (const auto& c : g.cylinders) {
    const double dx = at[0] - c[0], dy = at[1] - c[1];
    if (axis == 2) {
      if (dx * dx + dy * dy > c[2] * c[2]) return 0;
    } else {
      const double across = axis == 0 ? dy : dx, h2 = c[2] * c[2] - across * across;
      if (h2 < 0) return 0;
      const double mid = c[axis], h = std::sqrt(h2);
      in.cut({mid - h, mid + h});
    }
  }
  excluded.clear();
  for (const Wall& w : g.walls) {
    if (in.empty()) return 0;
    switch (w.kind) {
      case WallKind::Plane: {
        const double k = w.normal[axis];
        const double m = dot(w.normal, {at[0] - w.point[0], at[1] - w.point[1], at[2] - w.point[2]});
        if (k == 0) {
          if (m < 0) return 0;
        } else if (k > 0) {
          in.cut({-m / k, kInf});
        } else {
          in.cut({-kInf, -m / k});
        }
        break;
      }
      case WallKind::Cylinder: {
        const Interval solid = cylinder_on_line(w, axis, at);
        if (w.inside) in.cut(solid);
        else if (!solid.empty()) excluded.push_back(solid);
        break;
      }
      case WallKind::Polygon: break;   // a sheet: no volume
    }
  }
  if (in.empty()) return 0;
  double length = in.hi - in.lo;
  if (excluded.empty()) return length;
  std::sort(excluded.begin(), excluded.end(), [](const Interval& p, const Interval& q) { return p.lo < q.lo; });
  double covered_to = in.lo;
  for (Interval e : excluded) {
    e.cut({std::max(in.lo, covered_to), in.hi});
    if (e.empty()) continue;
    length -= e.hi - e.lo;
    covered_to = e.hi;
  }
  return length;
}

void push_off(Vec3& c, const Vec3& dir, double by) {
  for (int a = 0; a < 3; ++a) c[a] -= dir[a] * by;
}

// Moves the point (dx, dy) across an axis to within `most` of it, an excess moved `push` times over.
void pull_toward_axis(double& dx, double& dy, double most, double push) {
  const double rho = std::sqrt(dx * dx + dy * dy);
  if (!(rho > most)) return;
  const double to = std::clamp(most - (push - 1) * (rho - most), 0.0, most);
  dx *= to / rho;
  dy *= to / rho;
}

}  // namespace

bool clear_of_walls(const std::vector<Wall>& walls, const Vec3& c, double r) {
  for (const Wall& w : walls)
    if (wall_clearance(w, c, r).gap < 0) return false;
  return true;
}

bool Region::admits(const Vec3& c, double r) const {
  for (const auto& cyl : cylinders) {
    const double dx = c[0] - cyl[0], dy = c[1] - cyl[1], most = cyl[2] - r;
    if (most < 0 || dx * dx + dy * dy > most * most) return false;
  }
  return clear_of_walls(walls, c, r);
}

bool Region::holds_centre(const Vec3& c) const {
  for (int a = 0; a < 3; ++a)
    if (bounded[a] && (c[a] < lo[a] || c[a] > hi[a])) return false;
  for (const auto& cyl : cylinders) {
    const double dx = c[0] - cyl[0], dy = c[1] - cyl[1];
    if (dx * dx + dy * dy > cyl[2] * cyl[2]) return false;
  }
  for (const Wall& w : walls)
    if (wall_clearance(w, c, 0).wrong_side) return false;
  return true;
}

void Region::push_inside(std::array<double, 4>& b, double r, double push) const {
  Vec3 c = {b[0], b[1], b[2]};
  for (const auto& cyl : cylinders) {
    double dx = c[0] - cyl[0], dy = c[1] - cyl[1];
    pull_toward_axis(dx, dy, cyl[2] - r, push);
    c[0] = cyl[0] + dx;
    c[1] = cyl[1] + dy;
  }
  for (const Wall& w : walls) {
    if (w.kind == WallKind::Cylinder && w.inside) {   // along its length and within its radius, apart
      const Vec3 rel = {c[0] - w.point[0], c[1] - w.point[1], c[2] - w.point[2]};
      double s = dot(rel, w.normal);
      const Vec3 across = {rel[0] - s * w.normal[0], rel[1] - s * w.normal[1], rel[2] - s * w.normal[2]};
      const double rho = std::sqrt(dot(across, across)), most = std::max(0.0, w.radius - r);
      double f = 1;
      if (rho > most) f = std::clamp(most - (push - 1) * (rho - most), 0.0, most) / rho;
      if (s < 0) s = std::min(w.length, (push - 1) * -s);
      else if (s > w.length) s = std::max(0.0, w.length - (push - 1) * (s - w.length));
      for (int a = 0; a < 3; ++a) c[a] = w.point[a] + s * w.normal[a] + f * across[a];
      continue;
    }
    const WallTouch t = wall_touch(w, c);
    if (t.gap < r) push_off(c, t.dir, push * (r - t.gap));
  }
  for (int a = 0; a < 3; ++a) {
    if (bounded[a]) c[a] = std::clamp(c[a], lo[a] + r, hi[a] - r);
    b[a] = c[a];
  }
}

double Region::excess(const std::array<double, 4>& b, double r) const {
  const Vec3 c = {b[0], b[1], b[2]};
  double most = 0;
  for (int a = 0; a < 3; ++a)
    if (bounded[a]) most = std::max({most, lo[a] + r - c[a], c[a] - (hi[a] - r)});
  for (const auto& cyl : cylinders) {
    const double dx = c[0] - cyl[0], dy = c[1] - cyl[1];
    most = std::max(most, std::sqrt(dx * dx + dy * dy) - (cyl[2] - r));
  }
  for (const Wall& w : walls) {
    const WallClearance k = wall_clearance(w, c, r);
    // A container's ball past an end is as far out as its centre is past it.
    most = std::max(most, k.beyond_end > 0 ? k.beyond_end : -k.gap);
  }
  return most / r;
}

double Region::volume() const {
  // Planes across an axis and the bounding boxes of cylinders (the range's, containers) narrow the
  // box exactly; whatever else cuts it is integrated.
  Vec3 elo = lo, ehi = hi;
  bool box = cylinders.empty();
  int axis = 2;   // the lines along the first container's axis (its boundary then cuts no line)
  bool axis_chosen = false;
  for (const Wall& w : walls) {
    const Vec3& n = w.normal;
    if (w.kind == WallKind::Plane) {
      int along = 0, zeros = 0;
      for (int a = 0; a < 3; ++a) {
        if (n[a] == 0) ++zeros;
        else along = a;
      }
      if (zeros == 2) {
        if (n[along] > 0) elo[along] = std::max(elo[along], w.point[along]);
        else ehi[along] = std::min(ehi[along], w.point[along]);
      } else {
        box = false;
      }
    } else if (w.kind == WallKind::Cylinder) {
      box = false;
      if (!axis_chosen) {
        for (int a = 0; a < 3; ++a)
          if (std::abs(n[a]) > std::abs(n[axis])) axis = a;
        axis_chosen = true;
      }
      if (!w.inside) continue;
      for (int a = 0; a < 3; ++a) {
        const double e0 = w.point[a], e1 = w.point[a] + w.length * n[a];
        const double reach = w.radius * std::sqrt(std::max(0.0, 1 - n[a] * n[a]));
        elo[a] = std::max(elo[a], std::min(e0, e1) - reach);
        ehi[a] = std::min(ehi[a], std::max(e0, e1) + reach);
      }
    }
  }
  for (const auto& c : cylinders)
    for (int a = 0; a < 2; ++a) {
      elo[a] = std::max(elo[a], c[a] - c[2]);
      ehi[a] = std::min(ehi[a], c[a] + c[2]);
    }
  for (int a = 0; a < 3; ++a)
    if (!(ehi[a] > elo[a])) return 0;
  if (box) return (ehi[0] - elo[0]) * (ehi[1] - elo[1]) * (ehi[2] - elo[2]);
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  const double hb = (ehi[b] - elo[b]) / kLines, hc = (ehi[c] - elo[c]) / kLines;
  std::vector<Interval> excluded;
  excluded.reserve(walls.size());
  double sum = 0;
  for (int i = 0; i < kLines; ++i) {
    double row = 0;
    Vec3 at{};
    at[c] = elo[c] + (i + 0.5) * hc;
    for (int j = 0; j < kLines; ++j) {
      at[b] = elo[b] + (j + 0.5) * hb;
      row += trubal::line_length(*this, axis, at, elo, ehi, excluded);
    }
    sum += row;
  }
  return sum * hb * hc;
}

Region region_of(const Space& s, const Range& range, const std::vector<Wall>& walls, bool box_only) {
  Region g;
  g.lo = s.lo;
  g.hi = s.hi;
  g.walls = walls;
  for (int a = 0; a < 3; ++a) g.bounded[a] = !s.wraps(a);
  for (const auto& e : range) {
    using K = RangeElement::Kind;
    const int a = e.kind == K::X ? 0 : e.kind == K::Y ? 1 : e.kind == K::Z ? 2 : -1;
    if (e.kind == K::Cylinder && !e.negate) {
      g.cylinders.push_back({e.v[0], e.v[1], e.v[2]});
      continue;
    }
    if (a < 0 || e.negate) {
      if (box_only)
        throw std::runtime_error("GEN porosity: the region must be a box (`range x x0 x1 y y0 y1 z z0 z1`), a "
                                 "cylinder about a line along z (`range cylinder x y r`, with `z z0 z1`) or both, or "
                                 "the whole space; other range kinds have no volume to fill");
      continue;
    }
    g.lo[a] = std::max(g.lo[a], e.v[0]);
    g.hi[a] = std::min(g.hi[a], e.v[1]);
    g.bounded[a] = true;
  }
  for (int a = 0; a < 3; ++a)
    if (!(g.hi[a] > g.lo[a]))
      throw std::runtime_error(fmt::format("GEN: the range leaves no room along {} ([{:g}, {:g}])", "xyz"[a], g.lo[a], g.hi[a]));
  for (const auto& c : g.cylinders)
    if (!(c[2] > 0)) throw std::runtime_error(fmt::format("GEN: the range's cylinder has radius {:g}", c[2]));
  return g;
}

double room_for_centres(const Space& s, const Range& range, const std::vector<Wall>& walls, double rmax) {
  Region g;
  g.lo = s.lo;
  g.hi = s.hi;
  g.walls = walls;
  for (const auto& e : range) {
    using K = RangeElement::Kind;
    if (e.negate) continue;
    if (e.kind == K::Cylinder) g.cylinders.push_back({e.v[0], e.v[1], e.v[2] + rmax});
    const int a = e.kind == K::X ? 0 : e.kind == K::Y ? 1 : e.kind == K::Z ? 2 : -1;
    if (a < 0) continue;
    g.lo[a] = std::max(g.lo[a], e.v[0] - rmax);
    g.hi[a] = std::min(g.hi[a], e.v[1] + rmax);
  }
  return g.volume();
}

}  // namespace trubal
