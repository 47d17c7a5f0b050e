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
  auto sel = ctx.session.select(range);
  Model& m = ctx.session.edit();
  std::vector<double>* arrays[] = {&m.balls.vx, &m.balls.vy, &m.balls.vz, &m.balls.wx, &m.balls.wy, &m.balls.wz};
  for (auto k : sel)
    for (auto [c, v] : values) (*arrays[c])[k] = v;
  if (sel.empty()) ctx.warn("the range holds for no ball");
  ctx.out << fmt::format("{} set\n", count_of(sel.size(), "ball"));
}

const Command init_command = {
    "INIT", {}, "INIT xvel|yvel|zvel|xspin|yspin|zspin v ... [range ...]", "set velocities",
    "Sets velocity and spin components of the balls in the range (a fixed component keeps this value).",
    "init zvel -0.01 range group platens",
    {"xvel", "yvel", "zvel", "xspin", "yspin", "zspin", "range"}, run_init, false, false, OnRanks::ModelOnZero};

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
  auto sel = ctx.session.select(range);
  Model& m = ctx.session.edit();
  std::vector<double>* arrays[] = {&m.balls.ax, &m.balls.ay, &m.balls.az, &m.balls.amx, &m.balls.amy, &m.balls.amz};
  for (auto k : sel) {
    if (off)
      for (auto* a : arrays) (*a)[k] = 0;
    for (auto [c, v] : values) (*arrays[c])[k] = v;
  }
  if (sel.empty()) ctx.warn("the range holds for no ball");
  ctx.out << fmt::format("{} {}\n", count_of(sel.size(), "ball"), off ? "unloaded" : "loaded");
}

const Command apply_command = {
    "APPLY", {}, "APPLY xforce|yforce|zforce|xmom|ymom|zmom v ... [range ...]  |  APPLY off [range ...]",
    "applied forces and moments",
    "Applies constant forces and moments to the balls in the range (added to contact forces and gravity "
    "every cycle). `APPLY off` removes all applied loads from the range.",
    "apply zforce -10 range id 1",
    {"xforce", "yforce", "zforce", "xmom", "ymom", "zmom", "off", "range"}, run_apply, false, false, OnRanks::ModelOnZero};

}  // namespace trubal
