// The periodic cell's geometry (doc/physics.md "Periodic space"): its frame, the images of balls
// and how they move, wrapping balls into the cell and keeping its tilts short. Balls are wrapped
// into the cell at the start of every step, each pair carries the image of j that i sees (int8 per
// edge vector), and every pair search and kernel uses this arithmetic, so that every backend's
// answer is the same to the bit. The cell is a parallelepiped when it is sheared. The rule that keeps
// one image per pair: every width of the cell at least twice the largest diameter (then only the
// nearest image of a ball can touch it).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "model/model.hpp"

namespace trubal {

// The periodic cell as a matrix H whose columns are its edge vectors a = (lx, 0, 0),
// b = (xy, ly, 0), c = (xz, yz, lz) (upper triangular: the lengths along the axes and the tilts of
// Space), and their rate of change dH/dt = L H for the velocity gradient L of the strain rates.
// Image n = (ix, iy, iz) of a ball at x is x + H n and moves at v + (dH/dt) n: an image across
// the y faces is shifted by xy along x (Lees-Edwards), one across the z faces by xz and yz.
// Outside a periodic space every entry is 0, so that the plain difference comes out.
struct CellFrame {
  double lx = 0, ly = 0, lz = 0, xy = 0, xz = 0, yz = 0;         // H
  double vlx = 0, vly = 0, vlz = 0, vxy = 0, vxz = 0, vyz = 0;   // dH/dt
  // dH/dt is not 0: the images move (else every image velocity is +-0).
  bool moving() const { return vlx != 0 || vly != 0 || vlz != 0 || vxy != 0 || vxz != 0 || vyz != 0; }
};

CellFrame cell_frame(const Space& s);

// The velocity gradient of the strain rates (compression positive, tensor shear components):
// upper triangular, so that the cell stays in the form above; the shear is simple shear, e.g. e12
// moves x with y: L_xy = -2 e12 (the top y face moves toward -x for e12 > 0), with the spin that
// simple shear has. Rows x y z, columns x y z.
std::array<std::array<double, 3>, 3> velocity_gradient(const std::array<double, 6>& rates);

// H n, the offset of image n: (ix lx + iy xy + iz xz, iy ly + iz yz, iz lz), in this order
// everywhere (detection, contact kernel, time step), so that every backend rounds alike. With no
// tilt the terms of the other axes are (signed) zeros and leave the sum exact.
inline void image_offset(const CellFrame& f, std::int8_t ix, std::int8_t iy, std::int8_t iz, double& ox, double& oy,
                         double& oz) {
  const double nx = ix, ny = iy, nz = iz;
  ox = nx * f.lx + ny * f.xy + nz * f.xz;
  oy = ny * f.ly + nz * f.yz;
  oz = nz * f.lz;
}
// (dH/dt) n, the velocity of image n relative to the ball.
inline void image_velocity(const CellFrame& f, std::int8_t ix, std::int8_t iy, std::int8_t iz, double& ux, double& uy,
                           double& uz) {
  const double nx = ix, ny = iy, nz = iz;
  ux = nx * f.vlx + ny * f.vxy + nz * f.vxz;
  uy = ny * f.vly + nz * f.vyz;
  uz = nz * f.vlz;
}

// x_j - x_i for j's image at offset o (from image_offset): (x_j - x_i) + o.
inline double image_delta(double xj, double xi, double offset) { return (xj - xi) + offset; }

// The image (-1, 0, +1) of j nearest to i along one lattice direction, from the separation t along
// it (|t| < 1.5 edge).
inline std::int8_t nearest_image(double t, double length) {
  return t > 0.5 * length ? std::int8_t{-1} : (t < -0.5 * length ? std::int8_t{1} : std::int8_t{0});
}

// The image of j nearest to i for wrapped positions, separation d = x_j - x_i: each fractional
// coordinate of d (H^-1 d) rounded to the nearest integer. In a cell whose widths are at least
// twice the reach, an image within reach is this one.
inline void nearest_image(const CellFrame& f, double dx, double dy, double dz, std::int8_t& ix, std::int8_t& iy,
                          std::int8_t& iz) {
  const double sz = dz / f.lz;
  const double ty = dy - f.yz * sz;              // ly times the fractional y
  const double tx = dx - f.xy * (ty / f.ly) - f.xz * sz;
  ix = nearest_image(tx, f.lx);
  iy = nearest_image(ty, f.ly);
  iz = nearest_image(dz, f.lz);
}

// The widths of the periodic cell: the distances between its opposite faces (the edge lengths
// when it has no tilt).
std::array<double, 3> cell_widths(const Space& s);

// x_j - x_i of pair p of the contact table: at j's image (its offset from image_offset) where
// `periodic`, else the plain difference (the same bits: image_delta with a zero offset).
inline std::array<double, 3> pair_separation(const CellFrame& f, bool periodic, const Balls& b, const ContactTable& c,
                                             std::size_t p) {
  const std::size_t i = c.i[p], j = c.j[p];
  double ox = 0, oy = 0, oz = 0;
  if (periodic) image_offset(f, c.image_x[p], c.image_y[p], c.image_z[p], ox, oy, oz);
  return {image_delta(b.x[j], b.x[i], ox), image_delta(b.y[j], b.y[i], oy), image_delta(b.z[j], b.z[i], oz)};
}

// x_j - x_i at j's nearest image where `periodic` (that image in ix iy iz), else the plain
// difference (images 0): a pair whose image no list holds, as a bond's or one BOND considers.
inline std::array<double, 3> nearest_separation(const CellFrame& f, bool periodic, const Balls& b, std::size_t i,
                                                std::size_t j, std::int8_t& ix, std::int8_t& iy, std::int8_t& iz) {
  ix = iy = iz = 0;
  double ox = 0, oy = 0, oz = 0;
  if (periodic) {
    nearest_image(f, b.x[j] - b.x[i], b.y[j] - b.y[i], b.z[j] - b.z[i], ix, iy, iz);
    image_offset(f, ix, iy, iz, ox, oy, oz);
  }
  return {image_delta(b.x[j], b.x[i], ox), image_delta(b.y[j], b.y[i], oy), image_delta(b.z[j], b.z[i], oz)};
}

// Whether balls i < j touch within `reach` at j's nearest image; sets that image. The one test
// the periodic pair searches make (serial/threaded lists with a skin, allpairs without).
inline bool nearest_image_within(const CellFrame& f, const Balls& b, std::size_t i, std::size_t j, double reach,
                                 std::int8_t& ix, std::int8_t& iy, std::int8_t& iz) {
  nearest_image(f, b.x[j] - b.x[i], b.y[j] - b.y[i], b.z[j] - b.z[i], ix, iy, iz);
  double ox, oy, oz;
  image_offset(f, ix, iy, iz, ox, oy, oz);
  const double dx = image_delta(b.x[j], b.x[i], ox), dy = image_delta(b.y[j], b.y[i], oy),
               dz = image_delta(b.z[j], b.z[i], oz);
  return dx * dx + dy * dy + dz * dz < reach * reach;
}

// Throws std::runtime_error when some width of the cell is less than twice the largest ball diameter.
void check_periodic_cell(const Model& model);

// Whether some ball of [begin, end) lies outside the cell, so that wrap_into_cell would move it
// (a read-only test that threads can share out; a true answer may be conservative).
bool outside_cell(const Model& model, std::size_t begin, std::size_t end);
// The same for centres kept apart from a model (a batch deck's held BALL lines).
bool outside_cell(const Space& space, const std::vector<double>& x, const std::vector<double>& y,
                  const std::vector<double>& z, std::size_t begin, std::size_t end);

// Wraps every ball centre into the periodic cell (the parallelepiped lo + H s, s in [0, 1), taken
// z first, then y, then x). A ball moved by an edge vector has its velocity changed by that edge's
// velocity; the images of its pairs in model.contacts change so that each pair
// keeps the same partner image (and its history); ref (the pair list's reference positions, if the
// same size) moves with the ball. The kinetic energy that the velocity change adds is counted as
// boundary work. Returns whether any ball moved.
// terms: where given, each ball's velocity changes are listed there instead (in the order the
// energy adds them), and the model's energy is left alone (add_wrap_terms adds them, for a model
// whose balls were wrapped in parts: a distributed run's ranks).
struct WrapTerm {
  std::size_t ball;
  double work, gross;   // the kinetic energy the change adds, and its magnitude
};
bool wrap_into_cell(Model& model, std::vector<double>* ref_x, std::vector<double>* ref_y, std::vector<double>* ref_z,
                    std::vector<WrapTerm>* terms = nullptr);
// The energy of a wrap's terms (by ball, then in each ball's order) into the model's, with the
// additions of a wrap_into_cell without terms, to the bit.
void add_wrap_terms(Model& model, const std::vector<WrapTerm>& terms);

// Keeps the tilts within half an edge (|yz| <= ly/2, then |xz|, |xy| <= lx/2) by replacing an edge
// vector with itself less another (c - b, c - a, b - a): the same lattice of images, so nothing
// physical changes; the images of the pairs in model.contacts are renumbered to stay the same
// images, and the balls are wrapped into the new cell at the next step. Returns whether it did.
bool reduce_cell_tilt(Model& model);


}  // namespace trubal
