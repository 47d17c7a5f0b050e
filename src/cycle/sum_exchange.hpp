// The exact sums of a step as doubles, for the exchange between ranks: each exact sum as its
// normalised limbs (each below 2^32 in magnitude, so exact as a double) and its flags, then the
// min/max (a ball index below 2^53 is exact).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "cycle/kernels.hpp"

namespace trubal {

inline void pack(ExactSum& e, std::vector<double>& out) {
  for (std::int64_t l : e.normalised_limbs()) out.push_back(static_cast<double>(l));
  out.push_back(e.special());
}
inline void pack(StepSums& s, std::vector<double>& out) {
  s.each_sum([&](ExactSum& e) { pack(e, out); });
  for (double v : {s.critical_dt, s.fastest_speed2, static_cast<double>(s.fastest_ball)}) out.push_back(v);
}
inline void pack(WallLoad& w, std::vector<double>& out) {
  w.each_sum([&](ExactSum& e) { pack(e, out); });
  out.push_back(static_cast<double>(w.contacts));
}
inline void unpack(ExactSum& e, const double*& in) {
  std::array<std::int64_t, ExactSum::kLimbs> limbs;
  for (auto& l : limbs) l = static_cast<std::int64_t>(*in++);
  e.load(limbs.data(), static_cast<std::uint8_t>(*in++));
}
inline StepSums unpack_sums(const double*& in) {
  StepSums s;
  s.each_sum([&](ExactSum& e) { unpack(e, in); });
  s.critical_dt = *in++; s.fastest_speed2 = *in++;
  s.fastest_ball = static_cast<std::size_t>(*in++);
  return s;
}
inline WallLoad unpack_load(const double*& in) {
  WallLoad w;
  w.each_sum([&](ExactSum& e) { unpack(e, in); });
  w.contacts = static_cast<std::int64_t>(*in++);
  return w;
}

}  // namespace trubal
