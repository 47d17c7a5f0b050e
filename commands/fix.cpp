#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static const std::vector<std::string_view> kDofWords = {"xvel", "yvel", "zvel", "xspin", "yspin", "zspin",
                                                        "vel", "spin"};
static const std::uint8_t kDofBits[] = {kXVel, kYVel, kZVel, kXSpin, kYSpin, kZSpin, kVel, kSpin};

static std::uint8_t read_dofs(Args& args) {
  std::uint8_t mask = 0;
  while (!args.empty() && !match_keyword(args.peek(), {"range"})) mask |= kDofBits[args.expect(kDofWords, "component")];
  if (!mask) args.fail("name at least one component (xvel yvel zvel xspin yspin zspin vel spin)");
  return mask;
}

static void set_fixed(Context& ctx, Args& args, bool fix) {
  ctx.session.require_started();
  std::uint8_t mask = read_dofs(args);
  Range range = read_range(args, ctx.session);
  const std::size_t n = ctx.session.change_balls(range, [&](Balls& b, std::size_t k) {
    b.fixed[k] = fix ? (b.fixed[k] | mask) : (b.fixed[k] & ~mask);
  }, true);
  if (n == 0) ctx.warn("the range holds for no ball");
  ctx.out << fmt::format("{} {}\n", count_of(n, "ball"), fix ? "fixed" : "freed");
}

static void run_fix(Context& ctx, Args& args) { set_fixed(ctx, args, true); }
static void run_free(Context& ctx, Args& args) { set_fixed(ctx, args, false); }

const Command fix_command = {
    "FIX", {}, "FIX xvel|yvel|zvel|xspin|yspin|zspin|vel|spin ... [range ...]", "fix velocity components",
    "Fixes the named velocity components of the balls in the range: they keep their present value (set it "
    "with INIT), and the force the ball would have received is recorded as its reaction (PRINT balls, HIST "
    "platen).",
    "fix vel spin range group platens",
    {"xvel", "yvel", "zvel", "xspin", "yspin", "zspin", "vel", "spin", "range"}, run_fix, false, false, OnRanks::ModelOnZero, HeldUse::Place, {}, parts_where_kept};

const Command free_command = {
    "FREE", {}, "FREE xvel|yvel|zvel|xspin|yspin|zspin|vel|spin ... [range ...]", "free velocity components",
    "Frees the named velocity components of the balls in the range (undoes FIX).",
    "free zvel range group platens",
    {"xvel", "yvel", "zvel", "xspin", "yspin", "zspin", "vel", "spin", "range"}, run_free, false, false, OnRanks::ModelOnZero, HeldUse::Place, {}, parts_where_kept};

}  // namespace trubal
