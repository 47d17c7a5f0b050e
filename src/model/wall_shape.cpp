#include "model/wall_shape.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace trubal {
namespace {

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

// Some unit vector perpendicular to unit a.
Vec3 perpendicular(const Vec3& a) {
  const Vec3 t = std::abs(a[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 p = cross(a, t);
  return scale(p, 1 / norm(p));
}

// Nearest point to c on segment [a, b].
Vec3 nearest_on_segment(const Vec3& c, const Vec3& a, const Vec3& b) {
  const Vec3 ab = sub(b, a);
  const double len2 = dot(ab, ab);
  const double s = len2 > 0 ? std::clamp(dot(sub(c, a), ab) / len2, 0.0, 1.0) : 0.0;
  return add(a, scale(ab, s));
}

// Whether q (in the polygon's plane) is inside it: crossings of a ray in the plane's 2D frame.
bool inside_polygon(const Wall& w, const Vec3& q) {
  const Vec3 u = perpendicular(w.normal), v = cross(w.normal, u);
  const double qu = dot(q, u), qv = dot(q, v);
  bool in = false;
  const std::size_t n = w.vertices.size();
  for (std::size_t k = 0, l = n - 1; k < n; l = k++) {
    const double au = dot(w.vertices[k], u), av = dot(w.vertices[k], v);
    const double bu = dot(w.vertices[l], u), bv = dot(w.vertices[l], v);
    if ((av > qv) != (bv > qv) && qu < (bu - au) * (qv - av) / (bv - av) + au) in = !in;
  }
  return in;
}

WallTouch towards(const Vec3& c, const Vec3& p, const Vec3& fallback) {
  WallTouch t;
  const Vec3 d = sub(p, c);
  t.gap = norm(d);
  t.dir = t.gap > 0 ? scale(d, 1 / t.gap) : fallback;
  return t;
}

// Rotates v about unit axis k by angle a (Rodrigues).
Vec3 rotate(const Vec3& v, const Vec3& k, double a) {
  const double cs = std::cos(a), sn = std::sin(a);
  const Vec3 kv = cross(k, v);
  const double kd = dot(k, v) * (1 - cs);
  return {v[0] * cs + kv[0] * sn + k[0] * kd, v[1] * cs + kv[1] * sn + k[1] * kd, v[2] * cs + kv[2] * sn + k[2] * kd};
}

}  // namespace

const char* wall_kind_name(WallKind kind) {
  switch (kind) {
    case WallKind::Plane: return "plane";
    case WallKind::Polygon: return "polygon";
    case WallKind::Cylinder: return "cylinder";
  }
  return "?";
}

WallTouch wall_touch(const Wall& w, const Vec3& c) {
  switch (w.kind) {
    case WallKind::Plane: {
      WallTouch t;
      t.gap = dot(sub(c, w.point), w.normal);
      t.dir = scale(w.normal, -1);
      return t;
    }
    case WallKind::Polygon: {
      const double h = dot(sub(c, w.point), w.normal);
      const Vec3 side = scale(w.normal, h >= 0 ? -1.0 : 1.0);   // toward the plane
      const Vec3 q = sub(c, scale(w.normal, h));
      if (inside_polygon(w, q)) {
        WallTouch t;
        t.gap = std::abs(h);
        t.dir = side;
        return t;
      }
      Vec3 best{};
      double best2 = std::numeric_limits<double>::infinity();
      const std::size_t n = w.vertices.size();
      for (std::size_t k = 0; k < n; ++k) {
        const Vec3 p = nearest_on_segment(c, w.vertices[k], w.vertices[(k + 1) % n]);
        const Vec3 d = sub(p, c);
        const double d2 = dot(d, d);
        if (d2 < best2) { best2 = d2; best = p; }
      }
      if (!(best2 < std::numeric_limits<double>::infinity())) {   // NaN centre
        WallTouch t;
        t.gap = std::numeric_limits<double>::quiet_NaN();
        return t;
      }
      return towards(c, best, side);
    }
    case WallKind::Cylinder: {
      const Vec3 rel = sub(c, w.point);
      const double s = dot(rel, w.normal);
      const Vec3 radial_vec = sub(rel, scale(w.normal, s));
      const double rho = norm(radial_vec);
      const Vec3 out = rho > 0 ? scale(radial_vec, 1 / rho) : perpendicular(w.normal);
      if (s >= 0 && s <= w.length) {
        WallTouch t;
        t.gap = w.inside ? w.radius - rho : rho - w.radius;
        t.dir = w.inside ? out : scale(out, -1);
        t.radial = out;
        return t;
      }
      // Beyond an open end: the rim circle there, from either side.
      const Vec3 rim = add(add(w.point, scale(w.normal, s < 0 ? 0.0 : w.length)), scale(out, w.radius));
      WallTouch t = towards(c, rim, w.inside ? out : scale(out, -1));
      t.radial = out;
      if (!(s == s)) t.gap = std::numeric_limits<double>::quiet_NaN();
      return t;
    }
  }
  return {};
}

WallClearance wall_clearance(const Wall& w, const Vec3& c, double r) {
  WallClearance out;
  if (w.kind == WallKind::Cylinder && w.inside) {
    // A container: centres within its length, whole balls within its radius (the open ends hold no
    // ball in, so one past an end is outside it, whatever its distance to the rim).
    const double s = dot(sub(c, w.point), w.normal);
    out.beyond_end = s < 0 ? -s : s > w.length ? s - w.length : 0;
    if (out.beyond_end > 0) {
      out.wrong_side = true;
      out.gap = -out.beyond_end - r;
      return out;
    }
  }
  const double centre_gap = wall_touch(w, c).gap;
  out.gap = centre_gap - r;
  switch (w.kind) {
    case WallKind::Plane: out.wrong_side = centre_gap < 0; break;
    case WallKind::Polygon: break;
    case WallKind::Cylinder: {
      const double s = dot(sub(c, w.point), w.normal);
      out.wrong_side = w.inside ? centre_gap < 0 : s >= 0 && s <= w.length && centre_gap < 0;
      break;
    }
  }
  return out;
}

Vec3 wall_surface_velocity(const Wall& w, const Vec3& p, const WallTouch& touch) {
  Vec3 v = add(w.velocity, cross(w.spin, sub(p, w.spin_point)));
  if (w.kind == WallKind::Cylinder) v = add(v, scale(touch.radial, w.radius_rate));
  return v;
}

double wall_area(const Wall& w) {
  switch (w.kind) {
    case WallKind::Plane: return 0;
    case WallKind::Polygon: {
      Vec3 sum{0, 0, 0};
      const std::size_t n = w.vertices.size();
      for (std::size_t k = 0; k < n; ++k) sum = add(sum, cross(w.vertices[k], w.vertices[(k + 1) % n]));
      return 0.5 * std::abs(dot(sum, w.normal));
    }
    case WallKind::Cylinder: return 2 * M_PI * w.radius * w.length;
  }
  return 0;
}

Vec3 wall_centre(const Wall& w) {
  switch (w.kind) {
    case WallKind::Plane: return w.point;
    case WallKind::Polygon: {
      Vec3 sum{0, 0, 0};
      for (const Vec3& v : w.vertices) sum = add(sum, v);
      return scale(sum, 1.0 / static_cast<double>(w.vertices.size()));
    }
    case WallKind::Cylinder: return add(w.point, scale(w.normal, 0.5 * w.length));
  }
  return w.point;
}

double move_wall(Wall& w, double dt) {
  const Vec3 shift = scale(w.velocity, dt);
  const double spin = norm(w.spin);
  double moved = norm(shift);
  if (moved > 0) {
    w.point = add(w.point, shift);
    w.spin_point = add(w.spin_point, shift);
    for (Vec3& v : w.vertices) v = add(v, shift);
  }
  if (spin > 0) {
    const Vec3 axis = scale(w.spin, 1 / spin);
    const double angle = spin * dt;
    // How far the surface is from the spin axis at most: what the spin moves it by, per radian.
    double reach = 0;
    auto about = [&](const Vec3& p) { return sub(p, w.spin_point); };
    switch (w.kind) {
      case WallKind::Plane: reach = std::numeric_limits<double>::infinity(); break;
      case WallKind::Polygon:
        for (const Vec3& v : w.vertices) reach = std::max(reach, norm(about(v)));
        break;
      case WallKind::Cylinder:
        reach = std::max(norm(about(w.point)), norm(about(add(w.point, scale(w.normal, w.length))))) + w.radius;
        break;
    }
    moved += std::abs(angle) * reach;
    w.point = add(w.spin_point, rotate(about(w.point), axis, angle));
    for (Vec3& v : w.vertices) v = add(w.spin_point, rotate(about(v), axis, angle));
    const Vec3 n = rotate(w.normal, axis, angle);
    w.normal = scale(n, 1 / norm(n));
  }
  if (w.kind == WallKind::Cylinder && w.radius_rate != 0) {
    w.radius += w.radius_rate * dt;
    moved += std::abs(w.radius_rate * dt);
  }
  return moved;
}

std::string complete_wall(Wall& w) {
  auto finite = [](const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); };
  if (!finite(w.point) || !finite(w.normal)) return "the wall's point and direction must be finite";
  switch (w.kind) {
    case WallKind::Plane:
    case WallKind::Cylinder: {
      const double n = norm(w.normal);
      if (!(n > 0)) return w.kind == WallKind::Plane ? "the plane's normal is zero" : "the cylinder's axis is zero";
      w.normal = scale(w.normal, 1 / n);
      if (w.kind == WallKind::Cylinder) {
        if (!(w.radius > 0) || !std::isfinite(w.radius)) return "the cylinder's radius must be positive";
        if (!(w.length > 0) || !std::isfinite(w.length)) return "the cylinder's length must be positive";
      }
      return "";
    }
    case WallKind::Polygon: {
      const std::size_t n = w.vertices.size();
      if (n < 3) return "a polygon needs at least 3 vertices";
      for (const Vec3& v : w.vertices)
        if (!finite(v)) return "the polygon's vertices must be finite";
      // Newell's normal: the vector area, whatever the shape.
      Vec3 sum{0, 0, 0};
      for (std::size_t k = 0; k < n; ++k) sum = add(sum, cross(w.vertices[k], w.vertices[(k + 1) % n]));
      const double twice_area = norm(sum);
      double size = 0;
      for (const Vec3& v : w.vertices) size = std::max(size, norm(sub(v, w.vertices[0])));
      if (!(twice_area > 1e-12 * size * size)) return "the polygon's vertices lie on a line (it has no area)";
      w.normal = scale(sum, 1 / twice_area);
      w.point = w.vertices[0];
      for (std::size_t k = 0; k < n; ++k) {
        const double off = dot(sub(w.vertices[k], w.point), w.normal);
        if (std::abs(off) > 1e-9 * size)
          return fmt::format("vertex {} is {:.3g} off the plane of the others: a polygon must be planar", k + 1, off);
      }
      return "";
    }
  }
  return "";
}

}  // namespace trubal
