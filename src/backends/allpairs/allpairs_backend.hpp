// TPM 2.0's arrangement (the CM-5 port of TRUBAL): every pair of balls has a fixed slot, all
// N(N-1)/2 of them, and every pair is tested every cycle; no boxes, no lists kept between steps.
// It cannot miss a contact, which makes it the oracle the other backends are checked against.
// The touching pairs go to the same contact kernel, in (i, j) order, as the serial backend's.
#pragma once

#include <cstdint>
#include <memory>

#include "backends/backend.hpp"

namespace trubal {

// max_memory 0: default_allpairs_memory().
std::unique_ptr<Backend> make_allpairs_backend(std::uint64_t max_memory);

// The default limit on the pair slots' memory: 4 GiB or half the physical memory, the smaller.
std::uint64_t default_allpairs_memory();

}  // namespace trubal
