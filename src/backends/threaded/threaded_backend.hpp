// The boxes of the serial backend, sorted into cells in one pass and searched by the pipeline's
// threads, each for its own range of balls (backends/threaded/cell_pairs.hpp); in a periodic cell
// the shared periodic search on every thread. The list is the serial one, pair for pair.
#pragma once

#include <memory>

#include "backends/backend.hpp"

namespace trubal {

std::unique_ptr<Backend> make_threaded_backend();

}  // namespace trubal
