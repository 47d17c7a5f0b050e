#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_save(Context& ctx, Args& args) {
  std::string file = args.word("file name");
  args.done();
  ctx.session.require_started();
  ctx.session.save(file);
  ctx.out << fmt::format("saved to {} (cycle {})\n", file, ctx.session.model().cycle);
}

const Command save_command = {
    "SAVE", {}, "SAVE file", "write the whole state",
    "Writes the whole state (balls, contacts with their shear history, materials, settings, groups, energy) "
    "to a versioned binary file with a checksum. The file is written to a temporary name and renamed, so "
    "an existing save is never left half-written. Histories and the backend choice are not saved.",
    {}, run_save};

static void run_restart(Context& ctx, Args& args) {
  std::string file = args.word("file name");
  args.done();
  ctx.session.restart(file);
  const auto& m = ctx.session.model();
  ctx.out << fmt::format("restarted from {}: {} balls, cycle {}\n", file, m.balls.size(), m.cycle);
}

const Command restart_command = {
    "RESTART", {"RESTORE"}, "RESTART file", "read a saved state",
    "Reads a file written by SAVE; cycling then continues exactly (bitwise) as the saved run would have. A "
    "truncated, corrupted or foreign file is refused with an error and the current model is kept.",
    {}, run_restart};

}  // namespace trubal
