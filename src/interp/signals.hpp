// Ctrl-C: while a command runs it asks the command to stop at the end of the current step.
#pragma once

#include <atomic>

namespace trubal {

std::atomic<bool>& interrupt_requested();
// Installs the SIGINT handler that sets interrupt_requested() (a second Ctrl-C while the flag is
// still set ends the program the usual way). Under mpirun (several ranks) also SIGUSR1, which
// mpirun forwards to every rank, and SIGTERM, which mpirun sends them when it is itself
// interrupted (Ctrl-C at its terminal), a second before it kills them.
void install_interrupt_handler();

// Whether to stop now: interrupt_requested(), under mpirun agreed among the ranks (any rank's flag
// stops all, and sets every rank's). A collective call there: every rank makes it at the same
// point of the same computation (GEN's placement, a CYCLE's step).
bool interrupt_now();

// While one lives, this rank runs a command alone (OnRanks::ModelOnZero, RankZero: rank 0), which
// then makes no collective call: interrupt_now asks this rank's flag alone, and an input file
// rank 0 reads is not handed to the others (Interpreter::read_file_on_root).
class RankAlone {
 public:
  RankAlone();
  ~RankAlone();
  RankAlone(const RankAlone&) = delete;
  RankAlone& operator=(const RankAlone&) = delete;

 private:
  bool before_;
};
bool rank_alone();

}  // namespace trubal
