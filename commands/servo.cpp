// SERVO: the periodic cell's strain rates driven toward target average stresses.
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/cell.hpp"

namespace trubal {

Model& periodic_model(Context& ctx, Args& args, std::string_view command);

static void run_servo(Context& ctx, Args& args) {
  const Model& now = ctx.session.model();
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
    set_strain_rates(m, rates);
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
  for (double t : target)
    if (!std::isfinite(t)) args.fail("target stresses must be finite");
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
    "SERVO", {}, "SERVO s11 s22 s33 [gain g] [max r]  |  SERVO xx s [yy s] [zz s] [gain g] [max r]  |  SERVO off",
    "stress servo of the periodic space",
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
    "most 1e-4 of its size per step), which is also the rate used while nothing touches (I is then 0). "
    "`SERVO off` stops the servo; its axes stop straining. The integral is state: SAVE keeps it.",
    {"xx", "yy", "zz", "gain", "max", "off"}, run_servo};

}  // namespace trubal
