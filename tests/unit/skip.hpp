// A test whose dependency (mpirun, tmux, gnuplot, a pseudo-terminal) is missing is skipped, never
// passed. ctest runs each TEST_CASE on its own with TRUBAL_TEST_SKIP_CODE set (77, the tests'
// SKIP_RETURN_CODE): TRUBAL_SKIP then prints "SKIP: reason" and ends the process with that code,
// so ctest reports the test as skipped. Where the whole binary runs at once (by hand, under a
// sanitizer) there is no code to exit with: TRUBAL_SKIP warns with the reason and returns from the
// test case, and the cases after it still run.
//
// Call it in the TEST_CASE's own body, before its first assertion and before it makes temporary
// files: an exit leaves neither a failure seen before it nor a destructor's clean-up behind.
#pragma once

#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "support/comm.hpp"

namespace trubal::test {

// The exit status that means "skipped", from TRUBAL_TEST_SKIP_CODE; 0 where it is not set (or not
// a status a process can exit with), and the test then warns and returns instead.
inline int skip_exit_code() {
  const char* text = std::getenv("TRUBAL_TEST_SKIP_CODE");
  if (!text || !*text) return 0;
  char* end = nullptr;
  const long code = std::strtol(text, &end, 10);
  return *end == '\0' && code > 0 && code < 256 ? static_cast<int>(code) : 0;
}

// Writes to the process's stdout itself: a Catch2 reporter may have redirected std::cout.
[[noreturn]] inline void exit_skipped(const std::string& reason, int code) {
  std::fflush(nullptr);
  std::fprintf(stdout, "SKIP: %s\n", reason.c_str());
  std::fflush(stdout);
  std::_Exit(code);
}

// Whether `program` is found on PATH, as the shell that the tests run commands through finds it.
inline bool on_path(const std::string& program) {
  return std::system(("command -v '" + program + "' >/dev/null 2>&1").c_str()) == 0;
}

// Distributed runs need a build with MPI and mpirun on PATH.
inline bool can_run_mpi() { return comm::built_with_mpi() && on_path("mpirun"); }
inline const char* const kNoMpi = "not built with MPI, or no mpirun (Debian: libopenmpi-dev openmpi-bin)";

}  // namespace trubal::test

#define TRUBAL_SKIP(reason)                                                         \
  do {                                                                              \
    const std::string trubal_skip_reason_ = (reason);                               \
    if (const int trubal_skip_code_ = ::trubal::test::skip_exit_code())             \
      ::trubal::test::exit_skipped(trubal_skip_reason_, trubal_skip_code_);         \
    WARN("skipped: " << trubal_skip_reason_);                                       \
    return;                                                                         \
  } while (0)
