#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/membrane.hpp"

namespace trubal {

static void run_membrane(Context& ctx, Args& args) {
  ctx.session.require_started();
  const double pressure = args.real("pressure p");
  if (pressure < 0) args.fail("the confining pressure must not be negative (0 removes the membrane)");
  std::int64_t follow = 0;
  if (args.accept("follow")) follow = args.accept("every") ? args.count("every", 1) : 1;
  Range range = read_range(args, ctx.session);
  auto sel = ctx.session.select(range);
  if (sel.empty()) {
    ctx.warn("the range holds for no ball");
    return;
  }
  MembraneLoads loads;
  try {
    loads = membrane_loads(ctx.session.model(), sel, pressure);
  } catch (const std::runtime_error& e) {
    args.fail(e.what());
  }
  Model& m = ctx.session.edit();
  // The membrane replaces any horizontal load on the range's balls.
  for (auto k : sel) m.balls.ax[k] = m.balls.ay[k] = 0;
  if (pressure == 0) {
    m.membrane = {};
    ctx.out << fmt::format("membrane removed from {}\n", count_of(sel.size(), "ball"));
    return;
  }
  for (std::size_t q = 0; q < loads.balls.size(); ++q) {
    const std::size_t k = loads.balls[q];
    m.balls.ax[k] = loads.fx[q];
    m.balls.ay[k] = loads.fy[q];
    m.balls.fixed[k] |= kSpin;
  }
  m.membrane = {};
  m.membrane.pressure = pressure;
  m.membrane.area = loads.area;
  m.membrane.follow_every = follow;
  m.membrane.cell = loads.cell;
  for (std::size_t k : loads.balls) m.membrane.ids.push_back(m.balls.id[k]);
  m.membrane.face_x = loads.face_x;
  m.membrane.face_y = loads.face_y;
  m.membrane.layer = loads.layer;
  m.membrane.extent_x = loads.extent_x;
  m.membrane.extent_y = loads.extent_y;
  m.membrane.layer_cells = loads.layer_cells;
  ctx.out << fmt::format(
      "membrane: pressure {:.6g} on {} perimeter balls of {} of {} layers (their spins fixed); "
      "area {:.6g} = {:.6g} d^2{}\n",
      pressure, loads.balls.size(), loads.loaded_layers, loads.layers, loads.area,
      loads.area / (loads.cell * loads.cell),
      follow > 0 ? fmt::format("; following the sample every {}", count_of(static_cast<std::size_t>(follow), "cycle")) : "");
}

const Command membrane_command = {
    "MEMBRANE", {}, "MEMBRANE p [follow [every n]] [range ...]", "confining pressure on the outer balls (Rowe's triaxial test)",
    "Confining pressure p as constant horizontal forces on the perimeter balls of the sample's outermost "
    "square layers (Rowe's large layers: those that reach the sample's widest extent; the layers half a "
    "diameter inside are not loaded). Each ball owns the square cell of side d (its diameter) about it; "
    "every cell face with no cell behind it carries p d h, inward, h the layer's tributary height (half "
    "the distance to the loaded layers above and below; at the ends, half the distance to the one "
    "neighbour). A ball on a straight side of the octagon so gets p d h normal to it, one on a diagonal "
    "side sqrt(2) p d h at 45 degrees, and the forces on each side add up to p times its area: the lateral "
    "stress is p on the cross section A, the union of the cells (76 d^2 for Rowe's layer of 76, 37 d^2 for "
    "Cundall's of 37), which HIST ratio uses. The loaded balls' spins are fixed (FREE spin releases them). "
    "The forces are computed once, from the positions now, and replace the range's x and y applied "
    "loads (valid for small strains only, as the seed paper notes); with `follow` they are recomputed "
    "every n cycles (default 1; on cycles that are multiples of n, so however the run is cut) from the "
    "positions then: each loaded layer's tributary height from the loaded layers' heights, each face "
    "grown with its layer's extent across it, so that every side of the bulging sample still carries p "
    "times its area, and HIST ratio's A follows the widest layer's extent. `MEMBRANE 0` removes them. "
    "Balls must be of one size, each loaded layer on a square grid.",
    "membrane 1e5 follow every 10",
    {"follow", "every", "range"}, run_membrane, false, false, OnRanks::ModelOnZero};

}  // namespace trubal
