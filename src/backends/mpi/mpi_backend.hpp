// BACKEND mpi: the step shared among the ranks of `mpirun -np P trubal` (cycle/parallel_step.hpp
// says how); the pairs are found as the serial backend finds them, the search shared among the
// ranks by ranges of ball indices.
#pragma once

#include <atomic>
#include <memory>

#include "backends/backend.hpp"

namespace trubal {

std::unique_ptr<Backend> make_mpi_backend();

// Tests (TRUBAL_TEST_FAIL_AT "R search"): rank R's next share of the search fails as if out of
// memory; -1: none.
inline std::atomic<int> fail_search_for_test{-1};

}  // namespace trubal
