// TRUBAL's own way of finding pairs: space cut into boxes, balls hung on linked lists per box
// (backends/serial/box_grid.hpp); in a periodic cell the shared periodic search. One thread.
#pragma once

#include <memory>

#include "backends/backend.hpp"
#include "backends/serial/box_grid.hpp"

namespace trubal {

std::unique_ptr<Backend> make_serial_backend();

// The serial backend's search: the periodic search in a periodic cell, else `grid` filled afresh
// with boxes of the largest reach. Only the pairs whose lower ball i is in [i_begin, i_end) (the
// part of the list a rank of BACKEND mpi searches; the defaults: every pair).
void find_serial_pairs(const Model& model, double skin, BoxGrid& grid, PairCandidates& out, std::size_t i_begin = 0,
                       std::size_t i_end = ~std::size_t{0});

}  // namespace trubal
