// BACKEND mpi: the step shared among the ranks of `mpirun -np P trubal` (cycle/parallel_step.hpp
// says how); the pairs are found as the serial backend finds them, the search shared among the
// ranks by ranges of ball indices.
#pragma once

#include <memory>

#include "backends/backend.hpp"

namespace trubal {

// fail_search: where given, rank *fail_search's next share of a search fails as if out of memory
// (a test's fault, TRUBAL_TEST_FAIL_AT "R search"; BackendOptions::fail_search).
std::unique_ptr<Backend> make_mpi_backend(int* fail_search = nullptr);

}  // namespace trubal
