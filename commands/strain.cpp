// STRAIN: strain rates of the periodic cell (compression positive).
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/cell.hpp"

namespace trubal {

// The periodic model, or an InputError saying why not.
Model& periodic_model(Context& ctx, Args& args, std::string_view command);

// (The cell's settings alone are read and changed: Session::edit_cell, which leaves a distributed
// run's kept parts as they are.)
Model& periodic_model(Context& ctx, Args& args, std::string_view command) {
  if (!ctx.session.state().started) args.fail(fmt::format("{} needs a model: START first", command));
  if (!ctx.session.state().space.periodic)
    args.fail(fmt::format("{} acts on the periodic space (START x y z); this model is in a box", command));
  return ctx.session.edit_cell();
}

static void run_strain(Context& ctx, Args& args) {
  const Model& now = ctx.session.state();
  std::array<double, 6> rates = now.space.strain_rate;
  std::array<bool, 3> given{false, false, false};
  if (args.accept("reset")) {   // the accumulated strain starts again at 0 (a new stage); the rates stay
    args.done();
    Model& m = periodic_model(ctx, args, "STRAIN");
    m.space.strain = {0, 0, 0, 0, 0, 0};
    m.space.reference_volume = m.space.volume();   // and the volumetric strain with it
    ctx.out << "accumulated strain set to 0 (the rates are unchanged)\n";
    return;
  }
  if (args.accept("off")) {
    args.done();
    rates = {0, 0, 0, 0, 0, 0};
    given = {true, true, true};
  } else if (!args.empty() && match_keyword(args.peek(), {"xx", "yy", "zz", "xy", "xz", "yz"})) {
    while (!args.empty()) {
      const auto k = args.expect({"xx", "yy", "zz", "xy", "xz", "yz"}, "strain-rate component");
      const double r = args.real("strain rate");
      if (!std::isfinite(r)) args.fail("the strain rate must be a finite number");
      rates[k] = r;
      if (k < 3) given[k] = true;
    }
  } else {
    const char* names[6] = {"e11", "e22", "e33", "e12", "e13", "e23"};
    for (int a = 0; a < 6; ++a) {
      if (a >= 3 && args.empty()) {   // shear rates left out: none
        rates[a] = 0;
        continue;
      }
      rates[a] = args.real(names[a]);
      if (!std::isfinite(rates[a])) args.fail("the strain rate must be a finite number");
      if (a < 3) given[a] = true;
    }
    args.done();
  }
  {   // a mixed space: only the periodic axes deform (a shear component needs both of its axes)
    const Space& s = now.space;
    const char* names[6] = {"xx", "yy", "zz", "xy", "xz", "yz"};
    const int axes[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    for (int k = 0; k < 6; ++k)
      if (rates[k] != 0 && s.periodic && !(s.wraps(axes[k][0]) && s.wraps(axes[k][1])))
        args.fail(fmt::format("STRAIN {} needs {} periodic; this space is bounded across {} (move walls instead)",
                              names[k], k < 3 ? "that axis" : "both of its axes",
                              std::string(1, "xyz"[s.wraps(axes[k][0]) ? axes[k][1] : axes[k][0]])));
  }
  Model& m = periodic_model(ctx, args, "STRAIN");
  for (int a = 0; a < 3; ++a)
    if (given[a]) m.space.servo_on[a] = false;   // STRAIN takes an axis back from the servo
  ctx.session.set_cell_rates(rates);
  const auto& r = m.space.strain_rate;
  const bool shear = r[3] != 0 || r[4] != 0 || r[5] != 0;
  ctx.out << fmt::format("strain rates: xx {:.6g}  yy {:.6g}  zz {:.6g}{}{}\n", r[0], r[1], r[2],
                         shear ? fmt::format("  xy {:.6g}  xz {:.6g}  yz {:.6g}", r[3], r[4], r[5]) : std::string(),
                         m.space.servo_on[0] || m.space.servo_on[1] || m.space.servo_on[2] ? " (servo on the others)"
                                                                                             : "");
}

const Command strain_command = {
    "STRAIN", {},
    "STRAIN e11 e22 e33 [e12 e13 e23]  |  STRAIN xx r [yy r] [zz r] [xy r] [xz r] [yz r]  |  STRAIN off  |  STRAIN reset",
    "strain rates of the periodic space",
    "Sets the strain rates of the periodic cell, per unit time, compression positive: `STRAIN 0 0 1e-4` "
    "shortens the z edge by 1e-4 of its length per unit time. The cell deforms about its centre; ball "
    "velocities include the homogeneous field v = L (x - centre), L the velocity gradient, so a change of rate "
    "changes every free ball's velocity at once (its kinetic energy change counts as boundary work), and a "
    "ball wrapped across a face has its velocity changed by that face's velocity. The shear rates e12 e13 e23 "
    "(xy xz yz) are tensor components applied as simple shear: e12 moves the faces normal to y along x, "
    "L_xy = -2 e12 (for e12 > 0 the upper y face moves toward -x, and sigma_12 grows positive); e13 and e23 "
    "move the faces normal to z along x and y. The cell becomes a parallelepiped: an image across the y faces "
    "is shifted along x by the accumulated offset (Lees-Edwards), and the offsets are kept within half an "
    "edge by renaming images, so shear may go on without end. The positional form sets all six rates (the "
    "shear rates 0 when left out); the keyword form sets only the components named (the servo keeps the "
    "other axes); a STRAIN axis is taken from the servo. `STRAIN off` stops the straining (and the servo). "
    "After each step an edge L becomes L exp(-rate dt), so the accumulated strain on a normal axis (sum of rate "
    "dt) is the natural strain -ln(L/L0) exactly, and rates whose sum is zero (`STRAIN -0.25 -0.25 0.5`, an "
    "undrained test) keep the volume to rounding. "
    "The accumulated strain (sum of rate dt, compression positive, tensor shear components) is in PRINT "
    "strain and HIST strain (e11 ... e23); the cell's tilts are in PRINT info. `STRAIN reset` sets the "
    "accumulated strain to 0 and leaves the rates and the cell as they are, so that a new stage (shear after "
    "the isotropic compression) is measured from its own start.",
    "strain 0 0 1e-3",
    {"xx", "yy", "zz", "xy", "xz", "yz", "off", "reset"}, run_strain, false, false, OnRanks::Parts};

}  // namespace trubal
