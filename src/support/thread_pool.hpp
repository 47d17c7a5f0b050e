// Persistent workers for the threaded and allpairs backends: created once with the backend, woken
// twice a step. The caller is worker 0, so a pool of one runs everything on the calling thread.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace trubal {

class ThreadPool {
 public:
  // Throws std::runtime_error when the system will not start all the threads (none is left running).
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int size() const { return size_; }
  // Runs task(t) for t = 0 .. size()-1 (t = 0 on the calling thread); returns when all are done,
  // rethrowing the first exception a task threw.
  void run(const std::function<void(int)>& task);
  // The same tasks, but on the calling thread one after another when `parallel` is false: work too
  // small to pay for waking the workers keeps the same partition, hence the same answer.
  void run(const std::function<void(int)>& task, bool parallel) {
    if (parallel) { run(task); return; }
    for (int t = 0; t < size_; ++t) task(t);
  }

  // The machine's thread count (at least 1): the default for `threads`.
  static int hardware_threads();

 private:
  void work(int t);
  void stop_workers();   // wakes the workers to stop and joins them

  int size_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(int)>* task_ = nullptr;   // written under mutex_ before a generation
  std::atomic<std::uint64_t> generation_{0};           // bumped once per run()
  std::atomic<int> pending_{0};                        // workers (not the caller) still running
  bool stop_ = false;
  std::exception_ptr error_;
};

// Splits [0, count) into `parts` contiguous ranges; range t is [split(t), split(t+1)).
inline std::size_t split_point(std::size_t count, int parts, int t) {
  return static_cast<std::size_t>(static_cast<unsigned __int128>(count) * static_cast<unsigned>(t) /
                                  static_cast<unsigned>(parts));
}

}  // namespace trubal
