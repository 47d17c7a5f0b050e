#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_group(Context& ctx, Args& args) {
  std::string name = to_lower(args.word("group name"));
  if (match_keyword(name, {"range"})) args.fail("GROUP needs a name before RANGE");
  Range range = read_range(args, ctx.session);
  auto n = ctx.session.define_group(name, range);
  if (n == 0) ctx.warn(fmt::format("group {} holds no ball: its range holds for none", name));
  ctx.out << fmt::format("group {}: {}\n", name, count_of(n, "ball"));
}

const Command group_command = {
    "GROUP", {}, "GROUP name [range ...]", "name a set of balls",
    "Names the set of balls where the range holds now; later ranges can use `group name`. The set does "
    "not change as balls move; deleted balls leave it.",
    "group platens range z 0 0.01",
    {"range"}, run_group, false, false, OnRanks::ModelOnZero, HeldUse::Place, {}, parts_where_kept};

}  // namespace trubal
