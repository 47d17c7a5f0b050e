#include "model/range.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace trubal {

static bool element_holds(const Model& model, const RangeElement& e, const BallView& b) {
  using K = RangeElement::Kind;
  const auto& v = e.v;
  switch (e.kind) {
    case K::Id: return b.id >= v[0] && b.id <= v[1];
    case K::X: return b.x >= v[0] && b.x <= v[1];
    case K::Y: return b.y >= v[0] && b.y <= v[1];
    case K::Z: return b.z >= v[0] && b.z <= v[1];
    case K::Type: return b.type == static_cast<int>(v[0]);
    case K::Group: {
      auto it = model.groups.find(e.group);
      return it != model.groups.end() && std::binary_search(it->second.begin(), it->second.end(), b.id);
    }
    case K::Sphere: {
      double dx = b.x - v[0], dy = b.y - v[1], dz = b.z - v[2];
      return dx * dx + dy * dy + dz * dz <= v[3] * v[3];
    }
    case K::Cylinder: {
      double dx = b.x - v[0], dy = b.y - v[1];
      return dx * dx + dy * dy <= v[2] * v[2];
    }
    case K::Octagon: {
      double dx = std::abs(b.x - v[0]), dy = std::abs(b.y - v[1]);
      // A small relative slack so lattice points exactly on a side are inside despite rounding.
      double slack = 1e-9 * std::max(v[2], v[3]);
      return dx <= v[2] + slack && dy <= v[2] + slack && dx + dy <= v[3] * std::sqrt(2.0) + slack;
    }
  }
  return false;
}

bool holds(const Model& model, const Range& range, const BallView& ball) {
  for (const auto& e : range)
    if (element_holds(model, e, ball) == e.negate) return false;
  return true;
}

BallView view_of(const Model& model, std::size_t k) {
  const Balls& b = model.balls;
  return {b.id[k], b.type[k], b.x[k], b.y[k], b.z[k]};
}

std::vector<std::size_t> select(const Model& model, const Range& range) {
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < model.balls.size(); ++k)
    if (holds(model, range, view_of(model, k))) out.push_back(k);
  return out;
}

std::vector<double> range_numbers(const Range& range) {
  std::vector<double> out;
  for (const RangeElement& e : range) {
    out.push_back(static_cast<double>(e.kind));
    out.push_back(e.negate ? 1.0 : 0.0);
    out.insert(out.end(), e.v.begin(), e.v.end());
    out.push_back(static_cast<double>(e.group.size()));
    for (char ch : e.group) out.push_back(static_cast<unsigned char>(ch));
  }
  return out;
}

Range range_of_numbers(const std::vector<double>& numbers) {
  Range range;
  std::size_t at = 0;
  auto next = [&] {
    if (at >= numbers.size()) throw std::runtime_error("internal error: a range's numbers cut short");
    return numbers[at++];
  };
  while (at < numbers.size()) {
    RangeElement e;
    const double kind = next();
    if (!(kind >= 0 && kind <= static_cast<double>(RangeElement::Kind::Octagon)))
      throw std::runtime_error("internal error: a range's numbers name no kind");
    e.kind = static_cast<RangeElement::Kind>(static_cast<int>(kind));
    e.negate = next() != 0;
    for (double& v : e.v) v = next();
    const auto length = static_cast<std::size_t>(next());
    for (std::size_t k = 0; k < length; ++k) e.group.push_back(static_cast<char>(static_cast<unsigned char>(next())));
    range.push_back(std::move(e));
  }
  return range;
}

}  // namespace trubal
