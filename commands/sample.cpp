// SAMPLE: declares the specimen held by walls (platens and a cylinder or four sides), whose
// strains and stresses HIST sample, PRINT sample and CYCLE ... until read (physics/sample.hpp). It
// reads the walls alone, which every rank holds: every rank runs it, the ranks' parts kept.
#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/sample.hpp"
#include "physics/walls.hpp"

namespace trubal {

void print_sample(Context& ctx) {
  const Model& m = ctx.session.state();   // (light state: PRINT)
  if (!m.sample.declared()) {
    ctx.out << "no sample (SAMPLE platens a b cylinder c declares one)\n";
    return;
  }
  const Sample& s = m.sample;
  const SampleMeasures x = sample_measures(m);
  ctx.out << fmt::format("sample: platens {} and {}, ", s.platens[0], s.platens[1]);
  if (s.sides[1] == 0) ctx.out << fmt::format("cylinder {}\n", s.sides[0]);
  else ctx.out << fmt::format("sides {} {} and {} {}\n", s.sides[0], s.sides[1], s.sides[2], s.sides[3]);
  ctx.out << fmt::format("  height {:.6g} (then {:.6g}), cross-section {:.6g} (then {:.6g}), volume {:.6g}\n", x.height,
                         s.height0, x.area, s.area0, x.volume);
  ctx.out << fmt::format("  axial strain {:.6g}, volumetric strain {:.6g} (compression positive)\n", x.axial,
                         x.volumetric);
  ctx.out << fmt::format("  sigma1 {:.6g}, sigma3 {:.6g}, q {:.6g}, p {:.6g}\n", x.sigma1, x.sigma3, x.q, x.p);
}

static void run_sample(Context& ctx, Args& args) {
  ctx.session.require_started();
  if (args.empty()) return print_sample(ctx);
  if (args.accept("off")) {
    args.done();
    ctx.session.edit_sample() = Sample{};
    ctx.out << "sample: none\n";
    return;
  }
  if (args.accept("reset")) {
    args.done();
    const Model& m = ctx.session.state();   // (the walls: light state)
    if (!m.sample.declared()) args.fail("there is no sample to reset (SAMPLE platens a b cylinder c declares one)");
    Sample s = m.sample;
    const std::string problem = check_sample(m, s);
    if (!problem.empty()) args.fail(fmt::format("the sample's walls changed: {}", problem));
    reset_sample(m, s);
    ctx.session.edit_sample() = s;
    ctx.out << fmt::format("sample: strains from here (height {:.6g}, cross-section {:.6g})\n", s.height0, s.area0);
    return;
  }
  Sample s;
  args.expect({"platens"}, "`platens a b`, `reset` or `off`");
  s.platens[0] = args.count("platen id", 1);
  s.platens[1] = args.count("platen id", 1);
  const auto kind = args.expect({"cylinder", "sides"}, "lateral walls (`cylinder c` or `sides a b c d`)");
  if (kind == 0) {
    s.sides[0] = args.count("cylinder id", 1);
  } else {
    for (auto& id : s.sides) id = args.count("side id", 1);
  }
  args.done();
  const Model& m = ctx.session.state();   // (the walls: light state)
  const std::string problem = check_sample(m, s);
  if (!problem.empty()) args.fail(problem + " (PRINT walls lists the walls)");
  reset_sample(m, s);
  ctx.session.edit_sample() = s;
  ctx.out << fmt::format("sample between platens {} and {}: height {:.6g}, cross-section {:.6g}, volume {:.6g} "
                         "(its strains are from here)\n",
                         s.platens[0], s.platens[1], s.height0, s.area0, s.height0 * s.area0);
}

const Command sample_command = {
    "SAMPLE", {}, "SAMPLE platens a b (cylinder c | sides a b c d)  |  SAMPLE reset  |  SAMPLE off  |  SAMPLE",
    "declare the sample held by walls",
    "Declares the specimen of a test between walls: two platens (planes or polygons facing each other) and "
    "the lateral walls, a cylinder whose axis lies along the platens' normal or four sides (two pairs of "
    "facing planes square to the platens). Its measures, compression positive: the axial strain 1 - h/h0 "
    "(h the platens' distance), the volumetric strain 1 - V/V0 (V the cross-section, pi r^2 or the product "
    "of the two pairs' distances, times h), sigma1 (the platens' mean normal force over the "
    "cross-section), sigma3 (the cylinder's normal force over 2 pi r h; for sides, the mean of the two "
    "pairs' stresses), the deviator q = sigma1 - sigma3 and the mean stress p = (sigma1 + 2 sigma3) / 3, "
    "as PFC's triaxial tests report them. The strains are referred to the sample as it stands when declared; "
    "`reset` takes the sample as it stands now (after consolidation, say) as their reference. HIST sample "
    "records them (columns ea ev sig1 sig3 q p), CYCLE ... until axial e (or volumetric, q, p, sig1, sig3) "
    "cycles until one reaches a value, SAMPLE alone or PRINT sample prints them. The stresses are those "
    "of the last step's forces. Saved with the model. A triaxial test: `sample platens 1 2 cylinder 3`, "
    "`sample reset` after consolidation, `hist sample every 100 file triax.csv`, `cycle 500000 until axial 0.1`, "
    "`plot q vs ea`.",
    "sample platens 1 2 cylinder 3",
    {"platens", "cylinder", "sides", "reset", "off"}, run_sample, false, false, OnRanks::Parts};

}  // namespace trubal
