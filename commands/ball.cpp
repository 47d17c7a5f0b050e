#include <fmt/format.h>

#include "commands/common.hpp"
#include "model/edit.hpp"
#include "model/wall_shape.hpp"

namespace trubal {

// How a new ball stands against a wall it is not clear of: "" when it is clear.
static std::string against_wall(const Wall& w, const Vec3& c, double r) {
  const WallClearance k = wall_clearance(w, c, r);
  if (!(k.gap < 0)) return "";
  const char* kind = wall_kind_name(w.kind);
  std::string where;
  if (k.beyond_end > 0)
    where = fmt::format("lies beyond an end of wall {} ({}, balls inside), its centre {:.4g} past it", w.id, kind,
                        k.beyond_end);
  else if (k.wrong_side && w.kind == WallKind::Plane)
    where = fmt::format("lies behind wall {} ({}; balls belong on the side its normal points to)", w.id, kind);
  else if (k.wrong_side)
    where = fmt::format("lies {} wall {} ({}, balls {})", w.inside ? "outside" : "inside", w.id, kind,
                        w.inside ? "inside" : "outside");
  else
    where = fmt::format("crosses wall {} ({})", w.id, kind);
  return fmt::format("{}: the gap from its surface to the wall is {:.4g} (radius {:g})", where, k.gap, r);
}

static void run_ball(Context& ctx, Args& args) {
  auto p = read_xyz(args, "centre");
  double rad = args.real("rad");
  ctx.session.require_started();   // the radius is weighed against the START space
  if (const std::string why = ball_radius_problem(ctx.session.state().space, rad); !why.empty()) args.fail(why);
  std::int64_t id = 0;
  int type = 1;
  while (!args.empty()) {
    auto k = args.expect({"id", "type"}, "BALL option");
    if (k == 0) id = args.count("id", 1);
    else type = static_cast<int>(args.count("type", 1, 1000000));
  }
  // (Under mpirun, where the ranks hold a batch deck's BALL lines, every rank runs this: rank 0's
  // output alone is shown.)
  const std::int64_t made = ctx.session.add_ball_line(id, type, p[0], p[1], p[2], rad);
  // Placed as asked (the user may mean it), but a ball across a wall is thrown off at the first step.
  for (const Wall& w : ctx.session.state().walls)
    if (const std::string how = against_wall(w, {p[0], p[1], p[2]}, rad); !how.empty())
      ctx.warn(fmt::format("BALL: ball {} {}; placed as asked", made, how));
  if (ctx.interp.interactive) ctx.out << fmt::format("ball {} created\n", made);
}

const Command ball_command = {
    "BALL", {"CREATE"}, "BALL x y z rad [id i] [type t]",
    "one ball",
    "Creates one ball at (x, y, z) with radius rad, at rest; the radius must be positive and at most the START "
    "space's diagonal (a larger ball would cover all of it). Without `id` it takes one more than the largest "
    "id; an id already taken is an error, and so is a centre another ball has (the two would have no normal "
    "between them and fly apart; the message names the ball). Type defaults to 1. A ball that crosses a wall "
    "or lies on its wrong side (behind a plane, outside a container cylinder or past its end, inside an "
    "`outside` cylinder) is placed as asked, with a warning naming the ball, the wall and the gap from the "
    "ball's surface to the wall (the first CYCLE would push it off hard; GEN places no ball there).",
    "ball 0.05 0.05 0.1 0.003 id 1001",
    {"id", "type"}, run_ball, true, false, OnRanks::ModelOnZero, HeldUse::Add};

}  // namespace trubal
