// Pieces several command files share: RANGE phrases, vectors of numbers, the command list.
#pragma once

#include <array>
#include <chrono>
#include <functional>
#include <string>

#include "interp/command.hpp"
#include "support/format_number.hpp"
#include "interp/interpreter.hpp"
#include "model/range.hpp"
#include "session.hpp"

namespace trubal {

// Reads an optional RANGE phrase, which ends the command (so done() is checked here). A `group`
// that the model does not hold is an error (with the nearest group's name where one is near): a
// misspelt group would otherwise hold for no ball and the deck run on.
// `stop`: words that end the phrase before the command does (BOND's, whose words may follow it).
Range read_range(Args& args, const Session& session, const std::vector<std::string_view>& stop = {});
// The phrase alone, its groups not looked up (GEN's: the balls it makes are in no group yet).
Range read_range(Args& args, const std::vector<std::string_view>& stop = {});
// The words a RANGE phrase takes, for completion.
extern const std::vector<std::string_view> kRangeWords;
// Three numbers named prefix x, y, z in messages.
std::array<double, 3> read_xyz(Args& args, std::string_view what);
// Reports a long CYCLE's or SOLVE's progress. At the interactive prompt on a terminal (and no log
// file): one bar redrawn at most four times a second, erased by finish(). Otherwise (batch, a pipe,
// SET log): a plain line every SET progress seconds (default 10), never a control character.
class ProgressReporter {
 public:
  // `limit`: the total is an upper bound (SOLVE), so the time left is "at most".
  explicit ProgressReporter(Context& ctx, bool limit = false);
  ~ProgressReporter();
  ProgressReporter(const ProgressReporter&) = delete;
  ProgressReporter& operator=(const ProgressReporter&) = delete;
  // For Session::cycle / solve; refers to this object.
  std::function<void(std::int64_t, std::int64_t)> callback();
  // Erases the bar, if one is shown, so the next line starts clean.
  void finish();

 private:
  void report(std::int64_t done, std::int64_t total);
  Context& ctx_;
  bool bar_, limit_, shown_ = false;
  double interval_;
  std::chrono::steady_clock::time_point start_, last_;
};
// Prints what a CYCLE or SOLVE did (interrupted, unstable) and throws for an unstable run.
void report_cycle_result(Context& ctx, const CycleResult& r, std::int64_t asked);

// Command::ranks_for of the commands that change the balls where a range holds (INIT, APPLY, FIX,
// FREE, GROUP): every rank on its part where the ranks keep their parts (Session::change_balls,
// define_group), else rank 0 alone on its whole model.
inline OnRanks parts_where_kept(const Args&, bool parts_kept) { return parts_kept ? OnRanks::Parts : OnRanks::ModelOnZero; }

// One Command object per file in commands/.
#define TRUBAL_COMMANDS(X)                                                                                   \
  X(start) X(gen) X(ball) X(lattice) X(delete) X(renumber) X(bond) X(group) X(prop) X(damp) X(frac) X(tstep) X(grav) X(fix)    \
  X(free) X(init) X(apply) X(wall) X(membrane) X(strain) X(servo) X(sample) X(cycle) X(solve) X(print) X(hist) X(plot) X(dump) \
  X(save) X(restart) X(backend) X(set) X(call) X(echo) X(title) X(help) X(stop)
#define TRUBAL_DECLARE_COMMAND(name) extern const Command name##_command;
TRUBAL_COMMANDS(TRUBAL_DECLARE_COMMAND)
#undef TRUBAL_DECLARE_COMMAND

}  // namespace trubal
