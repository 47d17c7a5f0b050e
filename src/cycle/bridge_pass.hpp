// The capillary bridges' part of a step (physics/bridge.hpp; doc/physics.md "Capillary bridges"),
// for scenes with bridges only (Features::bridges): a pass of its own beside the contact loops, so
// that the contact kernel tables stay as they are and a dry scene does none of this work.
//
// 1. bridge_pairs, bridge_walls (by the pairs' owners, after the contact loops): each pair's and
//    ball-wall contact's bridge from its gap at t: it forms where the pair touches, breaks beyond the
//    rupture gap, and pulls with F(s) while it holds (the history `bridge`, 0 or 1). The force goes
//    to the pair's scratch, to the servo's moments (the stress counts it) and to the wall's load.
// 2. add_bridges (per ball, before the law of motion): each ball's bridge forces summed in the one
//    order of its contact sums (its pairs with lower partners ascending, then with higher ones, then
//    its walls), so that every backend, thread and rank count gives the same bits, and joined to
//    its contact force.
// 3. bridge_work (per ball, after the law of motion): the work the bridges did on the ball,
//    F(t) . (v(t - dt/2) + v(t + dt/2)) / 2 dt_mean, half of it after t, as the law of motion
//    charges every force: the energy balance books it as `capillary` work.
#pragma once

#include <cstddef>

#include "cycle/kernels.hpp"
#include "cycle/step_scratch.hpp"
#include "model/model.hpp"

namespace trubal {

// Sizes the pass's scratch and indexes each ball's pairs as partner j (for a new list).
void prepare_bridges(const Model& model, StepScratch& scratch);
// Pairs [begin, end) and wall contacts [wall_begin, wall_end) (whole runs of balls): step 1.
// `loads`: one per wall; `sums`: the servo's moments, where the pair's ball i is not a ghost.
void bridge_pairs(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                  StepSums& sums);
void bridge_walls(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                  WallLoad* loads);
// Balls [begin, end): step 2.
void add_bridges(const Model& model, StepScratch& scratch, std::size_t begin, std::size_t end);
// Balls [begin, end), moved: step 3 (a ghost's work is its owner's).
void bridge_work(const Model& model, const StepScratch& scratch, const StepKernels& k, std::size_t begin,
                 std::size_t end, StepSums& sums);

}  // namespace trubal
