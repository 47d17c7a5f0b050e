#include "backends/threaded/parallel_step.hpp"

#include <algorithm>
#include <chrono>

namespace trubal {

void ParallelStep::run(ThreadPool& pool, Model& model, const StepKernels& kernels, StepSums& sums) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const ContactTable& c = model.contacts;
  const std::size_t balls = model.balls.size();
  const std::size_t blocks = (balls + kContactBalls - 1) / kContactBalls;
  auto block_ball = [&](std::size_t k) { return std::min(balls, k * kContactBalls); };
  auto block_pair = [&](std::size_t k) { return static_cast<std::size_t>(c.run_begin[block_ball(k)]); };

  // Threads take runs of whole blocks with about equal pair counts (a block of many pairs is
  // never split, so a thread may get none).
  const int parts = static_cast<int>(std::min<std::size_t>(pool.size(), std::max<std::size_t>(blocks, 1)));
  first_block_.assign(parts + 1, blocks);
  first_block_[0] = 0;
  const std::size_t pairs = c.size();
  for (int t = 1; t < parts; ++t) {
    const std::size_t target = split_point(pairs, parts, t);
    std::size_t k = first_block_[t - 1];
    while (k < blocks && block_pair(k) < target) ++k;
    first_block_[t] = k;
  }
  const bool parallel = parts > 1;
  blocks_.assign(blocks, StepSums{});
  pool.run([&](int t) {
    if (t >= parts) return;
    kernels.cross(model, kernels, block_ball(first_block_[t]), block_ball(first_block_[t + 1]));
  }, parallel);
  pool.run([&](int t) {
    if (t >= parts) return;
    const std::size_t own_end = block_ball(first_block_[t + 1]);
    for (std::size_t k = first_block_[t]; k < first_block_[t + 1]; ++k)
      kernels.contacts(model, kernels, block_pair(k), block_pair(k + 1), own_end, blocks_[k]);
  }, parallel);
  for (const StepSums& block : blocks_) sums.add(block);
  const auto t1 = Clock::now();

  const std::size_t motion_blocks = (balls + kReduceBlock - 1) / kReduceBlock;
  blocks_.assign(motion_blocks, StepSums{});
  const int motion_parts = static_cast<int>(std::min<std::size_t>(pool.size(), std::max<std::size_t>(motion_blocks, 1)));
  pool.run([&](int t) {
    if (t >= motion_parts) return;
    for (std::size_t k = split_point(motion_blocks, motion_parts, t), e = split_point(motion_blocks, motion_parts, t + 1);
         k < e; ++k)
      kernels.motion(model, kernels, k * kReduceBlock, std::min(balls, (k + 1) * kReduceBlock), blocks_[k]);
  }, motion_parts > 1);
  for (const StepSums& block : blocks_) sums.add(block);
  const auto t2 = Clock::now();
  model.timing.forces += std::chrono::duration<double>(t1 - t0).count();
  model.timing.motion += std::chrono::duration<double>(t2 - t1).count();
}

}  // namespace trubal
