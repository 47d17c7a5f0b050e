#include <chrono>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/measure.hpp"

namespace trubal {

static void finish_run(Context& ctx, const CycleResult& r, std::int64_t asked, double seconds) {
  report_cycle_result(ctx, r, asked);
  if (r.interrupted && !ctx.interp.interactive)
    throw InputError(fmt::format("interrupted by Ctrl-C at cycle {}", ctx.session.model().cycle));
  const auto& m = ctx.session.model();
  double rate = seconds > 0 ? r.done * static_cast<double>(m.balls.size()) / seconds : 0;
  ctx.out << fmt::format("cycle {}  time {:.6g}  timestep {:.6g}  ({} cycles in {:.3f} s, {:.3g} ball-cycles/s)\n",
                         m.cycle, m.time, m.dt, r.done, seconds, rate);
}

static void run_cycle(Context& ctx, Args& args) {
  auto n = args.count("n (number of cycles)", 0);
  args.done();
  auto start = std::chrono::steady_clock::now();
  CycleResult r = ctx.session.cycle(n, progress_reporter(ctx));
  finish_run(ctx, r, n, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

const Command cycle_command = {
    "CYCLE", {}, "CYCLE n", "n time steps",
    "Runs n time steps. Ctrl-C stops at the end of the current step and keeps the model (in a batch run the "
    "deck then stops). A run that goes unstable stops with a message naming the cycle, a ball and a "
    "suggested FRAC, and leaves the last good state to print or save.",
    {}, run_cycle};

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
  auto r = ctx.session.solve(ratio, limit, progress_reporter(ctx));
  finish_run(ctx, r.run, limit, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
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
    {"ratio", "limit"}, run_solve};

}  // namespace trubal
