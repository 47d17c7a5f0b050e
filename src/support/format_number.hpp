// Small text helpers for PRINT info lines.
#pragma once

#include <array>
#include <cstddef>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace trubal {

// "1 ball", "2 balls": a count with its noun (a plural in s).
inline std::string count_of(std::size_t n, const char* noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

inline std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// The info lines of a backend that hangs balls on boxes; periodic_bins (nonzero): the last search
// was the periodic cell's (backends/periodic_pairs.hpp), whose bins are reported instead.
inline std::vector<std::pair<std::string, std::string>> box_info(const std::array<int, 3>& boxes, double box_size,
                                                                 const std::array<int, 3>& periodic_bins = {}) {
  if (periodic_bins[0] > 0)
    return {{"contact boxes", std::to_string(periodic_bins[0]) + " x " + std::to_string(periodic_bins[1]) + " x " +
                                  std::to_string(periodic_bins[2]) + " (the periodic search's, across the cell)"}};
  return {{"contact boxes", std::to_string(boxes[0]) + " x " + std::to_string(boxes[1]) + " x " + std::to_string(boxes[2])},
          {"box size", format_number(box_size)}};
}

}  // namespace trubal
