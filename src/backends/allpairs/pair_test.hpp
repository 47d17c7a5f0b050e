// The all-pairs overlap test: one row of the pair-slot triangle at a time.
#pragma once

#include <cstddef>
#include <cstdint>

#include "model/periodic_cell.hpp"

namespace trubal {

// For partners k = 0 .. count-1 (ball i+1+k), slot[k] = 1 when the balls overlap, else 0. The
// test is the contact law's own, d^2 < (R_i + R_j)^2 on the same differences (x_j - x_i), so a pair
// is found exactly when the contact kernel would give it a force. Branch-free over the row, so
// that the compiler vectorises it. Returns how many slots are set.
std::size_t test_row(double xi, double yi, double zi, double ri, const double* __restrict xj,
                     const double* __restrict yj, const double* __restrict zj, const double* __restrict rj,
                     std::size_t count, std::uint8_t* __restrict slot, double reach = 0.0);

// (reach: how far apart beyond contact a pair still counts, the capillary bridges' rupture gap; 0 without.)
// The same in a periodic cell: slot[k] = 1 when j overlaps i at j's nearest image, with
// nearest_image_within's arithmetic step for step (the image from nearest_image, its offset from
// image_offset, the differences from image_delta, the same sum of squares), so that a slot is set
// exactly where nearest_image_within(f, ...) says true. Branch-free: the image numbers are chosen
// by comparisons, not branches. `tilted`: the cell has some tilt (f.xy, f.xz or f.yz not 0); without
// one the tilt terms are (signed) zeros, which change no comparison and no square, so each axis is
// wrapped on its own (no divisions; the same sums of squares bit for bit). Returns how many slots
// are set.
std::size_t test_row_periodic(const CellFrame& f, bool tilted, double xi, double yi, double zi, double ri,
                              const double* __restrict xj, const double* __restrict yj, const double* __restrict zj,
                              const double* __restrict rj, std::size_t count, std::uint8_t* __restrict slot,
                              double reach = 0.0);

}  // namespace trubal
