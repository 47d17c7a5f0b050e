#include "backends/bin_index.hpp"

#include <algorithm>
#include <bit>
#include <numeric>

namespace trubal {

void BinIndex::build(const std::vector<std::uint64_t>& key, std::uint64_t bins) {
  const std::size_t n = key.size();
  order_.resize(n);
  sparse_ = static_cast<double>(bins) > 2.0 * static_cast<double>(n) + 27;
  if (!sparse_) {
    keys_.clear();
    table_.clear();
    start_.assign(static_cast<std::size_t>(bins) + 1, 0);
    for (std::size_t k = 0; k < n; ++k) ++start_[key[k] + 1];
    for (std::size_t q = 0; q < bins; ++q) start_[q + 1] += start_[q];
    std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
    for (std::size_t k = 0; k < n; ++k) order_[next[key[k]]++] = static_cast<std::uint32_t>(k);
    return;
  }
  // The balls by bin, each bin's in ascending index (a stable sort of the indices by bin).
  std::iota(order_.begin(), order_.end(), std::uint32_t{0});
  std::stable_sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
  keys_.clear();
  start_.clear();
  for (std::size_t e = 0; e < n; ++e)
    if (e == 0 || key[order_[e]] != keys_.back()) {
      keys_.push_back(key[order_[e]]);
      start_.push_back(static_cast<std::uint32_t>(e));
    }
  start_.push_back(static_cast<std::uint32_t>(n));
  // A table at most half full: a probe ends at an empty entry after a step or two.
  const std::size_t size = std::bit_ceil(std::max<std::size_t>(2 * keys_.size(), 16));
  mask_ = size - 1;
  shift_ = 64 - std::countr_zero(size);
  table_.assign(size, kNone);
  for (std::uint32_t s = 0; s < keys_.size(); ++s) {
    std::size_t h = hash(keys_[s]);
    while (table_[h] != kNone) h = (h + 1) & mask_;
    table_[h] = s;
  }
}

}  // namespace trubal
