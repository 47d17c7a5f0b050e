#include <chrono>
#include <cmath>
#include <functional>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "interp/summary.hpp"
#include "physics/measure.hpp"
#include "physics/measure_sphere.hpp"
#include "physics/sample.hpp"
#include "support/comm.hpp"

namespace trubal {

// The one-line summary of a run: where it got to, how fast, and (in batch, where nobody watches
// the run) where the time went.
static void finish_run(Context& ctx, ProgressReporter& progress, const CycleResult& r, std::int64_t asked,
                       double seconds) {
  progress.finish();
  report_cycle_result(ctx, r, asked);
  if (r.interrupted && !ctx.interp.interactive)
    throw InputError(fmt::format("interrupted by {} at cycle {}",
                                 comm::size() > 1 ? "a signal (Ctrl-C at mpirun, or SIGUSR1)" : "Ctrl-C",
                                 ctx.session.state().cycle));
  const auto& m = ctx.session.state();   // cycle, time, counts: the deferred results are not read
  double rate = seconds > 0 ? r.done * static_cast<double>(m.balls.size()) / seconds : 0;
  std::string split = r.done > 0 && !ctx.interp.interactive ? phase_split(r.times, r.seconds) : "";
  ctx.out << fmt::format("cycle {}  time {:.6g}  timestep {:.6g}  ({} cycles in {:.3f} s, {:.3g} ball-cycles/s{}{})\n",
                         m.cycle, m.time, m.dt, r.done, seconds, rate, split.empty() ? "" : "; ", split);
}

// What CYCLE ... until may read: the sample's measures (SAMPLE) where one is declared, else the
// periodic cell's (its accumulated strain, compression positive, and its average stress with z
// axial); and the time.
static const std::vector<std::string_view> kUntilMeasures = {"axial", "volumetric", "q", "p", "sig1", "sig3", "time"};

static std::function<double(const Model&)> until_measure(Context& ctx, Args& args, std::size_t which) {
  if (which == 6) return [](const Model& m) { return m.time; };
  const Model& now = ctx.session.state();
  if (now.sample.declared())
    return [which](const Model& m) {
      const SampleMeasures s = sample_measures(m);
      const double values[] = {s.axial, s.volumetric, s.q, s.p, s.sigma1, s.sigma3};
      return values[which];
    };
  if (!now.space.periodic)
    args.fail(fmt::format("`until {}` reads the sample between walls: declare it first (SAMPLE platens a b "
                          "cylinder c), or run in a periodic cell",
                          kUntilMeasures[which]));
  if (which == 0) return [](const Model& m) { return m.space.strain[2]; };
  if (which == 1) return [](const Model& m) { return volumetric_strain(m); };
  Session& session = ctx.session;
  // (Rank 0's, summed on the ranks' parts where they keep them: Session::cycle_until.)
  return [which, &session](const Model&) {
    const TriaxialStress s = triaxial_stress(session.average_stress_in(session.stress_volume()));
    const double values[] = {s.q, s.p, s.sigma1, s.sigma3};
    return values[which - 2];
  };
}

// CYCLE [n] until what value [every k]: n (default kUntilLimit) is the most it runs.
constexpr std::int64_t kUntilLimit = 1000000;
constexpr std::int64_t kUntilEvery = 100;

static void run_cycle_until(Context& ctx, Args& args, std::int64_t limit) {
  const auto which = args.expect(kUntilMeasures, "`until` measure");
  const std::string name(kUntilMeasures[which]);
  const double target = args.real("target value");
  if (!std::isfinite(target)) args.fail("the target value must be finite");
  std::int64_t every = kUntilEvery;
  if (args.accept("every")) every = args.count("every (cycles between checks)", 1);
  args.done();
  ctx.session.require_started();
  const auto measure = until_measure(ctx, args, which);
  const auto start = std::chrono::steady_clock::now();
  ProgressReporter progress(ctx, true);
  const bool driven = which == 0 || which == 6;   // the axial strain and the time go one way
  const auto r = ctx.session.cycle_until(limit, measure, target, driven, every, progress.callback());
  finish_run(ctx, progress, r.run, limit, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (r.reached)
    ctx.out << fmt::format("reached {} {:.6g} (target {:.6g}, from {:.6g}) at cycle {}\n", name, r.value, target, r.start,
                           ctx.session.state().cycle);
  else if (r.run.interrupted || r.run.unstable)
    return;
  else if (r.stalled)
    ctx.warn(fmt::format("CYCLE stopped after {} cycles: {} stayed at {:.6g} (target {:.6g}); nothing moves it "
                         "(are the platens moving, or the cell straining?)",
                         r.run.done, name, r.value, target));
  else if (r.receding)
    ctx.warn(fmt::format("CYCLE stopped after {} cycles: {} went from {:.6g} to {:.6g}, away from the target {:.6g} "
                         "(it was past it already?)",
                         r.run.done, name, r.start, r.value, target));
  else
    ctx.warn(fmt::format("CYCLE stopped at the limit of {} cycles with {} {:.6g} (target {:.6g}, from {:.6g}): give "
                         "a larger n (CYCLE n until ...)",
                         limit, name, r.value, target, r.start));
}

static void run_cycle(Context& ctx, Args& args) {
  if (args.accept("until")) return run_cycle_until(ctx, args, kUntilLimit);
  auto n = args.count("n (number of cycles)", 0);
  if (args.accept("until")) return run_cycle_until(ctx, args, n);
  args.done();
  auto start = std::chrono::steady_clock::now();
  ProgressReporter progress(ctx);
  CycleResult r = ctx.session.cycle(n, progress.callback(), true, true);
  finish_run(ctx, progress, r, n, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

const Command cycle_command = {
    "CYCLE", {}, "CYCLE n  |  CYCLE [n] until what value [every k]", "n time steps, or until a measure reaches a value",
    "Runs n time steps. With `until`, runs until a measure reaches the value: at or above a positive "
    "value, at or below a negative one, across 0 from the side it starts on; none where it is there already "
    "(checked every k cycles, default 100; at most n cycles, default 1000000; a warning where the limit "
    "came first, where the measure has not moved at all over ten checks, or where axial or time went farther "
    "from the target at each of ten checks): axial, volumetric, q, p, sig1, sig3 (the sample's, SAMPLE; in a periodic cell without "
    "one, the cell's accumulated strain and its average stress, z axial), or time. Example: "
    "`cycle 400000 until axial 0.1` shears a triaxial sample to 10% axial strain. Ctrl-C stops at the end of the current step and keeps the model (in a batch run the "
    "deck then stops). Under mpirun, Ctrl-C ends the job (mpirun's way) and the output says at which cycle; "
    "SIGUSR1 sent to mpirun stops the CYCLE as Ctrl-C does without it. A run that goes unstable stops with a message naming the cycle, how much the energy "
    "balance grew over the last cycles (or that the velocities flip sign every cycle), the fastest ball and a "
    "suggested FRAC (from the energy's growth where it grew exponentially, at most half the FRAC), and leaves the "
    "last good state to print or save. When the energy balance (PRINT energy) "
    "moved during the CYCLE by more than 1% of the energy that moved (the largest energy in play: kinetic, "
    "strain, and the changes of the potential and the works), a warning says so once at the end, with the "
    "FRAC (or TSTEP) that would hold it, from the error falling as the step squared: the step is too coarse "
    "for what happened, mostly contacts that form and break within a few steps (impacts). At the end of each CYCLE "
    "(and SOLVE) the overlaps are looked at once: where one is past 0.1 of the smaller radius, a warning names the "
    "pair, the cycle and how many contacts are past it (said again only where the largest doubles; an overlap that "
    "grew and came back within the CYCLE is not seen). A long run shows its progress "
    "(cycles/s, time left): a bar redrawn in place at the interactive prompt, a plain line every 10 s "
    "otherwise (SET progress). At the end one line gives the cycle, time, step and speed, and in batch "
    "where the time went (contact detection, forces, motion, output).",
    "cycle 1000",
    {"until", "axial", "volumetric", "q", "p", "sig1", "sig3", "time", "every"}, run_cycle, false, false, OnRanks::Parts, HeldUse::Split};

static void run_solve(Context& ctx, Args& args) {
  double ratio = 1e-3;
  std::int64_t limit = 100000;
  while (!args.empty()) {
    auto k = args.expect({"ratio", "limit"}, "SOLVE option");
    if (k == 0) ratio = args.real("ratio");
    else limit = args.count("limit", 1);
  }
  if (!(ratio > 0)) args.fail("ratio must be positive");
  auto start = std::chrono::steady_clock::now();
  ProgressReporter progress(ctx, true);
  auto r = ctx.session.solve(ratio, limit, progress.callback());
  finish_run(ctx, progress, r.run, limit, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (r.converged)
    ctx.out << fmt::format("solved: mean unbalanced-force ratio {:.3g} < {:.3g}\n", r.ratio, ratio);
  else if (!r.run.interrupted)
    ctx.warn(fmt::format("SOLVE stopped at the limit of {} cycles with ratio {:.3g} (target {:.3g})", limit,
                         r.ratio, ratio));
}

const Command solve_command = {
    "SOLVE", {}, "SOLVE [ratio r] [limit n]", "cycle to equilibrium",
    "Cycles until the mean unbalanced-force ratio (mean unbalanced force over mean contact force) is below "
    "r (default 1e-3), checking every 100 cycles, or until n cycles (default 100000).",
    "solve ratio 1e-4 limit 50000",
    // (Under mpirun on the ranks' parts, as CYCLE: Session::solve.)
    {"ratio", "limit"}, run_solve, false, false, OnRanks::Parts, HeldUse::Split};

}  // namespace trubal
