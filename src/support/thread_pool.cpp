#include "support/thread_pool.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

namespace trubal {
namespace {

// How long a waiting thread spins before it sleeps on the condition variable. A step's phases
// follow each other within microseconds, and the serial work between steps (the stale-list test,
// the engine's bookkeeping, most output) is short. A thread that sleeps costs a system call to wake
// and, on a virtual machine, the hypervisor's wake-up of its core (bench/NOTES.md has what a short
// spin cost). Intel's OpenMP runtime spins 200 ms by default (KMP_BLOCKTIME); we spin 20 ms, the
// first 50 us on the pause instruction, the rest yielding the core between looks, so that an
// oversubscribed machine loses little to the spinning thread.
constexpr std::chrono::microseconds kPauseSpin{50};
constexpr std::chrono::milliseconds kYieldSpin{20};

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#else
  std::this_thread::yield();
#endif
}

// Spins until ready() or the spin time is over; whether ready() held.
template <class Ready> bool spin_until(Ready ready) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  for (;;) {
    for (int s = 0; s < 64; ++s) {
      if (ready()) return true;
      cpu_relax();
    }
    const auto waited = Clock::now() - start;
    if (waited > kYieldSpin) return ready();
    if (waited > kPauseSpin) std::this_thread::yield();
  }
}

}  // namespace

int ThreadPool::hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

ThreadPool::ThreadPool(int threads) : size_(std::max(1, threads)) {
  workers_.reserve(size_ - 1);
  for (int t = 1; t < size_; ++t) {
    try {
      workers_.emplace_back([this, t] { work(t); });
    } catch (const std::exception& e) {
      // The system would not start more (memory, limits): stop and join the ones that started, as
      // the destructor would, and say so (a constructor that throws runs no destructor).
      stop_workers();
      throw std::runtime_error(std::string("could not start thread ") + std::to_string(t + 1) + " of " +
                               std::to_string(size_) + " (" + e.what() + "); ask for fewer threads");
    }
  }
}

void ThreadPool::stop_workers() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  for (auto& w : workers_) w.join();
  workers_.clear();
}

ThreadPool::~ThreadPool() { stop_workers(); }

void ThreadPool::run(const std::function<void(int)>& task) {
  if (size_ == 1) { task(0); return; }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    task_ = &task;
    error_ = nullptr;
    pending_.store(size_ - 1, std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  std::exception_ptr mine;
  try { task(0); } catch (...) { mine = std::current_exception(); }
  spin_until([&] { return pending_.load(std::memory_order_acquire) == 0; });
  {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return pending_.load(std::memory_order_acquire) == 0; });
    task_ = nullptr;
    if (!mine) mine = error_;
  }
  if (mine) std::rethrow_exception(mine);
}

void ThreadPool::work(int t) {
  std::uint64_t seen = 0;
  for (;;) {
    spin_until([&] { return generation_.load(std::memory_order_acquire) != seen; });
    const std::function<void(int)>* task;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return generation_.load(std::memory_order_acquire) != seen; });
      seen = generation_.load(std::memory_order_acquire);
      if (stop_) return;
      task = task_;
    }
    try {
      (*task)(t);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
      std::lock_guard<std::mutex> lock(mutex_);   // the caller checks pending_ under the lock
      done_.notify_one();
    }
  }
}

}  // namespace trubal
