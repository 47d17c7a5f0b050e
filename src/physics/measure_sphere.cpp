// Measurement spheres after PFC3D's: which balls and contacts a sphere holds, the stress from those
// contacts scaled by the sphere's solid fraction, its porosity from the parts of balls inside it.
#include "physics/measure_sphere.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "model/periodic_cell.hpp"

namespace trubal {
namespace {

constexpr double kPi = std::numbers::pi;

double ball_volume(double r) { return 4.0 / 3.0 * kPi * r * r * r; }

}  // namespace

double ball_sphere_overlap(double r, double R, double d) {
  if (d >= r + R) return 0;
  if (d <= std::abs(R - r)) return ball_volume(std::min(r, R));
  // The lens of two intersecting spheres: the two caps cut by their common plane.
  const double s = R + r - d;
  return kPi * s * s * (d * d + 2 * d * r - 3 * r * r + 2 * d * R + 6 * r * R - 3 * R * R) / (12 * d);
}

void check_measure_sphere(const Space& space, const MeasureSphere& sphere, double largest) {
  if (!(sphere.radius > 0) || !std::isfinite(sphere.radius))
    throw std::runtime_error(fmt::format("a measurement sphere needs a positive radius, not {}", sphere.radius));
  if (!space.periodic) return;
  // One image of a ball at most may reach the sphere, so the nearest image is the one to take.
  const auto widths = cell_widths(space);
  double narrowest = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a)
    if (space.wraps(a)) narrowest = std::min(narrowest, widths[a]);
  if (sphere.radius + largest > 0.5 * narrowest)
    throw std::runtime_error(fmt::format(
        "a measurement sphere of radius {} is too large for the periodic cell: its radius plus the largest ball "
        "radius ({}) must not pass half the cell's narrowest periodic width ({})",
        sphere.radius, largest, 0.5 * narrowest));
}

void SphereSums::add(const SphereSums& o) {
  solid.add(o.solid);
  inside_volume.add(o.inside_volume);
  for (int k = 0; k < 6; ++k) moment[k].add(o.moment[k]), fabric[k].add(o.fabric[k]);
  balls += o.balls, ball_contacts += o.ball_contacts, contacts += o.contacts, sliding += o.sliding;
  largest = std::max(largest, o.largest);
}

SphereSums sphere_sums(const Model& model, const MeasureSphere& sphere, const std::vector<std::uint32_t>* balls,
                       const std::vector<std::uint32_t>* pairs, const std::vector<std::uint32_t>* walls) {
  const Balls& b = model.balls;
  const Space& space = model.space;
  const CellFrame frame = cell_frame(space);
  // Each ball's distance from the centre, the nearest image's in a periodic space.
  auto distance = [&](std::size_t k) {
    double dx = b.x[k] - sphere.centre[0], dy = b.y[k] - sphere.centre[1], dz = b.z[k] - sphere.centre[2];
    if (space.periodic) {
      std::int8_t ix = 0, iy = 0, iz = 0;
      nearest_image(frame, dx, dy, dz, ix, iy, iz);
      double ox = 0, oy = 0, oz = 0;
      image_offset(frame, ix, iy, iz, ox, oy, oz);
      dx += ox, dy += oy, dz += oz;
    }
    return std::sqrt(dx * dx + dy * dy + dz * dz);
  };
  SphereSums s;
  // Whether each ball's centre is inside: every ball the rows below may name (a pair's second ball
  // need not be among `balls`).
  std::vector<char> inside(b.size(), 0);
  std::vector<double> dist(b.size());
  for (std::size_t k = 0; k < b.size(); ++k) {
    dist[k] = distance(k);
    inside[k] = dist[k] <= sphere.radius;
  }
  {
    ExactSum::Stream solid(s.solid), volume(s.inside_volume);
    each_row(balls, b.size(), [&](std::size_t k) {
      s.largest = std::max(s.largest, b.rad[k]);
      if (const double v = ball_sphere_overlap(b.rad[k], sphere.radius, dist[k]); v != 0) solid.add(v);
      if (!inside[k]) return;
      ++s.balls;
      volume.add(ball_volume(b.rad[k]));
    });
  }
  // Each inside ball's contacts: (contact point - centre) (x) (force on the ball), the sign turned
  // for compression positive. A pair with both balls inside adds its whole branch vector.
  // (The streams flush into s as this block ends, before s is returned.)
  {
    DyadSums moment(s.moment), fabric(s.fabric);
    const ContactTable& c = model.contacts;
    each_row(pairs, c.size(), [&](std::size_t p) {
      if (!c.touching(p)) return;
      const bool in_i = inside[c.i[p]], in_j = inside[c.j[p]];
      if (!in_i && !in_j) return;
      // n points from i to j, the force f is on j: i's arm (r_i - u/2) n carries -f, j's arm
      // -(r_j - u/2) n carries f; both give + arm length n (x) f.
      double arm = 0;
      if (in_i) arm += b.rad[c.i[p]] - 0.5 * c.overlap[p], ++s.ball_contacts;
      if (in_j) arm += b.rad[c.j[p]] - 0.5 * c.overlap[p], ++s.ball_contacts;
      moment.add(c.fx[p], c.fy[p], c.fz[p], arm * c.nx[p], arm * c.ny[p], arm * c.nz[p]);
      fabric.add(c.nx[p], c.ny[p], c.nz[p], c.nx[p], c.ny[p], c.nz[p]);
      ++s.contacts;
      s.sliding += c.state[p] == 2;
    });
    // Wall contacts of inside balls: the arm from the centre to the contact point, the force on the wall.
    const WallContacts& w = model.wall_contacts;
    if (w.fx.size() == w.size() && w.overlap.size() == w.size())
      each_row(walls, w.size(), [&](std::size_t p) {
        if (w.state[p] == 0 || w.ball[p] >= b.size() || !inside[w.ball[p]]) return;
        const double arm = b.rad[w.ball[p]] - w.overlap[p];
        moment.add(w.fx[p], w.fy[p], w.fz[p], arm * w.nx[p], arm * w.ny[p], arm * w.nz[p]);
      });
  }
  return s;
}

SphereMeasurement sphere_measurement(const Space& space, const MeasureSphere& sphere, const SphereSums& s) {
  check_measure_sphere(space, sphere, s.largest);
  SphereMeasurement m;
  m.volume = ball_volume(sphere.radius);
  m.solid = s.solid.value();
  m.balls = static_cast<std::size_t>(s.balls);
  m.contacts = static_cast<std::size_t>(s.contacts);
  m.porosity = 1 - m.solid / m.volume;
  m.void_ratio = m.solid > 0 ? m.porosity / (1 - m.porosity) : std::numeric_limits<double>::infinity();
  if (m.balls > 0) {
    // PFC's correction: the balls whose centres are inside stand for the solid in the sphere.
    const double scale = (1 - m.porosity) / s.inside_volume.value();
    for (int k = 0; k < 6; ++k) m.stress[k] = s.moment[k].value() * scale;
    m.coordination = s.ball_contacts / s.balls;
  }
  if (m.contacts > 0) {
    for (int k = 0; k < 6; ++k) m.fabric[k] = s.fabric[k].value() / s.contacts;
    m.sliding = s.sliding / s.contacts;
  }
  return m;
}

SphereMeasurement measure_sphere(const Model& model, const MeasureSphere& sphere) {
  check_measure_sphere(model.space, sphere, 0);   // (the radius, before reading the balls)
  return sphere_measurement(model.space, sphere, sphere_sums(model, sphere));
}

Porosity space_porosity(const Model& model, double volume) {
  Porosity p;
  p.volume = volume;
  for (double r : model.balls.rad) p.solid += ball_volume(r);
  if (volume > 0) {
    p.porosity = 1 - p.solid / volume;
    p.void_ratio = p.solid > 0 ? p.porosity / (1 - p.porosity) : std::numeric_limits<double>::infinity();
  }
  return p;
}

double volumetric_strain(const Model& model) {
  const Space& s = model.space;
  if (s.reference_volume > 0) return 1 - s.volume() / s.reference_volume;
  // A save older than format 6: the ratio from the accumulated (natural) strains, each the sum of
  // rate dt, so V / V0 = exp(-(e11 + e22 + e33)) to the steps' second order.
  return 1 - std::exp(-(s.strain[0] + s.strain[1] + s.strain[2]));
}

}  // namespace trubal
