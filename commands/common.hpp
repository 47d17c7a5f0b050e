// Pieces several command files share: RANGE phrases, vectors of numbers, the command list.
#pragma once

#include <array>
#include <string>

#include "interp/command.hpp"
#include "interp/interpreter.hpp"
#include "model/range.hpp"
#include "session.hpp"

namespace trubal {

// Reads an optional RANGE phrase, which ends the command (so done() is checked here).
Range read_range(Args& args);
// The words a RANGE phrase takes, for completion.
extern const std::vector<std::string_view> kRangeWords;
// Three numbers named prefix x, y, z in messages.
std::array<double, 3> read_xyz(Args& args, std::string_view what);
// Reports a long CYCLE's progress (terminal: one refreshed line; otherwise a plain line now and then).
std::function<void(std::int64_t, std::int64_t)> progress_reporter(Context& ctx);
// Prints what a CYCLE or SOLVE did (interrupted, unstable) and throws for an unstable run.
void report_cycle_result(Context& ctx, const CycleResult& r, std::int64_t asked);

// One Command object per file in commands/.
#define TRUBAL_COMMANDS(X)                                                                                   \
  X(start) X(gen) X(ball) X(lattice) X(delete) X(group) X(prop) X(damp) X(frac) X(tstep) X(grav) X(fix)    \
  X(free) X(init) X(apply) X(membrane) X(strain) X(servo) X(cycle) X(solve) X(print) X(hist) X(plot) X(dump) \
  X(save) X(restart) X(backend) X(set) X(call) X(echo) X(title) X(help) X(stop)
#define TRUBAL_DECLARE_COMMAND(name) extern const Command name##_command;
TRUBAL_COMMANDS(TRUBAL_DECLARE_COMMAND)
#undef TRUBAL_DECLARE_COMMAND

}  // namespace trubal
