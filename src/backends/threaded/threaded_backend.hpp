// TRUBAL's boxes and Verlet pair list, as the serial backend keeps them but built in parallel, with
// the contact and motion kernels spread over a pool of persistent threads. Same pairs, same blocks,
// same order of sums: bitwise the serial answer for any thread count.
#pragma once

#include <memory>

#include "backends/backend.hpp"

namespace trubal {

// threads <= 0: one per hardware thread.
std::unique_ptr<Backend> make_threaded_backend(int threads);

}  // namespace trubal
