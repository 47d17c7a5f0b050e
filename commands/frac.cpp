#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_frac(Context& ctx, Args& args) {
  double f = args.real("f");
  args.done();
  if (!(f > 0)) args.fail("FRAC must be positive");
  if (f > 1) ctx.warn(fmt::format("FRAC {} is above the critical step: the run will likely go unstable", f));
  ctx.session.settings().frac = f;
  ctx.session.settings().fixed_dt = 0;
}

const Command frac_command = {
    "FRAC", {}, "FRAC f", "time step as a fraction of the critical step",
    "The time step is f times the critical step, estimated every cycle from the stiffest ball (default "
    "0.8). The critical step is held through contact episodes and renewed only between them (no ball stiffer than "
    "a lone ball), when stability needs it (f times the held step above 0.9 of the estimate) or when the estimate "
    "has doubled (linear contacts: grown max(0.9, f)/f times, 1.125 at 0.8), so a collision's rebound does not depend on contacts that form and break elsewhere (man page, "
    "CONVENTIONS). Where the step changes, the velocities move by F/m times the mean of the step before and this one "
    "(velocity Verlet with a changing step, as LAMMPS's fix dt/reset), so a collision in progress stays second "
    "order. The default is for stability, not for "
    "resolving collisions: an impact's rebound is off by a few percent at 0.8 (CYCLE warns where the energy "
    "balance shows it; man page, CONVENTIONS, says why the default stays). Cancels a fixed TSTEP.",
    "frac 0.5",
    {}, run_frac, false, false, OnRanks::Parts, HeldUse::Keep};

static void run_tstep(Context& ctx, Args& args) {
  if (args.accept("auto")) {
    args.done();
    ctx.session.settings().fixed_dt = 0;
    return;
  }
  double dt = args.real("dt");
  args.done();
  if (!(dt > 0)) args.fail("TSTEP must be positive (TSTEP auto returns to FRAC)");
  ctx.session.settings().fixed_dt = dt;
}

const Command tstep_command = {
    "TSTEP", {}, "TSTEP dt  |  TSTEP auto", "fix the time step",
    "Fixes the time step to dt (the instability guard still watches the run). `TSTEP auto` goes back to "
    "FRAC times the critical step.",
    "tstep 1e-6",
    {"auto"}, run_tstep, false, false, OnRanks::Parts, HeldUse::Keep};

static void run_grav(Context& ctx, Args& args) {
  auto g = read_xyz(args, "gravity");
  args.done();
  ctx.session.settings().gravity = g;
}

const Command grav_command = {
    "GRAV", {}, "GRAV gx gy gz", "gravity",
    "Sets the gravitational acceleration (a body force m g on every ball). GRAV 0 0 0 turns it off.",
    "grav 0 0 -9.81",
    {},
    run_grav, false, false, OnRanks::Parts, HeldUse::Keep};

}  // namespace trubal
