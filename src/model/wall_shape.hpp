// The geometry of walls (model/model.hpp Wall): the nearest point of a wall to a ball's centre,
// the velocity of the wall's surface there, its area, and its motion over a step.
#pragma once

#include <array>
#include <string>

#include "model/model.hpp"

namespace trubal {

using Vec3 = std::array<double, 3>;

// Where a wall is, seen from a ball centre: `gap` the distance from the centre to the wall's nearest
// point (signed for one-sided walls: negative once the centre is past the surface), `dir` the unit
// vector from the centre toward that point (for a one-sided wall the inward normal, wherever the
// centre is), so the contact point is centre + gap dir. `radial`: a cylinder's outward radial unit
// vector at that point (the direction its radius rate moves the surface).
struct WallTouch {
  double gap = 0;
  Vec3 dir{0, 0, -1};
  Vec3 radial{0, 0, 0};
};

// The nearest point of the wall to centre c (any c, also NaN: then gap is NaN).
WallTouch wall_touch(const Wall& wall, const Vec3& c);

// How a ball of radius r centred at c lies against a wall, for placing balls (GEN places none that is
// not clear; BALL warns). `gap`: from the ball's surface to the wall, negative where the ball crosses
// the wall or lies on its wrong side; `wrong_side`: the centre is where the wall keeps balls out of
// (behind a plane; outside a container cylinder's radius or beyond its ends; within an outside
// cylinder's radius along its length); `beyond_end`: how far a container cylinder's ball centre lies
// past one of its ends (0 within its length; there the gap is -beyond_end - r). A polygon has no wrong
// side. A ball is clear of the wall when gap >= 0.
struct WallClearance {
  double gap = 0;
  bool wrong_side = false;
  double beyond_end = 0;
};
WallClearance wall_clearance(const Wall& wall, const Vec3& c, double r);

// Velocity of the wall's surface at point p (translation, spin about spin_point, radius rate).
Vec3 wall_surface_velocity(const Wall& wall, const Vec3& p, const WallTouch& touch);

// The area the wall's stress is taken over: polygon its area, cylinder its lateral area 2 pi r L,
// plane 0 (an infinite plane has none: SERVO wall needs `area`).
double wall_area(const Wall& wall);

// Moves the wall through one step of dt (translation, then the spin about the moved spin point,
// then the radius) and returns an upper bound of how far any point of its surface moved (infinite
// for a spinning infinite plane).
double move_wall(Wall& wall, double dt);

// Checks a wall's geometry and completes it: normalises the normal or axis, and a polygon's normal
// from its vertices. Returns what is wrong ("" when nothing is).
std::string complete_wall(Wall& wall);

// The wall's centre: a polygon's vertex mean, a cylinder's axis midpoint, a plane's point (the
// default spin point and what PRINT walls shows).
Vec3 wall_centre(const Wall& wall);

// Kind names for PRINT and messages.
const char* wall_kind_name(WallKind kind);

}  // namespace trubal
