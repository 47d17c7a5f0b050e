// What a backend's pair search returns: the pairs that may touch, for the cycle to install.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
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

// A pair as the ranks of a distributed run send it: 11 bytes, i, j, then j's image.
inline constexpr std::size_t kPairRecord = 2 * sizeof(std::uint32_t) + 3;
inline void write_pair_record(std::uint8_t* r, std::uint32_t i, std::uint32_t j, std::int8_t ix, std::int8_t iy,
                              std::int8_t iz) {
  std::memcpy(r, &i, 4);
  std::memcpy(r + 4, &j, 4);
  std::memcpy(r + 8, &ix, 1);
  std::memcpy(r + 9, &iy, 1);
  std::memcpy(r + 10, &iz, 1);
}
// The pairs of `records` (whole records, in order) into `out`, replacing its list.
inline void read_pair_records(const std::vector<std::uint8_t>& records, PairCandidates& out) {
  const std::size_t total = records.size() / kPairRecord;
  out.clear();
  out.i.resize(total); out.j.resize(total);
  out.image_x.resize(total); out.image_y.resize(total); out.image_z.resize(total);
  for (std::size_t p = 0; p < total; ++p) {
    const std::uint8_t* r = records.data() + p * kPairRecord;
    std::memcpy(&out.i[p], r, 4);
    std::memcpy(&out.j[p], r + 4, 4);
    std::memcpy(&out.image_x[p], r + 8, 1);
    std::memcpy(&out.image_y[p], r + 9, 1);
    std::memcpy(&out.image_z[p], r + 10, 1);
  }
}

}  // namespace trubal
