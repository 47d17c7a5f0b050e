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

SphereMeasurement measure_sphere(const Model& model, const MeasureSphere& sphere) {
  if (!(sphere.radius > 0) || !std::isfinite(sphere.radius))
    throw std::runtime_error(fmt::format("a measurement sphere needs a positive radius, not {}", sphere.radius));
  const Balls& b = model.balls;
  const Space& space = model.space;
  const CellFrame frame = cell_frame(space);
  if (space.periodic) {
    // One image of a ball at most may reach the sphere, so the nearest image is the one to take.
    const double largest = b.size() ? *std::max_element(b.rad.begin(), b.rad.end()) : 0.0;
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
  SphereMeasurement m;
  m.volume = ball_volume(sphere.radius);
  std::vector<char> inside(b.size(), 0);
  double inside_volume = 0;   // of the balls whose centres are inside, whole
  for (std::size_t k = 0; k < b.size(); ++k) {
    const double d = distance(k);
    m.solid += ball_sphere_overlap(b.rad[k], sphere.radius, d);
    if (d <= sphere.radius) {
      inside[k] = 1;
      ++m.balls;
      inside_volume += ball_volume(b.rad[k]);
    }
  }
  m.porosity = 1 - m.solid / m.volume;
  m.void_ratio = m.solid > 0 ? m.porosity / (1 - m.porosity) : std::numeric_limits<double>::infinity();
  // Each inside ball's contacts: sum of (contact point - centre) (x) (force on the ball), the sign
  // turned for compression positive. A pair with both balls inside adds its whole branch vector.
  Sym6 moment{};
  std::size_t ball_contacts = 0, sliding = 0;
  const ContactTable& c = model.contacts;
  for (std::size_t p = 0; p < c.size(); ++p) {
    if (!c.touching(p)) continue;
    const bool in_i = inside[c.i[p]], in_j = inside[c.j[p]];
    if (!in_i && !in_j) continue;
    // n points from i to j, the force f is on j: i's arm (r_i - u/2) n carries -f, j's arm
    // -(r_j - u/2) n carries f; both give + arm length n (x) f.
    double arm = 0;
    if (in_i) arm += b.rad[c.i[p]] - 0.5 * c.overlap[p], ++ball_contacts;
    if (in_j) arm += b.rad[c.j[p]] - 0.5 * c.overlap[p], ++ball_contacts;
    add_dyad(moment, c.fx[p], c.fy[p], c.fz[p], arm * c.nx[p], arm * c.ny[p], arm * c.nz[p]);
    add_dyad(m.fabric, c.nx[p], c.ny[p], c.nz[p], c.nx[p], c.ny[p], c.nz[p]);
    ++m.contacts;
    sliding += c.state[p] == 2;
  }
  // Wall contacts of inside balls: the arm from the centre to the contact point, the force on the wall.
  const WallContacts& w = model.wall_contacts;
  if (w.fx.size() == w.size() && w.overlap.size() == w.size())
    for (std::size_t p = 0; p < w.size(); ++p) {
      if (w.state[p] == 0 || w.ball[p] >= b.size() || !inside[w.ball[p]]) continue;
      const double arm = b.rad[w.ball[p]] - w.overlap[p];
      add_dyad(moment, w.fx[p], w.fy[p], w.fz[p], arm * w.nx[p], arm * w.ny[p], arm * w.nz[p]);
    }
  if (m.balls > 0) {
    // PFC's correction: the balls whose centres are inside stand for the solid in the sphere.
    const double scale = (1 - m.porosity) / inside_volume;
    for (double& v : moment) v *= scale;
    m.stress = moment;
    m.coordination = static_cast<double>(ball_contacts) / static_cast<double>(m.balls);
  }
  if (m.contacts > 0) {
    for (double& v : m.fabric) v /= static_cast<double>(m.contacts);
    m.sliding = static_cast<double>(sliding) / static_cast<double>(m.contacts);
  }
  return m;
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
