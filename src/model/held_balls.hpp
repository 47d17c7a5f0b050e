// BALL lines of a batch deck under mpirun, kept where they were read until a command reads the
// balls: every rank reads every line, and each ball is kept by one rank (the one its centre's hash
// picks), so that no rank holds the whole model while a million BALL lines are read. Each rank
// checks the part of BALL's rules it holds the facts for: the ranks whose centres it keeps (a
// centre taken twice), the ids whose hash picks it (an id taken twice); every rank knows every
// line's id (the next free one is one more than the largest) and the count. Session places them in
// the model, in the lines' order, when a command reads the balls (Session::place_held).
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "model/centre_index.hpp"

namespace trubal {

// A set of ball ids (positive), open addressing: 8 to 16 bytes an id.
class IdSet {
 public:
  bool contains(std::int64_t id) const {
    if (slots_.empty()) return false;
    for (std::size_t s = slot(id); slots_[s] != 0; s = (s + 1) & (slots_.size() - 1))
      if (slots_[s] == id) return true;
    return false;
  }
  // (Not there yet: contains first.)
  void insert(std::int64_t id) {
    if (2 * (count_ + 1) > slots_.size()) grow();
    put(id);
    ++count_;
  }
  void clear() {
    std::vector<std::int64_t>().swap(slots_);
    count_ = 0;
  }
  // The ids of `gone` (ascending) taken out: the others put in afresh.
  void erase_all(const std::vector<std::int64_t>& gone) {
    std::vector<std::int64_t> old;
    old.swap(slots_);
    count_ = 0;
    for (std::int64_t id : old)
      if (id != 0 && !std::binary_search(gone.begin(), gone.end(), id)) insert(id);
  }
  std::size_t bytes() const { return slots_.capacity() * sizeof(std::int64_t); }
  static std::uint64_t mix(std::int64_t id) {
    std::uint64_t h = static_cast<std::uint64_t>(id) * 0x9E3779B97F4A7C15ull;
    return h ^ (h >> 31);
  }

 private:
  std::size_t slot(std::int64_t id) const { return mix(id) & (slots_.size() - 1); }
  void put(std::int64_t id) {
    std::size_t s = slot(id);
    while (slots_[s] != 0) s = (s + 1) & (slots_.size() - 1);
    slots_[s] = id;
  }
  void grow() {
    std::vector<std::int64_t> old;
    old.swap(slots_);
    slots_.assign(old.empty() ? 1024 : 2 * old.size(), 0);
    for (std::int64_t id : old)
      if (id != 0) put(id);
  }
  std::vector<std::int64_t> slots_;   // 0 where none; a power of two long
  std::size_t count_ = 0;
};

struct HeldBalls {
  // This rank's balls, in the order of their lines.
  std::vector<std::uint64_t> line;   // its place among the held balls of every rank (0, 1, ...)
  std::vector<std::int64_t> id;
  std::vector<int> type;
  std::vector<double> x, y, z, rad;
  CentreIndex centres;   // of this rank's balls
  IdSet ids;             // the ids held on any rank that this rank checks (id_checker)
  // Every rank's alike: the balls held on all ranks, and the largest id among them (0: none).
  std::uint64_t total = 0;
  std::int64_t max_id = 0;

  std::size_t size() const { return id.size(); }
  // The rank that keeps a ball at this centre (of `ranks`), and the one that checks an id.
  static int keeper(double cx, double cy, double cz, int ranks) {
    const std::uint64_t h = CentreIndex::hash(cx, cy, cz) * 0xD6E8FEB86659FD93ull;   // (not the table's low bits)
    return static_cast<int>((h >> 32) % static_cast<std::uint64_t>(ranks));
  }
  static int id_checker(std::int64_t ball_id, int ranks) {
    return static_cast<int>((IdSet::mix(ball_id) >> 32) % static_cast<std::uint64_t>(ranks));
  }
  void add(std::uint64_t at, std::int64_t ball_id, int ball_type, double cx, double cy, double cz, double r) {
    line.push_back(at);
    id.push_back(ball_id);
    type.push_back(ball_type);
    x.push_back(cx);
    y.push_back(cy);
    z.push_back(cz);
    rad.push_back(r);
    centres.insert(*this, id.size() - 1);
  }
  std::size_t bytes() const {
    return line.capacity() * 8 + id.capacity() * 8 + type.capacity() * sizeof(int) +
           (x.capacity() + y.capacity() + z.capacity() + rad.capacity()) * sizeof(double) + centres.bytes() +
           ids.bytes();
  }
  // Empty, the memory given back.
  void clear() { *this = HeldBalls{}; }
};

}  // namespace trubal
