#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_save(Context& ctx, Args& args) {
  std::string file = args.word("file name");
  args.done();
  ctx.session.require_started();
  ctx.session.save(file);
  ctx.out << fmt::format("saved to {} (cycle {})\n", file, ctx.session.state().cycle);
}

const Command save_command = {
    "SAVE", {}, "SAVE file", "write the whole state",
    "Writes the whole state (balls, contacts with their shear history, materials, settings, groups, energy) "
    "to a versioned binary file with a checksum. The bytes are those of the state alone: a run cut into "
    "CYCLEs, or run on another backend or on several processes, saves the same bytes as the straight run. "
    "The file is written to a temporary name and renamed, so an existing save is never left half-written. The "
    "histories (HIST) are saved with their settings and the rows they hold in memory; the backend choice is not "
    "saved.",
    "save dense.sav",
    {}, run_save, false, false, OnRanks::RankZero};

static void run_restart(Context& ctx, Args& args) {
  std::string file = args.word("file name");
  args.done();
  const auto notes = ctx.session.restart(file);
  const auto& m = ctx.session.state();   // (the light state: the ranks' parts may hold the rest)
  ctx.out << fmt::format("restarted from {}: {}, cycle {}\n", file, count_of(m.balls.size(), "ball"), m.cycle);
  const auto& tables = ctx.session.history().tables();
  if (!tables.empty())
    ctx.out << fmt::format("  {} histories resumed (PRINT history lists them)\n", tables.size());
  for (const auto& note : notes) ctx.warn(note);
}

const Command restart_command = {
    "RESTART", {"RESTORE"}, "RESTART file", "read a saved state",
    "Reads a file written by SAVE; cycling then continues exactly (bitwise) as the saved run would have. A "
    "truncated, corrupted or foreign file is refused with an error and the current model is kept, as is a FIFO "
    "or a device (reading one would wait for a writer, or never end). The saved "
    "histories resume: each HIST file is appended to, after its rows past the saved cycle (of a later part of "
    "the run that wrote it) are dropped, and so is a last row cut short (a full disk or a killed run stopped "
    "the writing inside it); rows the save holds that the file lacks are written again. A file that is missing "
    "or holds other columns is started afresh with the rows the save kept. RESTART says what it did to each. A HIST given again with the same quantities, period and file "
    "(a deck that repeats its HIST after RESTART) goes on with the resumed history. A save of format 5 or older "
    "restarts with no histories. The file is read a buffer at a time (its checksum first, then the state), never "
    "held whole in memory beside the model.",
    "restart dense.sav",
    // (Every rank runs it: rank 0 alone reads the file, the others take its light state: Session::restart.)
    {}, run_restart, false, false, OnRanks::Parts};

}  // namespace trubal
