// The contact and motion kernels of one step spread over a thread pool. Each thread takes a run
// of whole kReduceBlock blocks and calls the kernel once per block, exactly as the serial backend
// does; block sums are kept per block and added in ascending block order afterwards. So the
// arithmetic, and the answer, is the serial one for every thread count.
#pragma once

#include <vector>

#include "backends/threaded/thread_pool.hpp"
#include "model/model.hpp"
#include "physics/kernels.hpp"

namespace trubal {

class ParallelStep {
 public:
  // Contacts over model.contacts (every pair), then motion over the balls.
  void run(ThreadPool& pool, Model& model, const StepKernels& kernels, StepSums& sums);

 private:
  void phase(ThreadPool& pool, Model& model, const StepKernels& kernels, ContactLoop loop, std::size_t count,
             StepSums& sums);
  std::vector<StepSums> blocks_;
};

// Splits [0, count) into `parts` contiguous ranges; range t is [split(t), split(t+1)).
inline std::size_t split_point(std::size_t count, int parts, int t) {
  return static_cast<std::size_t>(static_cast<unsigned __int128>(count) * static_cast<unsigned>(t) /
                                  static_cast<unsigned>(parts));
}

}  // namespace trubal
