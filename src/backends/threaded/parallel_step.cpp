#include "backends/threaded/parallel_step.hpp"

#include <algorithm>

namespace trubal {

void ParallelStep::phase(ThreadPool& pool, Model& model, const StepKernels& kernels, ContactLoop loop,
                         std::size_t count, StepSums& sums) {
  const std::size_t blocks = (count + kReduceBlock - 1) / kReduceBlock;
  blocks_.assign(blocks, StepSums{});
  const int parts = static_cast<int>(std::min<std::size_t>(pool.size(), std::max<std::size_t>(blocks, 1)));
  pool.run([&](int t) {
    if (t >= parts) return;
    for (std::size_t b = split_point(blocks, parts, t), e = split_point(blocks, parts, t + 1); b < e; ++b)
      loop(model, kernels, b * kReduceBlock, std::min(count, (b + 1) * kReduceBlock), blocks_[b]);
  }, parts > 1);
  for (const StepSums& block : blocks_) sums.add(block);
}

void ParallelStep::run(ThreadPool& pool, Model& model, const StepKernels& kernels, StepSums& sums) {
  phase(pool, model, kernels, kernels.contacts, model.contacts.size(), sums);
  phase(pool, model, kernels, kernels.motion, model.balls.size(), sums);
}

}  // namespace trubal
