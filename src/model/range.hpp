// RANGE phrases (doc/language.md "Ranges"): which balls a command acts on.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "model/model.hpp"

namespace trubal {

struct RangeElement {
  enum class Kind { Id, X, Y, Z, Type, Group, Sphere, Cylinder, Octagon };
  Kind kind = Kind::Id;
  bool negate = false;
  std::array<double, 4> v{};     // bounds, centre, radius... as the kind needs
  std::string group;
};

// All elements must hold. An empty range holds for every ball.
using Range = std::vector<RangeElement>;

// A ball, existing or about to be created (id 0: no id yet, so `id` and `group` do not hold).
struct BallView {
  std::int64_t id = 0;
  int type = 1;
  double x = 0, y = 0, z = 0;
};

bool holds(const Model& model, const Range& range, const BallView& ball);
BallView view_of(const Model& model, std::size_t index);
// Indices of the balls where the range holds, ascending.
std::vector<std::size_t> select(const Model& model, const Range& range);

// A range as numbers, for another process (each element: its kind, negate, its four values, its
// group's length and characters), and back. range_of_numbers throws std::runtime_error for numbers
// range_numbers did not make.
std::vector<double> range_numbers(const Range& range);
Range range_of_numbers(const std::vector<double>& numbers);

}  // namespace trubal
