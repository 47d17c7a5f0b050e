#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_gen(Context& ctx, Args& args) {
  auto n = args.count("n (number of balls)", 1, 100000000);
  double rlo = args.real("rlo");
  double rhi = args.real("rhi");
  int type = 1;
  std::uint64_t seed = ctx.session.seed;
  while (!args.empty() && !match_keyword(args.peek(), {"range"})) {
    auto k = args.expect({"type", "seed"}, "GEN option");
    if (k == 0) type = static_cast<int>(args.count("type", 1, 1000000));
    else seed = static_cast<std::uint64_t>(args.count("seed", 0));
  }
  Range range = read_range(args);
  auto placed = ctx.session.generate(static_cast<std::size_t>(n), rlo, rhi, type, seed, range);
  if (ctx.session.gen_interrupted)
    ctx.warn(fmt::format("GEN interrupted by Ctrl-C: {} of {} balls placed (kept)", placed, n));
  else if (placed < static_cast<std::size_t>(n))
    ctx.warn(fmt::format("GEN placed only {} of {} balls: no room for more without overlap", placed, n));
  ctx.out << fmt::format("{} balls generated (type {}, seed {})\n", placed, type, seed);
}

const Command gen_command = {
    "GEN", {}, "GEN n rlo rhi [type t] [seed s] [range ...]",
    "generate n balls at random non-overlapping positions",
    "Generates n balls with radii uniform in [rlo, rhi] at random positions that overlap no ball, inside "
    "the START box (whole balls) or anywhere in the periodic space, and where the range holds. The same "
    "seed gives the same balls (default seed: SET seed). More balls than the densest packing of spheres of "
    "radius rlo could hold is an error at once; if there is no room for all (200,000 failed tries in a row), "
    "it says how many it placed, and Ctrl-C stops it keeping those placed. The new balls are numbered in space order (by cells of the largest diameter: z slowest, then y, "
    "then x), so that balls near in space are near in number, as the threaded backend needs.",
    {"type", "seed", "range"}, run_gen};

}  // namespace trubal
