// Small text helpers for PRINT info lines.
#pragma once

#include <array>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace trubal {

inline std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// The info lines of a backend that hangs balls on boxes.
inline std::vector<std::pair<std::string, std::string>> box_info(const std::array<int, 3>& boxes, double box_size) {
  return {{"contact boxes", std::to_string(boxes[0]) + " x " + std::to_string(boxes[1]) + " x " + std::to_string(boxes[2])},
          {"box size", format_number(box_size)}};
}

}  // namespace trubal
