// STRAIN: strain rates of the periodic cell (compression positive).
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/cell.hpp"

namespace trubal {

// The periodic model, or an InputError saying why not.
Model& periodic_model(Context& ctx, Args& args, std::string_view command);

Model& periodic_model(Context& ctx, Args& args, std::string_view command) {
  if (!ctx.session.model().started) args.fail(fmt::format("{} needs a model: START first", command));
  if (!ctx.session.model().space.periodic)
    args.fail(fmt::format("{} acts on the periodic space (START x y z); this model is in a box", command));
  return ctx.session.edit();
}

static void run_strain(Context& ctx, Args& args) {
  const Model& now = ctx.session.model();
  std::array<double, 3> rates{now.space.strain_rate[0], now.space.strain_rate[1], now.space.strain_rate[2]};
  std::array<bool, 3> given{false, false, false};
  if (args.accept("off")) {
    args.done();
    rates = {0, 0, 0};
    given = {true, true, true};
  } else if (!args.empty() && match_keyword(args.peek(), {"xx", "yy", "zz", "xy", "xz", "yz"})) {
    while (!args.empty()) {
      const auto k = args.expect({"xx", "yy", "zz", "xy", "xz", "yz"}, "strain-rate component");
      const double r = args.real("strain rate");
      if (!std::isfinite(r)) args.fail("the strain rate must be a finite number");
      if (k >= 3) {
        if (r != 0) args.fail("shear strain rates (xy xz yz) are not available yet: only xx yy zz");
        continue;
      }
      rates[k] = r;
      given[k] = true;
    }
  } else {
    for (int a = 0; a < 3; ++a) {
      rates[a] = args.real(fmt::format("e{0}{0}", a + 1));
      given[a] = true;
    }
    for (const char* name : {"e12", "e13", "e23"})
      if (!args.empty() && args.real(name) != 0)
        args.fail("shear strain rates (e12 e13 e23) are not available yet: give 0 or leave them out");
    args.done();
  }
  Model& m = periodic_model(ctx, args, "STRAIN");
  for (int a = 0; a < 3; ++a)
    if (given[a]) m.space.servo_on[a] = false;   // STRAIN takes an axis back from the servo
  set_strain_rates(m, rates);
  const auto& r = m.space.strain_rate;
  ctx.out << fmt::format("strain rates: xx {:.6g}  yy {:.6g}  zz {:.6g}{}\n", r[0], r[1], r[2],
                         m.space.servo_on[0] || m.space.servo_on[1] || m.space.servo_on[2] ? " (servo on the others)"
                                                                                             : "");
}

const Command strain_command = {
    "STRAIN", {}, "STRAIN e11 e22 e33 [e12 e13 e23]  |  STRAIN xx r [yy r] [zz r]  |  STRAIN off",
    "strain rates of the periodic space",
    "Sets the strain rates of the periodic cell, per unit time, compression positive: `STRAIN 0 0 1e-4` "
    "shortens the z edge by 1e-4 of its length per unit time. The cell deforms about its centre; ball "
    "velocities include the homogeneous field v = -rate (x - centre), so a change of rate changes every "
    "free ball's velocity at once (its kinetic energy change counts as boundary work), and a ball wrapped "
    "across a face has its velocity changed by the cell's edge velocity. The keyword form sets only the axes "
    "named (the servo keeps the others); a STRAIN axis is taken from the servo. `STRAIN off` stops the "
    "straining (and the servo). The accumulated strain (sum of rate dt, compression positive) is in PRINT "
    "strain and HIST strain. Shear rates (e12 e13 e23, xy xz yz) are not available yet.",
    {"xx", "yy", "zz", "xy", "xz", "yz", "off"}, run_strain};

}  // namespace trubal
