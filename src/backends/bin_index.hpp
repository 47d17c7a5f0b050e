// The balls of a pair search hung on bins, by each ball's bin number (x fastest along a row of
// bins). Where there are few enough bins (about two a ball or fewer) every bin has its slot in a
// table (a counting sort, one pass); where there are more, as when the balls crowd into a corner of
// a large cell or box, only the bins that hold a ball are kept, found by a hash of their number. So
// the bins are as fine as the reach wherever the balls are, and their memory is bounded by the
// balls. Either way a bin's balls are in ascending index, and the bins of a row are in order, so the
// three bins along x around a ball are one run of balls.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace trubal {

class BinIndex {
 public:
  // Hangs ball k on bin key[k], every key below `bins`.
  void build(const std::vector<std::uint64_t>& key, std::uint64_t bins);
  // The balls of bins [first, last] (the bins of one row, at most a few): order()[begin, end).
  std::pair<std::uint32_t, std::uint32_t> run(std::uint64_t first, std::uint64_t last) const {
    if (!sparse_) return {start_[first], start_[last + 1]};
    std::uint32_t begin = 0, end = 0;
    bool any = false;
    for (std::uint64_t q = first; q <= last; ++q) {
      const std::uint32_t slot = find(q);
      if (slot == kNone) continue;
      if (!any) begin = start_[slot];
      end = start_[slot + 1];
      any = true;
    }
    return {begin, end};
  }
  const std::vector<std::uint32_t>& order() const { return order_; }
  // Whether only the occupied bins are kept.
  bool sparse() const { return sparse_; }

 private:
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  std::uint32_t find(std::uint64_t q) const {
    for (std::size_t h = hash(q);; h = (h + 1) & mask_) {
      const std::uint32_t slot = table_[h];
      if (slot == kNone || keys_[slot] == q) return slot;
    }
  }
  std::size_t hash(std::uint64_t q) const {
    return static_cast<std::size_t>((q * 0x9E3779B97F4A7C15ull) >> shift_) & mask_;
  }

  bool sparse_ = false;
  std::vector<std::uint32_t> start_;   // dense: bin q's balls from start_[q]; sparse: the slot's
  std::vector<std::uint32_t> order_;   // the balls by bin
  std::vector<std::uint64_t> keys_;    // sparse: the occupied bins, ascending (slot s holds keys_[s])
  std::vector<std::uint32_t> table_;   // sparse: open addressing, bin -> slot
  std::size_t mask_ = 0;
  int shift_ = 0;
};

}  // namespace trubal
