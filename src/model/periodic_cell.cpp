#include "model/periodic_cell.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace trubal {

CellFrame cell_frame(const Space& s) {
  CellFrame f;
  if (!s.periodic) return f;
  auto L = s.length();
  // A bounded axis of a mixed space: an edge three times the extent, so that no image along it is
  // ever nearest or within reach (its image numbers stay 0, and 0 times the edge is an exact 0).
  for (int a = 0; a < 3; ++a)
    if (!s.periodic_axis[a]) L[a] *= 3;
  f.lx = L[0]; f.ly = L[1]; f.lz = L[2];
  f.xy = s.tilt[0]; f.xz = s.tilt[1]; f.yz = s.tilt[2];
  const auto g = velocity_gradient(s.strain_rate);
  // dH/dt = L H, both upper triangular.
  f.vlx = g[0][0] * f.lx;
  f.vxy = g[0][0] * f.xy + g[0][1] * f.ly;
  f.vxz = g[0][0] * f.xz + g[0][1] * f.yz + g[0][2] * f.lz;
  f.vly = g[1][1] * f.ly;
  f.vyz = g[1][1] * f.yz + g[1][2] * f.lz;
  f.vlz = g[2][2] * f.lz;
  return f;
}

std::array<std::array<double, 3>, 3> velocity_gradient(const std::array<double, 6>& r) {
  return {{{-r[0], -2 * r[3], -2 * r[4]}, {0.0, -r[1], -2 * r[5]}, {0.0, 0.0, -r[2]}}};
}

std::array<double, 3> cell_widths(const Space& s) {
  const auto L = s.length();
  const double xy = s.tilt[0], xz = s.tilt[1], yz = s.tilt[2];
  // Face normals: b x c, c x a, a x b; width = volume / face area.
  const double q = (xy * yz - L[1] * xz) / (L[1] * L[2]);
  return {L[0] / std::sqrt(1 + (xy / L[1]) * (xy / L[1]) + q * q), L[1] / std::sqrt(1 + (yz / L[2]) * (yz / L[2])),
          L[2]};
}

void check_periodic_cell(const Model& model) {
  if (!model.space.periodic) return;
  const double d = 2 * model.balls.max_radius();
  const auto w = cell_widths(model.space);
  for (int a = 0; a < 3; ++a)
    if (model.space.periodic_axis[a] && !(w[a] >= 2 * d))
      throw std::runtime_error(fmt::format(
          "periodic cell too small: {} {} is {:.6g}, less than twice the largest ball diameter ({:.6g}); "
          "a ball could touch two images of another. Use a larger cell (START x y z) or smaller balls",
          model.space.tilt == std::array<double, 3>{0, 0, 0} ? "edge" : "width across", "xyz"[a], w[a], d));
}

namespace {

// The part of ball k's coordinate a that the tilts contribute (0 in an unsheared cell): the
// coordinate less it is lo[a] + edge length * the fractional coordinate along edge a.
double tilt_terms(const Space& s, const CellFrame& f, double y, double z, int a) {
  if (a == 2 || (f.xy == 0 && f.xz == 0 && f.yz == 0)) return 0;
  const double sz = (z - s.lo[2]) / f.lz;
  if (a == 1) return f.yz * sz;
  const double sy = (y - s.lo[1] - f.yz * sz) / f.ly;
  return f.xy * sy + f.xz * sz;
}

}  // namespace

bool outside_cell(const Model& model, std::size_t begin, std::size_t end) {
  const Balls& b = model.balls;
  return outside_cell(model.space, b.x, b.y, b.z, begin, end);
}

bool outside_cell(const Space& s, const std::vector<double>& x_, const std::vector<double>& y_,
                  const std::vector<double>& z_, std::size_t begin, std::size_t end) {
  if (!s.periodic) return false;
  const CellFrame f = cell_frame(s);
  const std::vector<double>* pos[3] = {&x_, &y_, &z_};
  if (f.xy == 0 && f.xz == 0 && f.yz == 0) {
    // An unsheared cell (the common case, every step): the same test axis by axis, without the
    // early exit, as a loop the compiler vectorises (an infinite coordinate is not outside; a NaN
    // fails neither comparison).
    for (int a = 0; a < 3; ++a) {
      if (!s.periodic_axis[a]) continue;
      const double* x = pos[a]->data();
      const double lo = s.lo[a], hi = s.hi[a];
      unsigned out = 0;
      for (std::size_t k = begin; k < end; ++k)
        out |= static_cast<unsigned>((x[k] < lo) | (x[k] >= hi)) & static_cast<unsigned>(std::abs(x[k]) != INFINITY);
      if (out != 0) return true;
    }
    return false;
  }
  for (std::size_t k = begin; k < end; ++k)
    for (int a = 2; a >= 0; --a) {   // the test wrap_into_cell makes, on unmoved coordinates
      if (!s.periodic_axis[a]) continue;
      const double x = (*pos[a])[k];
      if (!std::isfinite(x)) continue;
      const double t = x - tilt_terms(s, f, y_[k], z_[k], a);
      if (!(t >= s.lo[a] && t < s.hi[a])) return true;
    }
  return false;
}

void add_wrap_terms(Model& model, const std::vector<WrapTerm>& terms) {
  double work = 0;
  for (const WrapTerm& t : terms) {
    work += t.work;
    model.space.gross_work += t.gross;
  }
  model.energy.boundary_work += work;
}

bool wrap_into_cell(Model& model, std::vector<double>* ref_x, std::vector<double>* ref_y, std::vector<double>* ref_z,
                    std::vector<WrapTerm>* terms) {
  const Space& s = model.space;
  if (!s.periodic) return false;
  Balls& b = model.balls;
  ContactTable& c = model.contacts;
  const std::size_t n = b.size();
  const CellFrame f = cell_frame(s);
  // Edge vectors and their velocities, by axis (columns of H and dH/dt).
  const double edge[3][3] = {{f.lx, 0, 0}, {f.xy, f.ly, 0}, {f.xz, f.yz, f.lz}};
  const double edge_velocity[3][3] = {{f.vlx, 0, 0}, {f.vxy, f.vly, 0}, {f.vxz, f.vyz, f.vlz}};
  std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  std::vector<double>* vel[3] = {&b.vx, &b.vy, &b.vz};
  std::vector<double>* ref[3] = {ref_x, ref_y, ref_z};
  // A ball a million cells away (it crossed them in one step) has no image to speak of and its shift
  // no integer: the run is broken, say so before anything is moved rather than overflow.
  for (std::size_t k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) {
      if (!s.periodic_axis[a]) continue;   // a bounded axis: the box's conditions see to it
      const double x = (*pos[a])[k];
      if (std::isfinite(x) && !(std::abs(x - s.lo[a]) <= 1e6 * (std::abs(edge[a][a]) + std::abs(s.tilt[0]) + std::abs(s.tilt[1]) + std::abs(s.tilt[2]))))
        throw std::runtime_error(fmt::format(
            "ball {} is {:.3g} edge lengths of the periodic cell away along {} after one step (at {:.6g}): a load or "
            "velocity far beyond the scene's; nothing was wrapped",
            b.id[k], std::abs(x - s.lo[a]) / edge[a][a], "xyz"[a], x));
    }
  // Edge vectors each ball moved by, per axis (made when the first ball moves).
  std::vector<std::array<int, 3>> moved;
  bool any = false;
  double work = 0;
  for (std::size_t k = 0; k < n; ++k) {
    // z first: moving along c shifts y and x; then y (b shifts x); then x.
    for (int a = 2; a >= 0; --a) {
      if (!s.periodic_axis[a]) continue;
      double& x = (*pos[a])[k];
      if (!std::isfinite(x)) continue;   // the guard reports it
      const double tilt = tilt_terms(s, f, b.y[k], b.z[k], a);
      const double t = x - tilt;
      if (t >= s.lo[a] && t < s.hi[a]) continue;
      // The ball moves to its own image inside the cell: minus shift edge vectors.
      const double shift = std::floor((t - s.lo[a]) / edge[a][a]);
      if (shift == 0) continue;   // rounding at the upper face

      for (int e = 0; e <= a; ++e) (*pos[e])[k] -= shift * edge[a][e];
      // Rounding can land a tiny negative offset on hi: keep the shift, stay inside.
      if (x - tilt >= s.hi[a]) x = std::nextafter(s.hi[a], s.lo[a]) + tilt;
      if (x - tilt < s.lo[a]) x = s.lo[a] + tilt;
      const auto step = static_cast<int>(shift);
      for (int e = 0; e <= a; ++e)
        if (ref[e] && ref[e]->size() == n) (*ref[e])[k] -= shift * edge[a][e];
      for (int e = 0; e <= a; ++e) {
        if (edge_velocity[a][e] == 0) continue;
        double& v = (*vel[e])[k];
        const double v_old = v;
        v -= shift * edge_velocity[a][e];
        const double gain = 0.5 * b.mass[k] * (v * v - v_old * v_old), size = 0.5 * b.mass[k] * std::abs(v * v - v_old * v_old);
        if (terms) {
          terms->push_back({k, gain, size});
          continue;
        }
        work += gain;
        model.space.gross_work += size;
      }
      if (moved.empty()) moved.assign(n, {0, 0, 0});
      moved[k][a] += step;
      any = true;
    }
  }
  if (!terms) model.energy.boundary_work += work;
  // Image of j seen from i: x_j + H img - x_i. Moving j by -shift along edge a adds shift to img_a;
  // moving i takes it off. (A table that does not fit the balls has nothing to keep.)
  const bool table_fits = c.image_x.size() == c.size() && c.image_y.size() == c.size() && c.image_z.size() == c.size();
  if (any && table_fits) {
    std::vector<std::int8_t>* image[3] = {&c.image_x, &c.image_y, &c.image_z};
    for (std::size_t p = 0; p < c.size(); ++p) {
      const std::size_t i = c.i[p], j = c.j[p];
      if (i >= n || j >= n) continue;
      for (int a = 0; a < 3; ++a)
        if (moved[j][a] != moved[i][a])
          (*image[a])[p] = static_cast<std::int8_t>((*image[a])[p] + moved[j][a] - moved[i][a]);
    }
  }
  return any;
}

// How many edges to take off a tilt to bring it within half an edge: the nearest whole number,
// computed at once (a loop taking one edge at a time ran for ever on a tilt of 1e300 edges); 0 where
// the quotient is not finite (a collapsed or infinite cell, which CYCLE refuses elsewhere).
static double edges_off(double tilt, double edge) {
  if (!(std::abs(tilt) > 0.5 * edge)) return 0;
  const double n = std::round(tilt / edge);
  return std::isfinite(n) ? n : 0;
}

bool reduce_cell_tilt(Model& model) {
  Space& s = model.space;
  if (!s.periodic) return false;
  ContactTable& c = model.contacts;
  const auto L = s.length();
  // Replacing edge `from` by itself less n edges `other`: image m becomes m' with
  // m'_other = m_other + n m_from (the same offset H m). Images are 8-bit, so n counts modulo 256,
  // as n renamings one at a time would.
  auto renumber = [&](std::vector<std::int8_t>& other, const std::vector<std::int8_t>& from, double n) {
    const int by = static_cast<int>(std::fmod(n, 256.0));
    for (std::size_t p = 0; p < other.size() && p < from.size(); ++p)
      other[p] = static_cast<std::int8_t>(other[p] + by * from[p]);
  };
  bool any = false;
  if (const double n = edges_off(s.tilt[2], L[1]); n != 0) {   // yz: c -/+ n b
    s.tilt[2] -= n * L[1];
    s.tilt[1] -= n * s.tilt[0];
    renumber(c.image_y, c.image_z, n);
    any = true;
  }
  if (const double n = edges_off(s.tilt[1], L[0]); n != 0) {   // xz: c -/+ n a
    s.tilt[1] -= n * L[0];
    renumber(c.image_x, c.image_z, n);
    any = true;
  }
  if (const double n = edges_off(s.tilt[0], L[0]); n != 0) {   // xy: b -/+ n a
    s.tilt[0] -= n * L[0];
    renumber(c.image_x, c.image_y, n);
    any = true;
  }
  return any;
}

}  // namespace trubal
