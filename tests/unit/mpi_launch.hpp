// trubal under mpirun from a test: the environment every rank needs on the test machines, and a
// run of a deck on some ranks under a time limit, so that a rank left hanging fails the test
// instead of stalling it.
#pragma once

#include <string>

#include "counters.hpp"
#include "interp_support.hpp"
#include "paths.hpp"

namespace trubal::test {

// Root allowed (CI's containers run as root), more ranks than cores, and under ASan no leak check
// on the ranks (Open MPI keeps allocations of its own start-up to the end).
inline const std::string kMpiEnv =
    "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
    "ASAN_OPTIONS=detect_leaks=0";

// The decomposition's shares kept equal (TRUBAL_EQUAL_SHARES), where a test counts the lists
// rebuilt on the parts: on a loaded machine the ranks' speeds would move the shares, and a change
// of shares makes the parts afresh instead.
inline const std::string kEqualShares = "TRUBAL_EQUAL_SHARES=1";

// The time limit of a run of the cut matrix on ranks: a loaded machine takes a minute or two, a
// hang forever.
inline constexpr int kLongRunLimit = 600;

// The words before trubal's path: `ranks` ranks under mpirun (0: a plain trubal), under `timeout`
// (124 is then the exit status of a run that passed it); `env`: more "NAME=value ..." for every rank.
inline std::string launcher(int ranks, const std::string& env = "", int limit_s = 120) {
  const std::string timeout = "timeout " + std::to_string(limit_s) + " ";
  if (ranks == 0) return timeout;
  return "env " + env + (env.empty() ? "" : " ") + kMpiEnv + " " + timeout + "mpirun -np " + std::to_string(ranks) + " ";
}

// Runs trubal in `dir` with `args` (the file to run and the redirections) on `ranks` ranks (0: a
// plain trubal); returns the exit status.
inline int run_trubal(const TempDir& dir, int ranks, const std::string& args, const std::string& env = "") {
  return shell("cd " + quote(dir.str()) + " && " + launcher(ranks, env) + quote(TRUBAL_EXE) + args);
}

// deck.dat in `dir`, its output in out.txt.
inline int run_deck(const TempDir& dir, int ranks, const std::string& env = "") {
  return run_trubal(dir, ranks, " deck.dat >out.txt 2>&1", env);
}

// deck.dat, then the shell's lines in more.txt (trubal -i), its output in out.txt.
inline int run_shell(const TempDir& dir, int ranks, const std::string& env = "") {
  return run_trubal(dir, ranks, " -i deck.dat <more.txt >out.txt 2>&1", env);
}

// The files the distributed runs compare with the serial run's, and the counts (read back with
// counters_of).
inline const char* const kOutputs = "print balls file balls.csv\nprint contacts file contacts.csv\n";
inline const char* const kCounters = "print counters file counters.txt\n";
inline Counters counters_of(const TempDir& dir) { return read_counters(dir.path() / "counters.txt"); }

}  // namespace trubal::test
