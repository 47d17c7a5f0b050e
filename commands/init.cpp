#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_init(Context& ctx, Args& args) {
  ctx.session.require_started();
  static const std::vector<std::string_view> words = {"xvel", "yvel", "zvel", "xspin", "yspin", "zspin"};
  std::vector<std::pair<std::size_t, double>> values;
  while (!args.empty() && !match_keyword(args.peek(), {"range"})) {
    auto k = args.expect(words, "component");
    values.emplace_back(k, args.real(words[k]));
  }
  if (values.empty()) args.fail("name at least one component and its value");
  Range range = read_range(args, ctx.session);
  const std::size_t n = ctx.session.change_balls(range, [&](Balls& b, std::size_t k) {
    std::vector<double>* arrays[] = {&b.vx, &b.vy, &b.vz, &b.wx, &b.wy, &b.wz};
    for (auto [c, v] : values) (*arrays[c])[k] = v;
  });
  if (n == 0) ctx.warn("the range holds for no ball");
  ctx.out << fmt::format("{} set\n", count_of(n, "ball"));
}

const Command init_command = {
    "INIT", {}, "INIT xvel|yvel|zvel|xspin|yspin|zspin v ... [range ...]", "set velocities",
    "Sets velocity and spin components of the balls in the range (a fixed component keeps this value).",
    "init zvel -0.01 range group platens",
    {"xvel", "yvel", "zvel", "xspin", "yspin", "zspin", "range"}, run_init, false, false, OnRanks::ModelOnZero, HeldUse::Place, {}, parts_where_kept};

static void run_apply(Context& ctx, Args& args) {
  ctx.session.require_started();
  static const std::vector<std::string_view> words = {"xforce", "yforce", "zforce", "xmom", "ymom", "zmom"};
  bool off = args.accept("off");
  std::vector<std::pair<std::size_t, double>> values;
  while (!off && !args.empty() && !match_keyword(args.peek(), {"range"})) {
    auto k = args.expect(words, "load");
    values.emplace_back(k, args.real(words[k]));
  }
  if (!off && values.empty()) args.fail("name at least one load and its value, or APPLY off");
  Range range = read_range(args, ctx.session);
  const std::size_t n = ctx.session.change_balls(range, [&](Balls& b, std::size_t k) {
    std::vector<double>* arrays[] = {&b.ax, &b.ay, &b.az, &b.amx, &b.amy, &b.amz};
    if (off)
      for (auto* a : arrays) (*a)[k] = 0;
    for (auto [c, v] : values) (*arrays[c])[k] = v;
  });
  if (n == 0) ctx.warn("the range holds for no ball");
  ctx.out << fmt::format("{} {}\n", count_of(n, "ball"), off ? "unloaded" : "loaded");
}

const Command apply_command = {
    "APPLY", {}, "APPLY xforce|yforce|zforce|xmom|ymom|zmom v ... [range ...]  |  APPLY off [range ...]",
    "applied forces and moments",
    "Applies constant forces and moments to the balls in the range (added to contact forces and gravity "
    "every cycle). `APPLY off` removes all applied loads from the range.",
    "apply zforce -10 range id 1",
    {"xforce", "yforce", "zforce", "xmom", "ymom", "zmom", "off", "range"}, run_apply, false, false, OnRanks::ModelOnZero, HeldUse::Place, {}, parts_where_kept};

}  // namespace trubal
