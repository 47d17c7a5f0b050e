// Where GEN may put balls: the START box (or the periodic space) cut by the range and by the walls.
// A ball goes only where it touches no wall and lies on each wall's side (model/wall_shape.hpp
// wall_clearance), so that the first CYCLE does not throw it through one.
#pragma once

#include <array>
#include <vector>

#include "model/model.hpp"
#include "model/range.hpp"
#include "model/wall_shape.hpp"

namespace trubal {

// Whether a ball of radius r at c is clear of every wall (touching counts as clear).
bool clear_of_walls(const std::vector<Wall>& walls, const Vec3& c, double r);

// GEN's region: the box cut by the range's x, y, z intervals (on a bounded axis, the box's or one the
// range cuts, balls lie wholly inside; on a periodic one the centres anywhere in the period), the
// range's cylinders (about lines along z; balls wholly inside) and the walls' allowed sides.
struct Region {
  std::array<double, 3> lo{}, hi{};
  std::array<bool, 3> bounded{};
  std::vector<std::array<double, 3>> cylinders;   // range cylinder: x y radius
  std::vector<Wall> walls;

  // Whether anything but the box bounds it (then volume() integrates and the relaxation pushes).
  bool curved() const { return !cylinders.empty() || !walls.empty(); }
  // Whether a ball of radius r at c lies wholly inside the cylinders and clear of the walls (the
  // box's faces are the caller's: it draws centres inside them).
  bool admits(const Vec3& c, double r) const;
  // Whether a centre lies in the region (box, cylinders, the walls' sides): a ball already there
  // counts toward the porosity.
  bool holds_centre(const Vec3& c) const;
  // Moves a ball of radius r back inside the cylinders and clear of the walls, each excess moved
  // `push` times over (over-relaxation, as the relaxation's faces), the box's faces clamped after.
  void push_inside(std::array<double, 4>& b, double r, double push) const;
  // The largest excess left, over r: how far the ball crosses a face, cylinder or wall (0: clear).
  double excess(const std::array<double, 4>& b, double r) const;
  // The volume of the region (the box cut by the range's intervals and cylinders and by the walls'
  // sides). A box is exact; otherwise a midpoint rule over 2048 x 2048 lines, each line's length
  // inside the region exact (its intervals in planes and cylinders solved): the boundary cuts the
  // grid's cells, which puts the relative error near 1e-5 (within 1e-4 against pi r^2 h for a
  // cylinder in a box, tests/unit/gen_walls.cpp). The same on every machine: fixed grid and order.
  double volume() const;
};

// GEN's region for the balls of a size distribution: the range's x, y, z intervals and cylinders
// bound whole balls. box_only (GEN porosity): any other range element has no volume to fill and is
// an error. Throws where the range leaves no room along an axis.
Region region_of(const Space& space, const Range& range, const std::vector<Wall>& walls, bool box_only);

// The volume balls of radius up to rmax, centred where a range holds, may fill (GEN n rlo rhi's
// estimate of how many fit, an upper bound): the box cut by the range's x, y, z intervals and
// cylinders widened by rmax (its other elements left out) and by the walls' sides.
double room_for_centres(const Space& space, const Range& range, const std::vector<Wall>& walls, double rmax);

}  // namespace trubal
