#include "physics/sample.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "model/wall_shape.hpp"
#include "physics/measure.hpp"
#include "physics/walls.hpp"

namespace trubal {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The distance between two facing flat walls, along the first's normal.
double distance(const Wall& a, const Wall& b) {
  const Vec3 ca = wall_centre(a), cb = wall_centre(b);
  return std::abs(dot({cb[0] - ca[0], cb[1] - ca[1], cb[2] - ca[2]}, a.normal));
}

bool flat(const Wall& w) { return w.kind != WallKind::Cylinder; }

// The sample's walls, or nullptr where one is gone.
struct SampleWalls {
  const Wall* platen[2] = {nullptr, nullptr};
  const Wall* side[4] = {nullptr, nullptr, nullptr, nullptr};
  bool cylinder = false;
  bool whole = false;
};

SampleWalls walls_of(const Model& model, const Sample& s) {
  SampleWalls w;
  w.whole = true;
  for (int k = 0; k < 2; ++k) w.whole = (w.platen[k] = find_wall(model, s.platens[k])) && w.whole;
  w.cylinder = s.sides[1] == 0;
  for (int k = 0; k < (w.cylinder ? 1 : 4); ++k) w.whole = (w.side[k] = find_wall(model, s.sides[k])) && w.whole;
  return w;
}

// The cross-section from the sides.
double cross_section(const SampleWalls& w) {
  if (w.cylinder) return std::numbers::pi * w.side[0]->radius * w.side[0]->radius;
  return distance(*w.side[0], *w.side[1]) * distance(*w.side[2], *w.side[3]);
}

}  // namespace

SampleMeasures sample_measures(const Model& model) {
  SampleMeasures m;
  const Sample& s = model.sample;
  const SampleWalls w = walls_of(model, s);
  if (!s.declared() || !w.whole) {
    m.height = m.area = m.volume = m.axial = m.volumetric = m.sigma1 = m.sigma3 = m.q = m.p = kNaN;
    return m;
  }
  m.height = distance(*w.platen[0], *w.platen[1]);
  m.area = cross_section(w);
  m.volume = m.area * m.height;
  m.axial = 1 - m.height / s.height0;
  m.volumetric = 1 - m.volume / (s.area0 * s.height0);
  const double sigma1 = 0.5 * (w.platen[0]->normal_force + w.platen[1]->normal_force) / m.area;
  double sigma3 = 0;
  if (w.cylinder) {
    sigma3 = w.side[0]->normal_force / (2 * std::numbers::pi * w.side[0]->radius * m.height);
  } else {
    const double across0 = distance(*w.side[0], *w.side[1]), across1 = distance(*w.side[2], *w.side[3]);
    const double s0 = 0.5 * (w.side[0]->normal_force + w.side[1]->normal_force) / (across1 * m.height);
    const double s1 = 0.5 * (w.side[2]->normal_force + w.side[3]->normal_force) / (across0 * m.height);
    sigma3 = 0.5 * (s0 + s1);
  }
  const TriaxialStress t = triaxial_stress(sigma1, sigma3);
  m.sigma1 = t.sigma1;
  m.sigma3 = t.sigma3;
  m.q = t.q;
  m.p = t.p;
  return m;
}

std::string check_sample(const Model& model, const Sample& s) {
  const SampleWalls w = walls_of(model, s);
  auto missing = [&](std::int64_t id) { return find_wall(model, id) == nullptr; };
  for (std::int64_t id : s.platens)
    if (missing(id)) return fmt::format("there is no wall {}", id);
  for (std::int64_t id : s.sides)
    if (id != 0 && missing(id)) return fmt::format("there is no wall {}", id);
  if (s.platens[0] == s.platens[1]) return "the two platens are one wall";
  const Wall& a = *w.platen[0];
  const Wall& b = *w.platen[1];
  if (!flat(a) || !flat(b)) return "a platen is a plane or a polygon, not a cylinder";
  constexpr double kParallel = 1 - 1e-9;   // normals within about 0.003 degrees
  if (!(dot(a.normal, b.normal) < -kParallel))
    return fmt::format("platens {} and {} do not face each other (their normals must be opposite)", a.id, b.id);
  if (w.cylinder) {
    const Wall& c = *w.side[0];
    if (c.kind != WallKind::Cylinder)
      return fmt::format("wall {} is not a cylinder: give `cylinder c` or four sides (`sides a b c d`)", c.id);
    if (!(std::abs(dot(c.normal, a.normal)) > kParallel))
      return fmt::format("cylinder {}'s axis does not lie along the platens' normal", c.id);
  } else {
    for (int k = 0; k < 4; ++k) {
      const Wall& side = *w.side[k];
      if (!flat(side)) return fmt::format("side {} is a cylinder: give it as `cylinder {}`", side.id, side.id);
      if (!(std::abs(dot(side.normal, a.normal)) < 1 - kParallel))
        return fmt::format("side {}'s normal is not square to the platens' normal", side.id);
    }
    for (int k : {0, 2})
      if (!(dot(w.side[k]->normal, w.side[k + 1]->normal) < -kParallel))
        return fmt::format("sides {} and {} do not face each other", w.side[k]->id, w.side[k + 1]->id);
    if (!(std::abs(dot(w.side[0]->normal, w.side[2]->normal)) < 1 - kParallel))
      return fmt::format("sides {} and {} are not square to each other", w.side[0]->id, w.side[2]->id);
  }
  if (!(distance(a, b) > 0)) return "the platens are no distance apart";
  if (!(cross_section(w) > 0)) return "the sides enclose no area";
  return "";
}

void reset_sample(const Model& model, Sample& s) {
  const SampleWalls w = walls_of(model, s);
  if (!w.whole) return;
  s.height0 = distance(*w.platen[0], *w.platen[1]);
  s.area0 = cross_section(w);
}

}  // namespace trubal
