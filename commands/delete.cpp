#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_delete(Context& ctx, Args& args) {
  Range range = read_range(args, ctx.session);
  auto n = ctx.session.delete_balls(range);
  if (n == 0 && !range.empty()) ctx.warn("the range holds for no ball");
  ctx.out << fmt::format("{} deleted\n", count_of(n, "ball"));
}

const Command delete_command = {
    "DELETE", {}, "DELETE [range ...]", "remove balls",
    "Removes the balls where the range holds (all balls without a range), with their contacts.",
    "delete range z 0.15 0.2",
    {"range"}, run_delete, false, false, OnRanks::ModelOnZero, HeldUse::Delete, {},
    // (Where the ranks keep their parts, every rank deletes its own: Session::delete_balls.)
    [](const Args&, bool parts_kept) { return parts_kept ? OnRanks::Parts : OnRanks::ModelOnZero; }};

}  // namespace trubal
