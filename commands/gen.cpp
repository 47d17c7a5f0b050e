#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "interp/lexer.hpp"

namespace trubal {

namespace {

bool next_is_number(const Args& args) { return !args.empty() && parse_real(args.peek()).has_value(); }

// A sieve curve from a CSV or blank-separated file: diameter, percent passing on each line; lines
// that do not start with a number (a header, comments) are skipped.
// Under mpirun rank 0 alone reads it and hands its text to the others, as with every input file.
void read_sieve_file(Args& args, const std::string& path, SizeDistribution& d) {
  const std::optional<std::string> text = Interpreter::read_file_on_root(path);
  if (!text)
    args.fail(fmt::format("cannot read the sieve curve file '{}' (missing, unreadable, or not a regular file)", path));
  std::istringstream in(*text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t') c = ' ';
    std::istringstream words(line);
    std::string a, b;
    if (!(words >> a) || !parse_real(a)) continue;
    if (!(words >> b) || !parse_real(b))
      args.fail(fmt::format("{}:{}: a sieve point needs a diameter and a percent passing", path, number));
    d.diameter.push_back(*parse_real(a));
    d.passing.push_back(*parse_real(b));
  }
}

SizeDistribution read_psd(Args& args) {
  using K = SizeDistribution::Kind;
  SizeDistribution d;
  const auto kind = args.expect({"uniform", "volume", "normal", "lognormal", "sieve"}, "size distribution");
  switch (kind) {
    case 0: d.kind = K::Uniform; d.a = args.real("rlo"); d.b = args.real("rhi"); break;
    case 1: d.kind = K::Volume; d.a = args.real("rlo"); d.b = args.real("rhi"); break;
    case 2: case 3:
      d.kind = kind == 2 ? K::Normal : K::Lognormal;
      d.a = args.real(kind == 2 ? "mean radius" : "median radius");
      d.b = args.real(kind == 2 ? "standard deviation" : "sigma (of ln r)");
      if (args.accept("cut")) {
        d.lo = args.real("lower cut-off radius");
        d.hi = args.real("upper cut-off radius");
        if (!(d.lo > 0) || !(d.hi > d.lo)) args.fail(fmt::format("the cut-offs must satisfy 0 < rlo < rhi, got {:g} {:g}", d.lo, d.hi));
      }
      break;
    case 4:
      d.kind = K::Sieve;
      if (args.accept("file")) {
        read_sieve_file(args, args.word("sieve curve file"), d);
        break;
      }
      while (next_is_number(args)) {
        d.diameter.push_back(args.real("sieve diameter"));
        d.passing.push_back(args.real("percent passing"));
      }
      if (d.diameter.size() < 2) args.fail("a sieve curve needs at least two points: diameter percent-passing ...");
      break;
  }
  return d;
}

}  // namespace

// Ctrl-C stopped GEN, which keeps what it placed: at the shell a warning, in a batch deck an error
// that stops it (exit 1), as Ctrl-C stops a CYCLE.
static void interrupted(Context& ctx, const std::string& what) {
  if (!ctx.interp.interactive) throw InputError(what);
  ctx.warn(what);
}

static void run_gen(Context& ctx, Args& args) {
  Session::GenSpec spec;
  std::int64_t n = 0;
  const char* target = nullptr;
  double target_value = 0;
  if (args.accept("porosity")) {
    target = "porosity";
    spec.porosity = target_value = args.real("porosity");
  } else if (args.accept("void")) {
    target = "void ratio";
    target_value = args.real("void ratio");
    if (!(target_value > 0)) args.fail(fmt::format("the void ratio must be positive, got {:g}", target_value));
    spec.porosity = target_value / (1 + target_value);
  } else {
    n = args.count("n (number of balls)", 1, 100000000);
  }
  bool psd = false;
  if (args.accept("psd")) {
    psd = true;
    spec.sizes = read_psd(args);
  } else {
    spec.sizes.kind = SizeDistribution::Kind::Uniform;
    spec.sizes.a = args.real("rlo");
    spec.sizes.b = args.real("rhi");
  }
  int type = 1;
  bool types = false;
  spec.seed = ctx.session.seed;
  while (!args.empty() && !match_keyword(args.peek(), {"range"})) {
    auto k = args.expect({"type", "seed", "types"}, "GEN option");
    if (k == 0) {
      type = static_cast<int>(args.count("type", 1, 1000000));
      spec.types = {{type, 1.0}};
    } else if (k == 1) {
      spec.seed = static_cast<std::uint64_t>(args.count("seed", 0));
    } else {
      types = true;
      spec.types.clear();
      double sum = 0;
      while (!args.empty() && parse_integer(args.peek())) {
        const int t = static_cast<int>(args.count("type", 1, 1000000));
        const double f = args.real("mass fraction");
        if (!(f > 0)) args.fail(fmt::format("the mass fraction of type {} must be positive, got {:g}", t, f));
        for (const auto& [u, g] : spec.types)
          if (u == t) args.fail(fmt::format("type {} is named twice in `types`", t));
        spec.types.push_back({t, f});
        sum += f;
      }
      if (spec.types.empty()) args.fail("`types` needs pairs: type mass-fraction ...");
      if (std::abs(sum - 1) > 1e-6)
        args.fail(fmt::format("the mass fractions of `types` must add up to 1, they add up to {:g}", sum));
    }
  }
  spec.range = read_range(args);
  if (!target && !psd && !types) {   // as it always was: the same balls for the same seed
    auto placed = ctx.session.generate(static_cast<std::size_t>(n), spec.sizes.a, spec.sizes.b, type, spec.seed, spec.range);
    if (ctx.session.gen_interrupted)
      interrupted(ctx, fmt::format("GEN interrupted by Ctrl-C: {} of {} balls placed (kept)", placed, n));
    else if (placed < static_cast<std::size_t>(n) && ctx.session.gen_missed_range)
      ctx.warn(fmt::format("GEN placed only {} of {} balls: the places drawn stopped falling in the range (a range "
                           "by id or group holds no new ball; one by type only GEN's own type)", placed, n));
    else if (placed < static_cast<std::size_t>(n))
      ctx.warn(fmt::format("GEN placed only {} of {} balls: no room for more without overlap", placed, n));
    ctx.out << fmt::format("{} generated (type {}, seed {})\n", count_of(placed, "ball"), type, spec.seed);
    return;
  }
  spec.count = static_cast<std::size_t>(n);
  const PackResult made = ctx.session.generate(spec);
  std::string kinds;
  for (const auto& [t, f] : spec.types) kinds += fmt::format("{}{}", kinds.empty() ? "" : " ", t);
  const std::string what = fmt::format("{} balls generated (type{} {}, seed {}; {})", made.balls.size(),
                                       spec.types.size() > 1 ? "s" : "", kinds, spec.seed, ctx.session.last_sizes()->describe());
  if (!target) {
    if (ctx.session.gen_interrupted)
      interrupted(ctx, fmt::format("GEN interrupted by Ctrl-C: {} of {} balls placed (kept)", made.balls.size(), n));
    else if (made.balls.size() < static_cast<std::size_t>(n))
      ctx.warn(fmt::format("GEN placed only {} of {} balls: no room for more without overlap (the largest are "
                           "placed first)", made.balls.size(), n));
    ctx.out << what << '\n';
    return;
  }
  const double reached = made.porosity, asked = spec.porosity;
  const std::string as_void = fmt::format("void ratio {:.4f}", reached / (1 - reached));
  ctx.out << what << '\n';
  ctx.out << fmt::format("porosity {:.4f} ({}) in a volume of {:.6g}, asked {} {:g}; {} growth stages, {} relaxation "
                         "sweeps\n", reached, as_void, made.volume, target, target_value, made.stages, made.sweeps);
  if (ctx.session.gen_interrupted)
    interrupted(ctx, fmt::format("GEN interrupted by Ctrl-C at porosity {:.4f} (the balls are kept there)", reached));
  else if (!made.reached)
    throw std::runtime_error(fmt::format(
        "GEN: porosity {:g} not reached: the balls stopped at porosity {:.4f} ({}), where growing them further left "
        "overlaps of more than {:g} of a radius that would not relax ({} sweeps a stage, {} in all); the balls are "
        "kept at {:.4f}",
        asked, reached, as_void, kOverlapTolerance, kStageSweeps, kTotalSweeps, reached));
}

const Command gen_command = {
    "GEN", {},
    "GEN n|porosity p|void e  rlo rhi|psd DIST  [type t|types t f ...] [seed s] [range ...]",
    "generate balls at random non-overlapping positions: n of them, or to a porosity",
    "`GEN n rlo rhi` generates n balls with radii uniform in [rlo, rhi] at random positions that overlap no ball, "
    "inside the START box (whole balls) or anywhere in the periodic space, where the range holds, and clear of "
    "the walls. The same "
    "seed gives the same balls (default seed: SET seed) on every backend and thread count. More balls than the "
    "densest packing of spheres of radius rlo could hold is an error at once; if there is no room for all "
    "(200,000 failed tries in a row; a place drawn outside the range is no try, so a range in a corner of a large cell fills as well), it says how many it placed, and Ctrl-C stops it keeping those placed (a batch deck then stops, exit 1). In the periodic "
    "space every periodic edge must be at least twice the largest diameter (CYCLE's rule); a larger radius is an "
    "error at once. The "
    "new balls are numbered in space order (by cells of the largest diameter: z slowest, then y, then x), so that "
    "balls near in space are near in number, as the threaded backend needs. "
    "Walls bound every GEN: a ball goes only where it touches no wall and lies on the wall's side: on the side a "
    "plane's normal points to, at least its radius from it; within radius - r of a container cylinder's axis "
    "with its centre along the cylinder's length (for an `outside` cylinder, outside it); clear of polygons. "
    "The region is the box (or the range) on the walls' side, and its volume is what the estimate of how many "
    "balls fit and `porosity` use. Example: `WALL plane 0 0 0 0 0 1` then `GEN 100 0.004 0.006` in `START box "
    "-0.05 0.05 -0.05 0.05 -0.01 0.1` puts every ball above the floor. "
    "Size distributions, `psd DIST` in place of rlo rhi (radii, except the sieve curve's diameters): `uniform rlo "
    "rhi` (radius uniform by number, as rlo rhi); `volume rlo rhi` (uniform by volume: the mass is spread evenly "
    "over the radii, a straight grading line from 2 rlo to 2 rhi); `normal mean sd [cut rlo rhi]` (radius normal "
    "by number, cut at mean -+ 3 sd unless given); `lognormal median sigma [cut rlo rhi]` (ln r normal by number, "
    "sigma its standard deviation, cut at median e^-+3 sigma unless given); `sieve d1 p1 d2 p2 ...` or `sieve "
    "file f.csv` (a lab report's grading: diameters ascending, percent passing by mass, from 0 at the smallest "
    "size to 100 at the largest, never falling; between two sieves the mass is spread evenly in log d, as the "
    "curve is drawn). Mass is solid volume (one grain density). The radii are drawn one from each of n equal "
    "slices of the distribution (stratified), so the sample's grading follows the one asked for closely; the "
    "balls are placed largest first. With a distribution, a range's x, y, z intervals and cylinder bound whole "
    "balls (as the START box does); PRINT psd compares the sample's grading with the one asked for. `types t1 f1 t2 f2 ...` "
    "shares the balls among types by mass fraction (adding up to 1): each ball, largest first, goes to the type "
    "furthest below its share, so each type has the sample's grading; mass at the types' PROP densities where "
    "every one has one, else by volume. "
    "`GEN porosity p` (or `void e`, p = e / (1 + e)) makes as many balls as fill the region (the START box, the "
    "periodic cell, the box of `range x x0 x1 y y0 y1 z z0 z1`, the cylinder of `range cylinder x y r` (about "
    "a line along z, cut by `z z0 z1` where given), on the walls' side, balls already there counted) to porosity "
    "p = 1 - (volume of balls) / (volume of region), by radius expansion (PFC's method, with a geometric relaxation "
    "in place of cycling): the balls are placed at random at a solid fraction of 0.25, then grown in stages of at "
    "most 10% of their volume, each stage relaxed by moving overlapping balls apart (pair by pair in a fixed "
    "order, each pair's overlap removed 1.8 times over, over-relaxation, and shared in inverse proportion to the "
    "balls' volumes; balls already there stay) until no overlap is more than 1% of the smaller radius. A stage "
    "that does not relax in 150 sweeps is taken back and tried again with half the growth; when the growth falls "
    "below 0.1% of the volume (or after 2000 sweeps in all) GEN stops with an error giving the porosity reached, "
    "the balls kept there: a sand's grading reaches about 0.35, equal balls about 0.37 (random close packing, "
    "0.36, is the limit of moving balls apart without shaking them), and walls and the region's edges loosen the "
    "balls next to them, so a small region stops higher: about 0.43 in a cylinder ten diameters across. The "
    "porosity reached is printed. The region's volume is exact for a box; cut by a cylinder or a wall other than a plane across an "
    "axis it is integrated (2048 x 2048 lines, each cut exactly), to a relative 1e-4 or better. Example: `GEN "
    "porosity 0.45 0.002 0.003 range cylinder 0 0 0.02 z 0 0.1`. The balls come out at rest with their small overlaps (a slight prestress at the first CYCLE). A "
    "porosity outside (0, 1), below 0.2595 with balls of one size (the densest packing), or a region too small "
    "for the balls is an error at once. Generation is the same on every backend and thread count.",
    "gen 500 0.002 0.003 seed 7",
    {"porosity", "void", "psd", "uniform", "volume", "normal", "lognormal", "sieve", "cut", "file", "type", "types",
     "seed", "range"},
    run_gen, false, false, OnRanks::ModelOnZero, HeldUse::Generate};

}  // namespace trubal
