// The periodic pair search the serial and threaded backends share (model/periodic_cell.hpp has the
// geometry): wrapped positions, j's nearest image, the same test for every pair.
#pragma once

#include "backends/pair_candidates.hpp"
#include "model/model.hpp"
#include "support/thread_pool.hpp"

namespace trubal {

// Every pair i < j (wrapped positions) with j's nearest image closer than R_i + R_j + skin, sorted by
// (i, j), with that image. skin 0 gives exactly the pairs the contact kernel gives a force.
// With a pool, its threads search ranges of i and their lists are joined: the same list.
// [i_begin, i_end): only the pairs whose lower ball i is in this range (the part of the list a rank
// of BACKEND mpi searches; i_end beyond the balls: to the last).
void find_periodic_pairs(const Model& model, double skin, PairCandidates& out, ThreadPool* pool = nullptr,
                         std::size_t i_begin = 0, std::size_t i_end = ~std::size_t{0});

}  // namespace trubal
