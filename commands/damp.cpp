#include <numbers>

#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_damp(Context& ctx, Args& args) {
  Damping d;
  if (args.accept("off")) {
    d.kind = DampKind::None;
  } else if (args.accept("local")) {
    d.kind = DampKind::Local;
    d.local = args.real("local damping coefficient");
    if (d.local < 0 || d.local >= 1) args.fail("local damping must be in [0, 1)");
  } else if (!args.empty() && match_keyword(args.peek(), {"mass", "stiff"})) {
    d.kind = DampKind::Rayleigh;
    while (!args.empty()) {
      auto k = args.expect({"mass", "stiff"}, "DAMP coefficient");
      double v = args.real(k == 0 ? "mass coefficient" : "stiffness coefficient");
      if (v < 0) args.fail("damping coefficients must not be negative");
      (k == 0 ? d.alpha : d.beta) = v;
    }
  } else {
    d.kind = DampKind::Rayleigh;
    d.lambda = args.real("lambda (fraction of critical damping)");
    d.freq = args.real("f (frequency, Hz)");
    if (d.lambda < 0 || !(d.freq > 0)) args.fail("DAMP lambda f needs lambda >= 0 and f > 0");
    double omega = 2 * std::numbers::pi * d.freq;   // doc/physics.md, Damping 1
    d.alpha = d.lambda * omega;
    d.beta = d.lambda / omega;
  }
  args.done();
  ctx.session.settings().damping = d;
}

const Command damp_command = {
    "DAMP", {}, "DAMP lambda f  |  DAMP mass a stiff b  |  DAMP local a  |  DAMP off",
    "Rayleigh or local damping",
    "Rayleigh damping C = alpha M + beta K given as a fraction lambda of critical damping at frequency f "
    "(Hz): alpha = lambda 2 pi f, beta = lambda / (2 pi f); or the coefficients directly (mass a, stiff b). "
    "The stiffness part is a dashpot at each contact and shortens the automatic time step. `DAMP local a` "
    "selects Cundall's local non-viscous damping. There is no damping until a deck asks for it.",
    "damp local 0.7",
    {"mass", "stiff", "local", "off"}, run_damp, false, false, OnRanks::Parts, HeldUse::Keep};

}  // namespace trubal
