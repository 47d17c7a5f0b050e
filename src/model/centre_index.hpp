// The balls by their exact centres, for BALL's check that no two balls share one (two balls at one
// centre have no normal between them). An open-addressing table of ball indices, the centres read
// from the balls' own arrays: 4 to 8 bytes a ball, where a map of centres to ids took about 70
// (a million BALL lines' map was most of rank 0's memory beside the balls themselves).
#pragma once

#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "model/model.hpp"

namespace trubal {

class CentreIndex {
 public:
  static constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

  // The index of a ball of `b` whose centre is (x, y, z) exactly (-0 and 0 the same), or kNone.
  // (`b`: the balls, or anything that holds centres in arrays x, y and z: HeldBalls.)
  template <class Centres> std::size_t find(const Centres& b, double x, double y, double z) const {
    if (slots_.empty()) return kNone;
    for (std::size_t s = hash(x, y, z) & mask(); slots_[s] != kEmpty; s = (s + 1) & mask()) {
      const std::uint32_t k = slots_[s];
      if (b.x[k] == x && b.y[k] == y && b.z[k] == z) return k;
    }
    return kNone;
  }
  // Ball k of `b` added (its centre not there yet: find first).
  template <class Centres> void insert(const Centres& b, std::size_t k) {
    if (2 * (count_ + 1) > slots_.size()) grow(b);
    put(b, static_cast<std::uint32_t>(k));
    ++count_;
  }
  // Every ball of `b`, afresh.
  template <class Centres> void rebuild(const Centres& b) {
    clear();
    for (std::size_t k = 0; k < b.x.size(); ++k) insert(b, k);
  }
  // Empty, its memory given back.
  void clear() {
    std::vector<std::uint32_t>().swap(slots_);
    count_ = 0;
  }

  // (HeldBalls picks the rank that keeps a centre by it.)
  static std::uint64_t hash(double x, double y, double z) {
    std::uint64_t h = 1469598103934665603ull;
    for (double v : {x, y, z}) {
      if (v == 0) v = 0;   // (-0 hashes as 0)
      std::uint64_t bits;
      std::memcpy(&bits, &v, sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
      h ^= h >> 29;
    }
    return h;
  }
  // The bytes it holds.
  std::size_t bytes() const { return slots_.capacity() * sizeof(std::uint32_t); }

 private:
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
  std::size_t mask() const { return slots_.size() - 1; }
  template <class Centres> void put(const Centres& b, std::uint32_t k) {
    std::size_t s = hash(b.x[k], b.y[k], b.z[k]) & mask();
    while (slots_[s] != kEmpty) s = (s + 1) & mask();
    slots_[s] = k;
  }
  template <class Centres> void grow(const Centres& b) {
    std::vector<std::uint32_t> old;
    old.swap(slots_);
    slots_.assign(old.empty() ? 1024 : 2 * old.size(), kEmpty);
    for (std::uint32_t k : old)
      if (k != kEmpty) put(b, k);
  }

  std::vector<std::uint32_t> slots_;   // ball indices, kEmpty where none; a power of two long
  std::size_t count_ = 0;
};

}  // namespace trubal
