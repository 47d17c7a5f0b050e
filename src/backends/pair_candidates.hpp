// What a backend's pair search returns: the pairs that may touch, for the cycle to install.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace trubal {

// Candidate pairs i < j (ball indices), sorted by (i, j), with the periodic image of j.
struct PairCandidates {
  std::vector<std::uint32_t> i, j;
  std::vector<std::int8_t> image_x, image_y, image_z;
  // The bins per axis of the periodic search that made the list (backends/periodic_pairs.hpp);
  // zero after a search by boxes (PRINT info reports the one that ran).
  std::array<int, 3> periodic_bins{};
  void clear() { i.clear(); j.clear(); image_x.clear(); image_y.clear(); image_z.clear(); }
  void push(std::uint32_t a, std::uint32_t b) {
    i.push_back(a); j.push_back(b); image_x.push_back(0); image_y.push_back(0); image_z.push_back(0);
  }
  // Appends another list (the threads' lists of consecutive ranges of i, joined in order).
  void append(const PairCandidates& o) {
    i.insert(i.end(), o.i.begin(), o.i.end());
    j.insert(j.end(), o.j.begin(), o.j.end());
    image_x.insert(image_x.end(), o.image_x.begin(), o.image_x.end());
    image_y.insert(image_y.end(), o.image_y.begin(), o.image_y.end());
    image_z.insert(image_z.end(), o.image_z.begin(), o.image_z.end());
  }
};

}  // namespace trubal
