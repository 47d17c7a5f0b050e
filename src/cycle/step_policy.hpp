// How a run's steps are shared among threads and ranks where the default is a timed or measured
// choice, and the faults a test injects. One per Session (the pipeline and what it holds read it
// by reference; a pipeline made without one keeps its own defaults). The defaults are a normal
// run's: tests set other values to force one path on any machine; main.cpp sets some from the
// environment (TRUBAL_TEST_FAIL_AT, TRUBAL_REBUILD_WHOLE). No rule changes the answer: every
// path gives the same bits.
#pragma once

#include <cstdint>

namespace trubal {

struct StepPolicy {
  // Whether the threads share the steps in space (a part of the decomposition each) rather than by
  // ball numbers: 0 each pair list decides (Pipeline::threads_in_space), 1 always where there are
  // threads, -1 never.
  int split_rule = 0;
  // The split in space's trial steps count this many times their time (1000: the trial finds one
  // thread faster, 0.001: the split), so that either verdict can be asserted on any machine.
  double space_time_scale = 1.0;
  // Whether the threads share a step at all (ParallelStep): 0 timed (a trial), 1 always (small
  // scenes still exercise the split), -1 never.
  int share_rule = 0;
  // Stale pair lists of a run by the decomposition: 0 rebuilt on the parts where they can be
  // (BrickStep::rebuild_local), -1 always through the whole model (TRUBAL_REBUILD_WHOLE, to compare
  // the two ways in one build).
  int local_rule = 0;
  // The rescue copy of a run by the decomposition: each rank's of its own live part (false), or
  // rank 0's of the whole model (true: TRUBAL_RESCUE_WHOLE, to compare the two ways in one build).
  bool whole_rescue = false;
  // Whether the decomposition's shares follow the members' measured speeds at each split and stale
  // list (BrickStep::proposed_shares; true) or stay equal (false: TRUBAL_EQUAL_SHARES, so that a
  // test may count the lists rebuilt on the parts on a loaded machine, where the speeds would
  // move the shares and have the parts made afresh instead).
  bool follow_speeds = true;
  // The member (team rank) whose own work is counted kSlowFactor times slower at each split, as a
  // busy core would make it, to see the shares follow; -1: none. Eight times, so that a machine
  // busy with other work (which slows both members by up to about two) cannot hide it.
  int slow_member = -1;
  static constexpr double kSlowFactor = 8;
  // The rows of a save's table that a distributed RESTART reads, checks and hands out at a time
  // (SavedTables::check, BrickStep::split_from_file): fewer (TRUBAL_SAVE_PIECE) have a test's small
  // scene cross many pieces.
  std::uint64_t save_piece_rows = std::uint64_t{1} << 16;

  // Faults (TRUBAL_TEST_FAIL_AT), each on one rank of a distributed run (-1: none), each once: the
  // rank's next split of the decomposition ("R split"), next search on its part ("R part") and
  // next share of a search through the whole model ("R search") fail as if out of memory.
  int fail_split = -1;
  // Rank 0 fails as out of memory cutting rank R's part at its next split of the ranks ("R cut";
  // R > 0: the ranks before have theirs, the ones after are told to go without).
  int fail_cut = -1;
  int fail_part_search = -1;
  int fail_search = -1;
  // Rank R's next gather of the contact results from the parts ("R results"), its next step taken
  // again to make them ("R remake": on the parts, or rank 0's alone).
  int fail_results = -1;
  int fail_remake = -1;
  // (A deck's line that fails on one rank, "R L", is the interpreter's: Interpreter::fail_line_for_test.)
};

}  // namespace trubal
