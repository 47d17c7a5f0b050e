// SERVO: the periodic cell's strain rates driven toward target average stresses.
#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/cell.hpp"
#include "physics/walls.hpp"

namespace trubal {

Model& periodic_model(Context& ctx, Args& args, std::string_view command);

// SERVO wall n ...: the wall's speed along its normal (a cylinder: its radius) holds a stress.
static void servo_wall(Context& ctx, Args& args) {
  ctx.session.require_started();
  const std::int64_t id = args.count("wall id", 1);
  const Model& now = ctx.session.state();   // (the walls alone are read)
  const Wall* found = find_wall(now, id);
  if (!found) args.fail(fmt::format("there is no wall {} (PRINT walls lists them)", id));
  const std::size_t k = static_cast<std::size_t>(found - now.walls.data());
  Wall w = *found;
  if (args.accept("off")) {
    args.done();
    Model& m = ctx.session.edit_walls();
    m.walls[k].servo_on = false;
    m.walls[k].servo_integral = 0;
    stop_servo_motion(m.walls[k]);   // the servo's motion stops with it
    ctx.out << fmt::format("wall {}: servo off\n", id);
    return;
  }
  args.expect({"stress"}, "`stress s` (the target, compression positive) or `off`");
  w.servo_target = args.real("target stress");
  auto wall_id = [&](const char* what) {
    const std::int64_t other = args.count(what, 1);
    if (!find_wall(now, other)) args.fail(fmt::format("there is no wall {} (PRINT walls lists them)", other));
    if (other == id) args.fail("a wall's area cannot come from itself");
    return other;
  };
  while (!args.empty()) {
    const auto opt = args.expect({"gain", "max", "area", "in", "between"}, "SERVO wall option");
    if (opt == 3) {   // a platen in a cylinder: pi r^2
      if (w.kind == WallKind::Cylinder) args.fail("`in c` is for a platen (a plane or polygon) in cylinder c");
      w.area_walls = {wall_id("cylinder id"), 0};
      if (find_wall(now, w.area_walls[0])->kind != WallKind::Cylinder) args.fail("`in c` names a cylinder");
      w.servo_area = 0;
      continue;
    }
    if (opt == 4) {   // a cylinder between two platens: 2 pi r h
      if (w.kind != WallKind::Cylinder) args.fail("`between a b` is for a cylinder between platens a and b");
      w.area_walls[0] = wall_id("platen id");
      w.area_walls[1] = wall_id("platen id");
      w.servo_area = 0;
      continue;
    }
    const double v = args.real(opt == 0 ? "gain" : opt == 1 ? "max speed" : "area");
    if (!(v >= 0) || !std::isfinite(v)) args.fail("gain, max speed and area must be finite and not negative (0: default)");
    (opt == 0 ? w.servo_gain : opt == 1 ? w.servo_max_speed : w.servo_area) = v;
  }
  if (!std::isfinite(w.servo_target)) args.fail("the target stress must be finite");
  Model probe;   // the area with this wall's new settings
  probe.walls = now.walls;
  probe.walls[k] = w;
  if (!(wall_servo_area(probe, w) > 0))
    args.fail("an infinite plane has no area of its own: give `area a` (the platen's loaded area) or `in c` "
              "(the cross-section of cylinder c)");
  w.servo_on = true;
  Model& m = ctx.session.edit_walls();
  m.walls[k] = w;
  ctx.out << fmt::format("wall {}: servo to stress {:.6g} over area {:.6g}, gain {}, max speed {}\n", id,
                         w.servo_target, wall_servo_area(probe, w),
                         w.servo_gain > 0 ? fmt::format("{:.4g}", w.servo_gain) : std::string("default"),
                         w.servo_max_speed > 0 ? fmt::format("{:.4g}", w.servo_max_speed) : std::string("default"));
}

static void run_servo(Context& ctx, Args& args) {
  if (args.accept("wall")) return servo_wall(ctx, args);
  const Model& now = ctx.session.state();   // (the cell's settings alone are read)
  std::array<bool, 3> on = now.space.servo_on;
  std::array<double, 3> target = now.space.servo_target;
  double gain = now.space.servo_gain, most = now.space.servo_max_rate;
  if (args.accept("off")) {
    args.done();
    Model& m = periodic_model(ctx, args, "SERVO");
    std::array<double, 3> rates{m.space.strain_rate[0], m.space.strain_rate[1], m.space.strain_rate[2]};
    for (int a = 0; a < 3; ++a)
      if (m.space.servo_on[a]) rates[a] = 0;   // the servo's axes stop; STRAIN axes keep their rate
    m.space.servo_on = {false, false, false};
    const auto& r = m.space.strain_rate;
    ctx.session.set_cell_rates({rates[0], rates[1], rates[2], r[3], r[4], r[5]});
    ctx.out << "servo off\n";
    return;
  }
  auto options = [&] {
    while (!args.empty()) {
      const auto k = args.expect({"gain", "max"}, "SERVO option");
      const double v = args.real(k == 0 ? "gain" : "max rate");
      if (!(v >= 0) || !std::isfinite(v)) args.fail("gain and max rate must be finite and not negative (0: default)");
      (k == 0 ? gain : most) = v;
    }
  };
  if (!args.empty() && match_keyword(args.peek(), {"xx", "yy", "zz"})) {
    while (!args.empty() && match_keyword(args.peek(), {"xx", "yy", "zz"})) {
      const auto k = args.expect({"xx", "yy", "zz"}, "stress component");
      target[k] = args.real("target stress");
      on[k] = true;
    }
  } else {
    for (int a = 0; a < 3; ++a) {
      target[a] = args.real(fmt::format("s{0}{0}", a + 1));
      on[a] = true;
    }
  }
  options();
  // STRAIN's bound on what a step may do to the cell, for the fastest rate the servo may choose:
  // checked here where the step is known (TSTEP, or the last CYCLE's), else before the first step.
  const double dt = now.settings.fixed_dt > 0 ? now.settings.fixed_dt : now.dt;
  if (most > 0 && dt > 0 && !(most * dt <= kMostEdgeChangePerStep))
    args.fail(fmt::format("max rate {:.4g} would change a cell edge by {:.3g} of its length in one step of {:.3g} (at "
                          "most {}): give at most {:.3g}",
                          most, most * dt, dt, kMostEdgeChangePerStep, kMostEdgeChangePerStep / dt));
  for (double t : target)
    if (!std::isfinite(t)) args.fail("target stresses must be finite");
  for (int a = 0; a < 3; ++a)
    if (on[a] && now.space.periodic && !now.space.wraps(a))
      args.fail(fmt::format("the space is bounded across {0}: the servo can drive only its periodic axes (SERVO wall "
                            "drives a wall across {0})", "xyz"[a]));
  Model& m = periodic_model(ctx, args, "SERVO");
  m.space.servo_on = on;
  m.space.servo_target = target;
  m.space.servo_gain = gain;
  m.space.servo_max_rate = most;
  std::string axes;
  for (int a = 0; a < 3; ++a)
    if (on[a]) axes += fmt::format("  {} {:.6g}", a == 0 ? "xx" : a == 1 ? "yy" : "zz", target[a]);
  ctx.out << fmt::format("servo targets:{}  gain {}  max rate {}\n", axes,
                         gain > 0 ? fmt::format("{:.4g}", gain) : std::string("default"),
                         most > 0 ? fmt::format("{:.4g}", most) : std::string("default"));
}

const Command servo_command = {
    "SERVO", {}, "SERVO s11 s22 s33 [gain g] [max r]  |  SERVO xx s [yy s] [zz s] [gain g] [max r]  |  SERVO off  "
    "|  SERVO wall n stress s [gain g] [max v] [area a | in c | between a b]  |  SERVO wall n off",
    "stress servo of the periodic space, or of a wall",
    "Drives the strain rates of the periodic cell so that the average stress (over the cell volume, "
    "compression positive) holds the targets, each axis on its own, by proportional-integral control: before "
    "every step rate = g (target - sigma) + I, where the integral term I grows each step by f/4 times the "
    "proportional rate, f = g M dt the fraction of the error the gain closes per step (critical damping if "
    "the stress followed the contact stiffness at once), so that a steady loading (STRAIN on another axis, "
    "dilation under shear) is held without offset; the rate is limited to +-max and changes by at most max/4 "
    "per step, and I does not grow past the limits. The keyword form servoes only the axes named; the others "
    "keep their STRAIN rate (STRAIN zz r with SERVO xx s yy s is drained triaxial compression). The default "
    "gain (gain 0 or absent) is recomputed every step from the last force pass: g = 0.15 / (M dt) with "
    "M = (1/V) sum k_n (l n_a)^2 over the touching contacts, so that the stress would close 15% of its error "
    "per step (PFC's gain rule in stress form). The default max rate is 1e-4 / dt (the cell changes by at "
    "most 1e-4 of its size per step), which is also the rate used while nothing touches (I is then 0). As "
    "for STRAIN, max times the step may not pass 0.5 (half an edge in one step): SERVO refuses a larger max "
    "where the step is known (TSTEP, or after a CYCLE), and CYCLE before its first step. "
    "`SERVO off` stops the servo; its axes stop straining. The integral is state: SAVE keeps it. "
    "`SERVO wall n stress s` drives wall n instead (PFC's servo-controlled platen): its speed along its normal "
    "(toward the balls for a plane; the right-hand normal of a polygon's vertex order, so order them to face "
    "the balls), or for a cylinder its radius rate (shrinking for balls inside), follows the same "
    "proportional-integral law on the wall's stress: the sum of its contacts' normal forces over its area "
    "(a polygon's own, a cylinder's lateral 2 pi r l; a plane has none, so `area a` is needed, and `area` "
    "overrides the others). For a triaxial test in a cylinder the areas follow the sample: `in c` gives a "
    "platen the cross-section pi r^2 of cylinder c, `between a b` gives a cylinder 2 pi r h, h the distance "
    "between platens a and b along its axis; the areas stay for PRINT walls and HIST wall after SERVO wall "
    "off. The default gain is G = 0.15 A / (sum k_n dt) over the wall's touching "
    "contacts; the default max speed 1e-4 of the smallest ball radius per step, also the speed at which a "
    "wall touching nothing approaches. The other velocity components stay as WALL set them. `SERVO wall n "
    "off` stops it (and its motion along the normal).",
    "servo 1e5 1e5 1e5",
    {"xx", "yy", "zz", "gain", "max", "off", "wall", "stress", "area", "in", "between"}, run_servo, false, false, OnRanks::Parts,
    HeldUse::Keep, {}, nullptr, {"off"}};

}  // namespace trubal
