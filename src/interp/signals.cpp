#include "interp/signals.hpp"

#include <csignal>

#include "support/comm.hpp"

namespace trubal {

std::atomic<bool>& interrupt_requested() {
  static std::atomic<bool> flag{false};
  return flag;
}

static void on_sigint(int signal) {
  if (interrupt_requested().exchange(true)) {
    std::signal(signal, SIG_DFL);
    std::raise(signal);
  }
}

static void on_sigusr1(int) { interrupt_requested().store(true); }

void install_interrupt_handler() {
  struct sigaction sa {};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  if (comm::size() > 1) {
    sigaction(SIGTERM, &sa, nullptr);
    struct sigaction usr {};
    usr.sa_handler = on_sigusr1;
    sigemptyset(&usr.sa_mask);
    usr.sa_flags = SA_RESTART;
    sigaction(SIGUSR1, &usr, nullptr);
  }
}

namespace {
bool g_rank_alone = false;   // (the interpreter's thread alone runs commands)
}  // namespace

RankAlone::RankAlone() : before_(g_rank_alone) { g_rank_alone = true; }
RankAlone::~RankAlone() { g_rank_alone = before_; }
bool rank_alone() { return g_rank_alone; }

bool interrupt_now() {
  if (comm::size() == 1 || g_rank_alone) return interrupt_requested().load();
  const bool any = comm::any_all(interrupt_requested().load());
  if (any) interrupt_requested().store(true);
  return any;
}

}  // namespace trubal
