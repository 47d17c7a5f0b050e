#include "cycle/parallel_step.hpp"

#include "cycle/bond_pass.hpp"
#include "cycle/bridge_pass.hpp"
#include "physics/walls.hpp"

#include <algorithm>
#include <chrono>

namespace trubal {

void ParallelStep::split(const ContactTable& c, const StepScratch& scratch, std::size_t balls, int parts) {
  const std::size_t blocks = (balls + kContactBalls - 1) / kContactBalls;
  split_version_ = c.list_version;
  split_parts_ = parts;
  first_block_.assign(parts + 1, blocks);
  first_block_[0] = 0;
  if (parts == 1) { cross_lists(c, balls, parts); return; }
  // start[k]: pairs before block k; cross[k]: pairs with i before block k and j in or after it.
  std::vector<std::size_t> start(blocks + 1), cross(blocks + 2, 0);
  for (std::size_t k = 0; k <= blocks; ++k) start[k] = scratch.run_begin[std::min(balls, k * kContactBalls)];
  for (std::size_t p = 0; p < c.size(); ++p) {
    const std::size_t bi = c.i[p] / kContactBalls, bj = c.j[p] / kContactBalls;
    if (bj > bi) { ++cross[bi + 1]; --cross[bj + 1]; }
  }
  for (std::size_t k = 1; k <= blocks; ++k) cross[k] += cross[k - 1];
  // The smallest largest cost that `parts` runs of blocks can have, a run [a, b) costing
  // start[b] - start[a] + cross[a] (its own pairs and, roughly, the cross pairs it redoes: a cross
  // pair costs more, but weighting it made the split worse; bench/NOTES.md).
  auto fits = [&](std::size_t most, bool record) {
    std::size_t a = 0;
    for (int t = 0; t < parts; ++t) {
      if (record) first_block_[t] = a;
      std::size_t b = a;
      while (b < blocks && start[b + 1] - start[a] + cross[a] <= most) ++b;
      if (b == a && a < blocks) return false;   // a block alone exceeds `most`
      a = b;
    }
    if (record) first_block_[parts] = blocks;
    return a == blocks;
  };
  std::size_t lo = 0, hi = start[blocks] + c.size() + 1;
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (fits(mid, false)) hi = mid; else lo = mid + 1;
  }
  if (!fits(lo, true)) {   // cannot happen (hi always fits); keep a valid split anyway
    for (int t = 0; t <= parts; ++t) first_block_[t] = split_point(blocks, parts, t);
  }
  cross_lists(c, balls, parts);
}

void ParallelStep::split_if_stale(const ContactTable& c, const StepScratch& scratch, std::size_t balls, int parts) {
  const std::size_t blocks = (balls + kContactBalls - 1) / kContactBalls;
  if (c.list_version != split_version_ || parts != split_parts_ || first_block_.size() != static_cast<std::size_t>(parts) + 1 ||
      first_block_.back() != blocks)
    split(c, scratch, balls, parts);
}

void set_wall_loads(std::vector<Wall>& walls, std::vector<WallLoad>& totals, bool loads) {
  for (std::size_t w = 0; w < walls.size() && w < totals.size(); ++w) {
    WallLoad& total = totals[w];
    Wall& wall = walls[w];
    wall.work += total.work.value();
    wall.relative_kinetic = total.relative_kinetic.value();
    if (!loads) continue;
    wall.force = {total.fx.value(), total.fy.value(), total.fz.value()};
    wall.moment = {total.mx.value(), total.my.value(), total.mz.value()};
    wall.normal_force = total.normal_force.value();
    wall.stiffness = total.stiffness.value();
    wall.contacts = total.contacts;
  }
}

void ParallelStep::add_wall_loads(Model& model, int parts, bool loads, bool moving) {
  // Each wall's load: every thread's exact sums merged (where the loads are not formed, the two
  // that are: the work and the kinetic energy in the wall's frame; where besides no wall moves,
  // those are zero, and the threads' parts, not cleared for that step, are not read).
  const std::size_t wall_count = model.walls.size();
  wall_totals_.resize(wall_count);
  for (std::size_t w = 0; w < wall_count; ++w) {
    WallLoad& total = wall_totals_[w];
    if (!loads && !moving) {
      total.work = total.relative_kinetic = ExactSum{};
    } else if (loads) {
      total = WallLoad{};
      for (int t = 0; t < parts; ++t) total.add(wall_loads_[t * wall_count + w]);
    } else {
      total.work = total.relative_kinetic = ExactSum{};
      for (int t = 0; t < parts; ++t) {
        total.work.add(wall_loads_[t * wall_count + w].work);
        total.relative_kinetic.add(wall_loads_[t * wall_count + w].relative_kinetic);
      }
    }
  }
  if (!part_only_) set_wall_loads(model.walls, wall_totals_, loads);
}

bool ParallelStep::share_now(std::size_t balls, int parts) {
  const int rule = policy_->share_rule;
  if (rule != 0) return rule > 0;
  return trial_.shared_now(balls, parts);
}

void ParallelStep::cross_lists(const ContactTable& c, std::size_t balls, int parts) {
  cross_.assign(parts, {});
  if (parts == 1) return;
  // The thread owning each block, then each pair whose j a later thread owns than its i.
  const std::size_t blocks = (balls + kContactBalls - 1) / kContactBalls;
  std::vector<int> owner(blocks, parts - 1);
  for (int t = 0; t < parts; ++t)
    for (std::size_t k = first_block_[t]; k < first_block_[t + 1]; ++k) owner[k] = t;
  for (std::size_t p = 0; p < c.size(); ++p) {
    const int ti = owner[c.i[p] / kContactBalls], tj = owner[c.j[p] / kContactBalls];
    if (tj != ti) cross_[tj].push_back(static_cast<std::uint32_t>(p));
  }
}

// Scenes with rolling resistance (Features::rolling), before the law of motion of balls [begin, end):
// each ball's rolling moment M joins its shear forces' -R t as t - M / R (the motion loop makes the
// moment from that one sum), and its rolling work goes to the step's sum (a ghost's is its owner's).
// Out of the motion loops' templates, which scenes without it then do not carry.
static void add_rolling(const Balls& b, StepScratch& scratch, std::size_t begin, std::size_t end, StepSums& sums) {
  const bool ghosts = !scratch.ghost.empty();
  ExactSum::Stream work(sums.rolling_work);
  for (std::size_t i = begin; i < end; ++i) {
    const RollingMoment& m = scratch.ball_rolling[i];
    PairForce& f = scratch.ball_force[i];
    f.tx -= m.mx / b.rad[i]; f.ty -= m.my / b.rad[i]; f.tz -= m.mz / b.rad[i];
    if (!ghosts || !scratch.ghost[i]) work.add(m.work);
  }
}

void ParallelStep::run(ThreadPool& pool, Model& model, StepScratch& scratch, const StepKernels& kernels, StepSums& sums,
                       PhaseTimes& times, const VerletReference* moved) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  if (kernels.writes_results()) model.contacts.keep_results();   // where they were not kept
  const ContactTable& c = model.contacts;
  const std::size_t balls = model.balls.size();
  const std::size_t blocks = (balls + kContactBalls - 1) / kContactBalls;
  auto block_ball = [&](std::size_t k) { return std::min(balls, k * kContactBalls); };
  auto block_pair = [&](std::size_t k) { return static_cast<std::size_t>(scratch.run_begin[block_ball(k)]); };

  const int parts = static_cast<int>(std::min<std::size_t>(pool.size(), std::max<std::size_t>(blocks, 1)));
  split_if_stale(c, scratch, balls, parts);
  const bool parallel = parts > 1 && share_now(balls, parts);
  const int threads = parallel ? static_cast<int>(pool.size()) : 1;
  // Thread 0 adds to `sums` itself, the others to parts of their own merged after (exact sums, a
  // min and a max: the same in any order).
  if (threads > 1) thread_sums_.assign(threads, StepSums{});
  auto part = [&](int t) -> StepSums& { return t == 0 ? sums : thread_sums_[t]; };
  const std::size_t wall_count = model.walls.size();
  auto block_wall = [&](std::size_t k) { return static_cast<std::size_t>(scratch.wall_run_begin[block_ball(k)]); };
  // Each thread's loads, zero: all of them where the step forms the loads, else the two it adds
  // to (StepKernels::wall_loads), and none where no wall moves.
  const bool loads = kernels.wall_loads;
  bool moving = false;
  for (const Wall& w : model.walls) moving = moving || !wall_still(w);
  if (wall_count && (loads || wall_loads_.size() < threads * wall_count)) {
    wall_loads_.assign(threads * wall_count, WallLoad{});
  } else if (wall_count && moving) {
    for (std::size_t k = 0; k < threads * wall_count; ++k) wall_loads_[k].work = wall_loads_[k].relative_kinetic = ExactSum{};
  }
  // After all of a thread's blocks (every sum of its balls is then complete): its balls' wall contacts.
  auto walls = [&](std::size_t first, std::size_t last, int t) {
    if (!wall_count) return;
    for (std::size_t k = first; k < last; ++k)
      kernels.walls(model, scratch, kernels, block_wall(k), block_wall(k + 1), &wall_loads_[t * wall_count]);
  };
  // Every pair's owner writes its new history over the table's, a batch at a time; a thread's cross
  // pairs belong to an earlier thread, which may already be writing them, so their history before
  // the step is copied first (a few pairs: those across the threads' boundaries), and the passes
  // need no barrier between them.
  if (parallel) {
    cross_history_.resize(parts);
    for (int t = 0; t < parts; ++t) {
      std::vector<double>& h = cross_history_[t];
      const std::vector<std::uint32_t>& list = cross_[t];
      const std::size_t n = kernels.features.friction ? list.size() : 0;
      // Every history array's values of these pairs, one array after another (for_each_history's
      // order: the kernel reads each part's at its place).
      h.resize(c.history_count() * n);
      std::size_t at = 0;
      c.for_each_history([&](const auto& v, const HistoryPart&) {
        for (std::size_t q = 0; q < n; ++q) h[at + q] = v[list[q]];
        at += n;
      });
    }
    pool.run([&](int t) {
      if (t >= parts) return;
      const std::size_t own_end = block_ball(first_block_[t + 1]);
      kernels.cross(model, scratch, kernels, block_ball(first_block_[t]), own_end, cross_[t].data(), cross_[t].size(),
                    cross_history_[t].data());
      for (std::size_t k = first_block_[t]; k < first_block_[t + 1]; ++k)   // block by block: the same batches
        kernels.contacts(model, scratch, kernels, block_pair(k), block_pair(k + 1), own_end);
      walls(first_block_[t], first_block_[t + 1], t);
    });
  } else {   // every block on this thread: no cross pairs
    kernels.cross(model, scratch, kernels, 0, balls, nullptr, 0, nullptr);
    for (std::size_t k = 0; k < blocks; ++k) kernels.contacts(model, scratch, kernels, block_pair(k), block_pair(k + 1), balls);
    walls(0, blocks, 0);
  }
  // Scenes with capillary bridges: each pair's and wall contact's bridge, by the owner of its
  // block (cycle/bridge_pass.hpp), once every contact loop is done.
  if (kernels.features.bridges) {
    prepare_bridges(model, scratch);
    auto bridges = [&](std::size_t first, std::size_t last, int t) {
      bridge_pairs(model, scratch, kernels, block_pair(first), block_pair(last), part(t));
      if (wall_count) bridge_walls(model, scratch, kernels, block_wall(first), block_wall(last), &wall_loads_[t * wall_count]);
    };
    if (parallel) pool.run([&](int t) { if (t < parts) bridges(first_block_[t], first_block_[t + 1], t); });
    else bridges(0, blocks, 0);
  }
  // Scenes with bonds: each bond's push, the step's order in equal shares (cycle/bond_pass.hpp).
  if (kernels.features.bonds) {
    prepare_bonds(model, scratch, parallel ? parts : 1);
    const std::size_t bonds = bond_places(scratch);
    auto share = [&](int t, int of) { bond_forces(model, scratch, kernels, split_point(bonds, of, t), split_point(bonds, of, t + 1), part(t), t); };
    if (parallel) pool.run([&](int t) { if (t < parts) share(t, parts); });
    else share(0, 1);
    settle_broken_bonds(scratch);
  }
  if (wall_count) add_wall_loads(model, threads, loads, moving);
  const auto t1 = Clock::now();

  // The balls in equal shares (the contact split may be uneven, to even out cross pairs).
  const std::size_t motion_blocks = (balls + kReduceBlock - 1) / kReduceBlock;
  const int motion_parts = parallel ? static_cast<int>(std::min<std::size_t>(pool.size(), motion_blocks)) : 1;
  moved_.assign(motion_parts, 0.0);
  pool.run([&](int t) {
    if (t >= motion_parts) return;
    const std::size_t first = split_point(motion_blocks, motion_parts, t), last = split_point(motion_blocks, motion_parts, t + 1);
    const std::size_t ball0 = std::min(balls, first * kReduceBlock), ball1 = std::min(balls, last * kReduceBlock);
    if (kernels.features.rolling) add_rolling(model.balls, scratch, ball0, ball1, part(t));
    if (kernels.features.bridges) add_bridges(model, scratch, ball0, ball1);
    if (kernels.features.bonds) add_bonds(scratch, kernels, ball0, ball1);
    kernels.motion(model, scratch, kernels, ball0, ball1, part(t));
    if (kernels.features.bridges) bridge_work(model, scratch, kernels, ball0, ball1, part(t));
    if (moved) moved_[t] = moved->max_displacement2(model.balls, ball0, ball1);
  }, motion_parts > 1);
  moved2_ = 0;
  for (double m : moved_) moved2_ = std::max(moved2_, m);
  for (int t = 1; t < threads; ++t) sums.add(thread_sums_[t]);
  const auto t2 = Clock::now();
  if (parts > 1 && policy_->share_rule == 0 && trial_.in_trial())
    trial_.record(parallel, std::chrono::duration<double>(t2 - t0).count());
  times.forces += std::chrono::duration<double>(t1 - t0).count();
  times.motion += std::chrono::duration<double>(t2 - t1).count();
}

}  // namespace trubal
