// BACKEND mpi: the step shared among the ranks of `mpirun -np P trubal` (cycle/parallel_step.hpp
// says how); the pairs are found as the serial backend finds them, the search shared among the
// ranks by ranges of ball indices.
#pragma once

#include <memory>

#include "backends/backend.hpp"

namespace trubal {

std::unique_ptr<Backend> make_mpi_backend();

}  // namespace trubal
