// One step's contact and motion kernels over the pipeline's thread pool (a pool of one runs them
// all on the calling thread). Thread t owns a contiguous range of balls, made of whole pair blocks (the pairs of
// kContactBalls consecutive balls i): it zeroes its balls' sums and adds the pairs they have with
// lower balls of earlier ranges (cross pairs, computed again from the same inputs), then runs its
// pair blocks in list order, adding each pair to ball i and to ball j where it owns j. Every
// ball's sum is thus the same additions in the same order (lower partners ascending, then higher
// ones) for every thread count; the global sums (energies) are exact sums, merged from the threads'
// parts (kernels.hpp, StepSums). So the
// answer is the serial one, bit for bit. Each pair's owner writes its new shear history in place;
// the cross pairs read a copy of theirs made before the pass, so no barrier is needed between
// the two. The motion pass then gives each thread an equal share of the balls.
//
// Whether the threads share a step at all is timed (ParallelStep::share_now); the split itself is
// by pair counts, not by measured thread speeds (bench/NOTES.md says why).
#pragma once

#include <vector>

#include "support/thread_pool.hpp"
#include "cycle/kernels.hpp"
#include "cycle/phase_times.hpp"
#include "cycle/step_policy.hpp"
#include "cycle/step_scratch.hpp"
#include "cycle/timed_choice.hpp"
#include "cycle/verlet.hpp"
#include "model/model.hpp"

namespace trubal {

// Each wall's force, moment, normal force, stiffness and contacts from its merged load (rounded
// once), where `loads` (StepKernels::wall_loads); its work grows by the load's, and its
// relative_kinetic is the load's.
void set_wall_loads(std::vector<Wall>& walls, std::vector<WallLoad>& totals, bool loads);

class ParallelStep {
 public:
  // policy: whether the threads share a step (StepPolicy::share_rule), the owner's, outliving this.
  explicit ParallelStep(const StepPolicy& policy) : policy_(&policy) {}

  // Contacts over model.contacts (every pair; `scratch` indexes it), then motion over the balls;
  // the time of each phase is added to `times` (forces, motion).
  // With `moved`, each thread also measures, right after moving its balls, their largest squared
  // displacement from the reference positions of the pair list: the next step's stale-list test
  // (moved2()) costs no pass of its own.
  void run(ThreadPool& pool, Model& model, StepScratch& scratch, const StepKernels& kernels, StepSums& sums,
           PhaseTimes& times, const VerletReference* moved = nullptr);
  double moved2() const { return moved2_; }
  // Threads the steps share their work among: 1 where the rule or the last trial says one thread,
  // at most one per pair block, all of them while a trial runs; 0 before the first step.
  int active() const {
    const int rule = policy_->share_rule;
    const bool sharing = rule != 0 ? rule > 0 : trial_.in_trial() || trial_.verdict();
    return sharing ? split_parts_ : 1;
  }
  // A rank's part of a spatially decomposed step (cycle/brick_step.hpp): the walls' loads are left
  // in wall_totals() for the ranks to merge, not written to the walls.
  void set_part_only(bool on) { part_only_ = on; }
  std::vector<WallLoad>& wall_totals() { return wall_totals_; }

 private:
  // The walls' loads of this step from the `parts` threads' loads (Model::walls' force, moment, ...);
  // loads: the step forms them (StepKernels::wall_loads); moving: some wall's surface moves.
  void add_wall_loads(Model& model, int parts, bool loads, bool moving);
  const StepPolicy* policy_;
  bool part_only_ = false;
  std::vector<WallLoad> wall_totals_;      // per wall: the threads' loads merged
  // Splits the pair blocks among `parts` threads, balancing each thread's pairs plus the cross
  // pairs it computes again (kept while the pair list stays the same).
  void split(const ContactTable& c, const StepScratch& scratch, std::size_t balls, int parts);
  // The split, made again where the list, the ball count or the number of parts changed.
  void split_if_stale(const ContactTable& c, const StepScratch& scratch, std::size_t balls, int parts);
  void cross_lists(const ContactTable& c, std::size_t balls, int parts);

  std::vector<StepSums> thread_sums_;      // per thread but the first (which adds to the step's sums)
  std::vector<WallLoad> wall_loads_;       // per thread, per wall
  std::vector<std::size_t> first_block_;   // per thread, then the block count
  std::vector<std::vector<std::uint32_t>> cross_;   // per thread: its cross pairs, in list order
  std::vector<std::vector<double>> cross_history_;  // per thread: their history before the step (CrossLoop)
  std::uint64_t split_version_ = 0;
  std::vector<double> moved_;
  double moved2_ = 0;
  int split_parts_ = 0;

  // Whether this step shares the work (cycle/timed_choice.hpp: a trial step or the trial's verdict).
  bool share_now(std::size_t balls, int parts);
  TimedChoice trial_;
};

}  // namespace trubal
