// Ball-wall contacts and the wall servo (doc/physics.md "Walls").
//
// A ball-wall contact is computed by the ball-pair law itself (physics/contact_law.hpp), so that
// every part of it (linear or Hertz-Mindlin, friction, cohesion, dashpots) is the same code: the
// ball of radius R is ball i, and the wall is a partner j of radius 2R whose centre lies 3R + gap
// from the ball's centre along the direction to the wall's nearest point. Then R_i + R_j - d is the
// overlap R - gap, the normal is that direction, and R* = R_i R_j / (R_i + R_j) = R, the effective
// radius of a sphere on a flat surface (Hertz). The partner moves with the wall's surface at the
// contact point and has infinite mass (the dashpot's m* is the ball's mass); the spin term is the
// ball's alone (R w). The ball's moment arm is R, as for ball pairs.
#pragma once

#include <array>
#include <bit>
#include <cstdint>

#include "model/model.hpp"
#include "model/wall_shape.hpp"

namespace trubal {

// The inputs of one ball-wall contact, as the pair law reads them.
struct WallLane {
  double dx, dy, dz;          // "x_j - x_i": dir (3R + gap)
  double r;                   // radius of both lanes' balls: 2R
  Vec3 point;                 // the contact point on the wall: centre + gap dir
  Vec3 velocity;              // the wall's surface velocity there
};

// Whether the wall stands still: no velocity (+0 in every component), spin or radius rate, so its
// surface velocity (wall_surface_velocity) is +0 everywhere.
inline bool wall_still(const Wall& w) {
  return std::bit_cast<std::uint64_t>(w.velocity[0]) == 0 && std::bit_cast<std::uint64_t>(w.velocity[1]) == 0 &&
         std::bit_cast<std::uint64_t>(w.velocity[2]) == 0 && w.spin[0] == 0 && w.spin[1] == 0 && w.spin[2] == 0 &&
         w.radius_rate == 0;
}

// A centre past a one-sided wall by more than R (or NaN) is no contact: gap is then taken as 2R.
inline WallLane wall_lane(const Wall& wall, const Vec3& centre, double radius) {
  const WallTouch t = wall_touch(wall, centre);
  const double gap = t.gap > -radius ? t.gap : 2 * radius;
  const double d = 3 * radius + gap;
  WallLane lane;
  lane.dx = t.dir[0] * d; lane.dy = t.dir[1] * d; lane.dz = t.dir[2] * d;
  lane.r = 2 * radius;
  lane.point = {centre[0] + t.dir[0] * gap, centre[1] + t.dir[1] * gap, centre[2] + t.dir[2] * gap};
  // (A wall standing still: its surface velocity is +0 in every component, as the sum would give.)
  lane.velocity = wall_still(wall) ? Vec3{0, 0, 0} : wall_surface_velocity(wall, lane.point, t);
  return lane;
}

// The stress a wall carries (compression positive): the sum of its contacts' normal forces
// (Wall::normal_force) over wall_servo_area.
double wall_stress(const Model& model, const Wall& wall);
// Where a wall is, as one number (HIST wall's pos): a cylinder's radius; a plane's or polygon's
// offset along its normal, point . normal (for a platen with normal +z or -z: +-its height).
double wall_position(const Wall& wall);
// The area the stress is over: the SERVO's `area`, or from other walls (Wall::area_walls: a platen
// inside a cylinder, a cylinder between platens), or the wall's own (model/wall_shape.hpp
// wall_area; 0 for a plane).
double wall_servo_area(const Model& model, const Wall& wall);
// The wall with this id, or nullptr.
const Wall* find_wall(const Model& model, std::int64_t id);

// The wall servo, proportional-integral as the cell's (physics/cell.hpp: kServoFraction,
// kServoIntegral): before a step, each servo-driven wall's speed along its normal (a cylinder: its
// radius rate) from the stress and stiffness of the last force pass. The default gain closes
// kServoFraction of the error per step if the stress followed the contact stiffness at once,
// G = f A / (sum k_n dt) (PFC's rule); the speed is limited to the SERVO's max, by default
// default_wall_speed (where nothing touches, the wall moves at that speed toward the balls).
void walls_before_step(Model& model, double dt);
// Stops the motion a wall servo drives: a cylinder's radius rate, or a plane's or polygon's velocity
// along its normal (the other components stay as WALL set them).
void stop_servo_motion(Wall& wall);
// The default largest servo speed: 1e-4 of the smallest ball radius per step.
double default_wall_speed(const Model& model, double dt);

}  // namespace trubal
