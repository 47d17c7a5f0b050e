// The all-pairs overlap test: one row of the pair-slot triangle at a time.
#pragma once

#include <cstddef>
#include <cstdint>

namespace trubal {

// For partners k = 0 .. count-1 (ball i+1+k), slot[k] = 1 when the balls overlap, else 0. The
// test is the contact law's own, d^2 < (R_i + R_j)^2 on the same differences (x_j - x_i), so a pair
// is found exactly when the contact kernel would give it a force. Branch-free over the row, so
// that the compiler vectorises it. Returns how many slots are set.
std::size_t test_row(double xi, double yi, double zi, double ri, const double* __restrict xj,
                     const double* __restrict yj, const double* __restrict zj, const double* __restrict rj,
                     std::size_t count, std::uint8_t* __restrict slot);

}  // namespace trubal
