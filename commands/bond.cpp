#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static const std::vector<std::string_view> kBondWords = {"gap", "kn", "ks", "ten", "coh", "fa", "rmul", "mcf"};

static void run_bond(Context& ctx, Args& args) {
  ctx.session.require_started();
  if (args.accept("delete")) {
    const Range range = read_range(args, ctx.session);
    const std::size_t n = ctx.session.delete_bonds(range);
    ctx.out << fmt::format("{} deleted\n", count_of(n, "bond"));
    return;
  }
  BondSpec spec;
  Range range;
  bool seen[8] = {};
  while (!args.empty()) {
    if (match_keyword(args.peek(), {"range"})) {
      if (!range.empty()) args.fail("BOND takes one range");
      range = read_range(args, ctx.session, kBondWords);
      continue;
    }
    const std::size_t k = args.expect(kBondWords, "bond property");
    if (seen[k]) args.fail(fmt::format("{} is given twice", kBondWords[k]));
    seen[k] = true;
    const double v = args.real(kBondWords[k]);
    auto nonneg = [&] { if (!(v >= 0) || !std::isfinite(v)) args.fail(fmt::format("{} must be a number, not negative", kBondWords[k])); };
    auto positive = [&] { if (!(v > 0) || !std::isfinite(v)) args.fail(fmt::format("{} must be positive", kBondWords[k])); };
    switch (k) {
      case 0:
        if (!std::isfinite(v)) args.fail("gap must be a finite length (negative: only pairs overlapping by more)");
        spec.gap = v;
        break;
      case 1: positive(); spec.kn = v; break;
      case 2: positive(); spec.ks = v; break;
      case 3: nonneg(); spec.tension = v; break;
      case 4: nonneg(); spec.cohesion = v; break;
      case 5:
        if (!(v >= 0) || v >= 90) args.fail("fa is the bond's friction angle in degrees, in [0, 90)");
        spec.tan_friction = std::tan(v * std::numbers::pi / 180);
        break;
      case 6: positive(); spec.rmul = v; break;
      case 7:
        if (!(v >= 0) || v > 1) args.fail("mcf (the moment contribution factor) must be in [0, 1]");
        spec.mcf = v;
        break;
    }
  }
  for (std::size_t k : {1, 2, 3, 4})
    if (!seen[k]) args.fail(fmt::format("BOND needs {} (kn, ks, ten and coh have no default)", kBondWords[k]));
  const std::size_t made = ctx.session.make_bonds(range, spec);
  if (made == 0) ctx.warn("no pair of balls in the range is within the gap and unbonded: no bond made");
  ctx.out << fmt::format("{} made\n", count_of(made, "bond"));
}

const Command bond_command = {
    "BOND", {}, "BOND [range ...] [gap G] kn KN ks KS ten T coh C [fa DEG] [rmul L] [mcf B] | BOND delete [range ...]",
    "parallel bonds between balls (cemented grains, rock)",
    "Cements every pair of balls in the range (all balls without one) whose gap is at most G (default 0: "
    "touching; the gap is the distance between the surfaces) with a linear parallel bond, PFC's (Potyondy "
    "and Cundall 2004): a disc of cement of radius Rb = L min(R1, R2) (rmul L, default 1) acting beside the "
    "pair's contact law. kn and ks are its normal and shear stiffness per unit area (Pa/m: stress per "
    "length); it carries a normal force, a shear force, a twisting and a bending moment, each built up from "
    "the pair's relative motion from the moment it is made (at zero force): kn A and ks A against the "
    "relative displacement, kn I against bending and ks J against twisting, A = pi Rb^2, I = pi Rb^4/4, "
    "J = pi Rb^4/2. It breaks for good where the largest tensile stress -Fn/A + B |Mb| Rb/I exceeds its "
    "tensile strength T (ten, Pa), or where the largest shear stress |Fs|/A + B |Mt| Rb/J exceeds its shear "
    "strength C - sigma tan(fa), C its cohesion (coh, Pa), fa its friction angle in degrees (default 0) and "
    "sigma = -Fn/A the mean normal stress (tension positive); B is the moment contribution factor (mcf, in "
    "[0, 1], default 1). A broken bond carries nothing: its pair is an ordinary contact. A pair bonded "
    "once is not bonded again. The range may come first or after the words. `BOND delete [range ...]` "
    "removes the bonds, intact or broken, that hold a ball of the range. PRINT bonds lists them, PRINT info "
    "counts them, HIST bonds records the counts, PRINT energy books the energy the broken bonds held as "
    "`bond breakage`, DUMP vtk draws them.",
    "bond gap 1e-3 kn 2e12 ks 1e12 ten 5e6 coh 10e6 fa 30 range group platens",
    {"delete", "gap", "kn", "ks", "ten", "coh", "fa", "rmul", "mcf", "range"}, run_bond, false, false, OnRanks::ModelOnZero};

}  // namespace trubal
