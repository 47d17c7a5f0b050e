// What cycle/pipeline.cpp and cycle/pipeline_bricks.cpp share: the pipeline's walk over its parts
// and two small helpers. Included by those two files alone.
#pragma once

#include <chrono>
#include <exception>
#include <mutex>

#include "cycle/pipeline.hpp"

namespace trubal {

// PRINT info's "last step shared by" where such a scene's steps are timed faster on one thread.
inline constexpr const char* kOneThread = "one thread (sharing the steps in space was timed slower)";

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

template <class F> void Pipeline::each_part(F&& f) {
  if (bricks_.size() == 1) { f(*bricks_[0], 0); return; }
  // A thread that fails (out of memory) releases the others from the team's barriers, so the
  // pool returns and rethrows its error instead of waiting forever; the parts are then dropped.
  // The error rethrown is the thread's that failed first, not the others' "another thread failed".
  thread_team_->sync.reset();
  std::mutex first_mutex;
  std::exception_ptr first;
  try {
    pool_.run([&](int t) {
      try {
        f(*bricks_[t], t);
      } catch (const TeamAborted&) {
        throw;
      } catch (...) {
        {
          std::lock_guard<std::mutex> lock(first_mutex);
          if (!first) first = std::current_exception();
        }
        thread_team_->sync.abort();
        throw;
      }
    });
  } catch (...) {
    if (first) std::rethrow_exception(first);
    throw;
  }
}

}  // namespace trubal
