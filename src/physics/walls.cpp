#include "physics/walls.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "physics/cell.hpp"

namespace trubal {

const Wall* find_wall(const Model& model, std::int64_t id) {
  const auto it = std::lower_bound(model.walls.begin(), model.walls.end(), id,
                                   [](const Wall& w, std::int64_t v) { return w.id < v; });
  return it != model.walls.end() && it->id == id ? &*it : nullptr;
}

double wall_servo_area(const Model& model, const Wall& w) {
  if (w.servo_area > 0) return w.servo_area;
  if (w.area_walls[0] != 0) {
    const Wall* a = find_wall(model, w.area_walls[0]);
    if (!a) return 0;
    if (w.kind != WallKind::Cylinder) return a->kind == WallKind::Cylinder ? M_PI * a->radius * a->radius : 0;
    const Wall* b = find_wall(model, w.area_walls[1]);
    if (!b) return 0;
    double gap = 0;
    for (int k = 0; k < 3; ++k) gap += (b->point[k] - a->point[k]) * w.normal[k];
    return 2 * M_PI * w.radius * std::abs(gap);
  }
  return wall_area(w);
}

double wall_position(const Wall& w) {
  if (w.kind == WallKind::Cylinder) return w.radius;
  return w.point[0] * w.normal[0] + w.point[1] * w.normal[1] + w.point[2] * w.normal[2];
}

double wall_stress(const Model& model, const Wall& w) {
  const double area = wall_servo_area(model, w);
  return area > 0 ? w.normal_force / area : 0;
}

void stop_servo_motion(Wall& w) {
  if (w.kind == WallKind::Cylinder) {
    w.radius_rate = 0;
    return;
  }
  const double along = w.velocity[0] * w.normal[0] + w.velocity[1] * w.normal[1] + w.velocity[2] * w.normal[2];
  for (int a = 0; a < 3; ++a) w.velocity[a] -= along * w.normal[a];
}

double default_wall_speed(const Model& model, double dt) {
  double r = std::numeric_limits<double>::infinity();
  for (double v : model.balls.rad) r = std::min(r, v);
  return dt > 0 && std::isfinite(r) ? 1e-4 * r / dt : 0;
}

void walls_before_step(Model& model, double dt) {
  double fallback = -1;   // default_wall_speed, found once
  for (Wall& w : model.walls) {
    if (!w.servo_on) { w.servo_integral = 0; continue; }
    const double area = wall_servo_area(model, w);
    // No area (a save older than format 8 lost the wall it came from): the servo cannot measure a
    // stress, and the wall stands until SERVO wall n is given again.
    if (!(area > 0)) {
      stop_servo_motion(w);
      continue;
    }
    if (fallback < 0) fallback = default_wall_speed(model, dt);
    const double most = w.servo_max_speed > 0 ? w.servo_max_speed : fallback;
    // The stress follows the wall's advance s as sum k_n s / A: G = f A / (sum k_n dt).
    const double k = w.stiffness / area;
    const double gain = w.servo_gain > 0 ? w.servo_gain
                        : (k > 0 && dt > 0 ? kServoFraction / (k * dt) : std::numeric_limits<double>::infinity());
    const double closes = k > 0 && dt > 0 ? std::min(1.0, gain * k * dt) : 0.0;
    const double error = w.servo_target - wall_stress(model, w);   // too little: advance into the balls
    // The advance: along the normal for a plane or polygon, the radius shrinking for a container
    // cylinder, growing for one the balls are outside of.
    const double sense = w.kind == WallKind::Cylinder ? (w.inside ? -1.0 : 1.0) : 1.0;
    double now;
    if (w.kind == WallKind::Cylinder) {
      now = sense * w.radius_rate;
    } else {
      now = w.velocity[0] * w.normal[0] + w.velocity[1] * w.normal[1] + w.velocity[2] * w.normal[2];
    }
    const double speed = servo_rate(error, gain, closes, w.servo_integral, most, now);
    if (w.kind == WallKind::Cylinder) {
      w.radius_rate = sense * speed;
    } else {   // the component along the normal is the servo's; the others stay as given
      const double change = speed - now;
      for (int a = 0; a < 3; ++a) w.velocity[a] += change * w.normal[a];
    }
  }
}

}  // namespace trubal
