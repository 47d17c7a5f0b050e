#include <cmath>
#include <numbers>
#include <optional>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/scene.hpp"

namespace trubal {

static void run_prop(Context& ctx, Args& args) {
  ctx.session.require_started();
  int type = 1;
  if (args.accept("type")) type = static_cast<int>(args.count("type", 1, 1000000));
  if (args.empty())
    args.fail("PROP needs at least one property (kn, ks, fric, mu, dens, coh, shear, poisson, rest, rr_fric, bridge, "
              "tension, angle)");
  const auto& materials = ctx.session.state().materials;   // (light state: every rank holds it)
  Material m = materials.count(type) ? materials.at(type) : Material{};
  static const std::vector<std::string_view> names = {"kn", "ks", "fric", "mu", "dens", "coh", "shear", "poisson",
                                                      "rest", "rr_fric", "bridge", "tension", "angle"};
  double small_angle = 0;   // a fric in (0, 1): a coefficient typed where an angle goes? (0: none)
  while (!args.empty()) {
    auto k = args.expect(names, "property");
    double v = args.real(names[k]);
    auto nonneg = [&] { if (v < 0) args.fail(fmt::format("{} must not be negative", names[k])); };
    switch (k) {
      case 0: nonneg(); m.kn = v; break;
      case 1: nonneg(); m.ks = v; break;
      case 2:
        if (v < 0 || v >= 90) args.fail("fric is a friction angle in degrees, in [0, 90)");
        m.friction = std::tan(v * std::numbers::pi / 180);
        small_angle = v > 0 && v < 1 ? v : 0;
        break;
      case 3: nonneg(); m.friction = v; small_angle = 0; break;
      case 4:
        if (!(v > 0)) args.fail("dens must be positive");
        m.density = v;
        break;
      case 5: nonneg(); m.cohesion = v; break;
      case 6: nonneg(); m.shear_modulus = v; break;
      case 7:
        if (v < -1 || v >= 0.5) args.fail("poisson must be in (-1, 0.5)");
        m.poisson = v;
        break;
      case 8:
        if (!(v > 0) || v > 1) args.fail("rest (restitution) must be in (0, 1]");
        m.restitution = v;
        m.has_restitution = v < 1;
        break;
      case 9: nonneg(); m.rolling_friction = v; break;
      case 10: nonneg(); m.bridge_volume = v; break;
      case 11: nonneg(); m.surface_tension = v; break;
      case 12:
        if (!(v >= 0) || v >= 90) args.fail("angle is the liquid's contact angle in degrees, in [0, 90)");
        m.contact_angle = v * std::numbers::pi / 180;
        break;
    }
  }
  if (m.bridge_volume > 0 && !(m.surface_tension > 0))
    args.fail("bridge V needs the liquid's surface tension: `tension gamma`, gamma > 0");
  ctx.session.set_material(type, m);
  // PFC's `fric` is the coefficient: 0.5 typed here is half a degree, mu 0.0087.
  if (small_angle > 0)
    ctx.warn(fmt::format("fric {0:g} is a friction angle in degrees: mu = tan({0:g} deg) = {1:.3g}; for a friction "
                         "coefficient of {0:g} write `mu {0:g}`", small_angle, m.friction));
}

const Command prop_command = {
    "PROP", {}, "PROP [type t] kn v ks v fric deg|mu v dens v [coh v] [shear G poisson nu] [rest e] [rr_fric mu_r] "
    "[bridge V tension gamma [angle deg]]",
    "material properties of a ball type",
    "Sets material properties of a type (default type 1); properties not named keep their value (0 at "
    "first). trubal has no units of its own (any consistent set will do); here they are SI (N, m, kg, s), "
    "as in the examples. kn, ks: normal and shear spring "
    "stiffness of the linear law, in N/m (force per metre of overlap or of shear displacement); "
    "fric: friction angle in degrees, mu = tan(fric) (a value between 0 and 1 gets a warning: a friction "
    "coefficient typed as an angle, as PFC's `fric` is the coefficient); mu: the friction coefficient itself, "
    "no unit (fric and mu set the same property; the later one wins); dens: density in kg/m^3; coh: cohesion "
    "in N, a force added to the Coulomb limit; shear G (Pa) and poisson nu (no unit, in (-1, 0.5)) select the "
    "Hertz-Mindlin law for the type, whose stiffness then follows from G, nu, the radii and the overlap (kn "
    "and ks are not used between two Hertz types); rest e (no unit, in (0, 1]) adds a contact dashpot giving "
    "restitution e in a head-on impact; rr_fric mu_r (no unit) adds rolling resistance, PFC's linear "
    "rolling-resistance model: a rolling spring of stiffness ks R^2 on the rolling part of the balls' "
    "relative rotation, its moment capped at mu_r R Fn, R = R1 R2 / (R1 + R2) between balls and the ball's "
    "radius at a wall (mu_r is a length ratio: a ball rolls when the moment about its contact exceeds mu_r R "
    "Fn; PRINT energy books the work lost as `rolling`); bridge V tension gamma [angle deg] wets the type: "
    "a capillary bridge of liquid volume V (m^3) forms where two balls (or a ball and a wall) touch and pulls "
    "them together with F = 2 pi R gamma cos(theta) / (1 + 2.1 S + 10 S^2), S = (s/2) sqrt(R/V), s the gap "
    "(F at contact while they touch), R = 2 R1 R2 / (R1 + R2) (twice the ball's radius at a wall), gamma the "
    "liquid's surface tension (N/m), theta its contact angle (default 0, in [0, 90)) (Willett et al. 2000); "
    "it breaks at s = (1 + theta/2) V^(1/3), theta in radians (Lian et al. 1993), and does not form again "
    "until the pair touches; PRINT energy books the bridges' work as `capillary`, HIST bridges counts them. "
    "kn and ks are the stiffness of a contact between two balls of this "
    "type; two types meet with k = 2 k1 k2 / (k1 + k2) (each ball a spring of stiffness 2k in series), the "
    "smaller friction, cohesion and rr_fric, and a bridge where both types have one, of the mean V, gamma "
    "and theta.",
    "prop kn 1e6 ks 1e6 fric 30 dens 2650",
    {"type", "kn", "ks", "fric", "mu", "dens", "coh", "shear", "poisson", "rest", "rr_fric", "bridge", "tension", "angle"},
    run_prop, true, false, OnRanks::ModelOnZero, HeldUse::Keep, {}, parts_where_kept};

}  // namespace trubal
