#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_renumber(Context& ctx, Args& args) {
  const std::size_t how = args.keyword({"space", "present"}).value_or(0);
  args.done();
  const std::size_t n = ctx.session.state().balls.size();
  const Renumbering r = ctx.session.renumber(how == 0 ? RenumberOrder::Space : RenumberOrder::Present);
  if (n == 0)
    ctx.out << "no balls to renumber\n";
  else if (how == 0)
    ctx.out << fmt::format("{} balls renumbered 1 to {} in space order (cells {:.6g} wide)\n", n, n, r.cell);
  else
    ctx.out << fmt::format("{} balls renumbered 1 to {} in their present order\n", n, n);
}

const Command renumber_command = {
    "RENUMBER", {}, "RENUMBER [space | present]", "give the balls ids 1 to N, in space order",
    "Gives the balls the ids 1 to N. `space` (the default) numbers them in space order: the Morton (Z) order "
    "of cubic cells one largest diameter wide, from the lowest centre, balls in one cell in the order of their "
    "ids, as LAMMPS's `reset_atoms id sort yes` numbers atoms by bins. `present` keeps the order of their "
    "ids and closes the gaps DELETE left. The run keeps the balls in space order in memory whatever their ids "
    "(SET sort), so RENUMBER is for the ids themselves: compact, or near in number where near in space. The balls and their contacts stay as "
    "they are (a contact's shear history follows it); groups, the membrane's balls, HIST's platens and PRINT "
    "psd's balls follow their balls. Ids given later (ranges by `id`, BALL's `id`) are the new ones; so is the id "
    "of a `HIST ball n` given before: it records whichever ball has id n (its columns keep their names). A run "
    "renumbered at the same point gives the same results on every backend and however it is cut, as any command "
    "does; it is not the run without RENUMBER, since each ball then adds its contacts in another order (the same "
    "physics, other rounding).",
    "renumber",
    {"space", "present"}, run_renumber};

}  // namespace trubal
