#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_ball(Context& ctx, Args& args) {
  auto p = read_xyz(args, "centre");
  double rad = args.real("rad");
  if (!(rad > 0)) args.fail("the radius must be positive");
  std::int64_t id = 0;
  int type = 1;
  while (!args.empty()) {
    auto k = args.expect({"id", "type"}, "BALL option");
    if (k == 0) id = args.count("id", 1);
    else type = static_cast<int>(args.count("type", 1, 1000000));
  }
  auto index = ctx.session.add_ball(id, type, p[0], p[1], p[2], rad);
  if (ctx.interp.interactive) ctx.out << fmt::format("ball {} created\n", ctx.session.model().balls.id[index]);
}

const Command ball_command = {
    "BALL", {"CREATE"}, "BALL x y z rad [id i] [type t]",
    "one ball",
    "Creates one ball at (x, y, z) with radius rad, at rest. Without `id` it takes one more than the largest "
    "id; an id already taken is an error, and so is a centre another ball has (the two would have no normal "
    "between them and fly apart; the message names the ball). Type defaults to 1.",
    "ball 0.05 0.05 0.1 0.003 id 1001",
    {"id", "type"}, run_ball, true};

}  // namespace trubal
