#include "backends/allpairs/allpairs_backend.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "backends/allpairs/pair_test.hpp"
#include "model/periodic_cell.hpp"

namespace trubal {
namespace {

// Slots before row i of the triangle (row i holds partners i+1 .. n-1).
inline std::uint64_t row_start(std::uint64_t i, std::uint64_t n) { return i * (2 * n - i - 1) / 2; }

std::string bytes_text(std::uint64_t bytes) {
  const char* unit[] = {"bytes", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024 && u < 4) { v /= 1024; ++u; }
  return u == 0 ? fmt::format("{} bytes", bytes) : fmt::format("{:.3g} {} ({} bytes)", v, unit[u], bytes);
}

// Calls visit(q) for each set slot q of a row, in ascending q, skipping eight empty slots at a time
// (the periodic rows; the free-space loop below is the same, written out).
template <class Visit>
inline void for_each_set(const std::uint8_t* slot, std::size_t count, Visit&& visit) {
  std::size_t k = 0;
  for (; k + 8 <= count; k += 8) {
    std::uint64_t word;
    std::memcpy(&word, slot + k, 8);
    if (word == 0) continue;
    for (std::size_t q = k; q < k + 8; ++q)
      if (slot[q]) visit(q);
  }
  for (; k < count; ++k)
    if (slot[k]) visit(k);
}

// Fewer pair slots than this are tested on one thread: waking workers costs more.
constexpr std::uint64_t kParallelSlots = 1 << 16;

class AllPairsBackend final : public Backend {
 public:
  explicit AllPairsBackend(std::uint64_t max_memory) : max_memory_(max_memory > 0 ? max_memory : default_allpairs_memory()) {}

  std::string name() const override { return "allpairs"; }
  bool keeps_list() const override { return false; }
  std::uint64_t pair_tests() const override { return tests_; }

  // reach: 0 (no list is kept), or the capillary bridges' rupture gap (Pipeline::list_reach).
  void find_pairs(const Model& model, double reach, ThreadPool& pool, PairCandidates& out) override {
    reserve(model.balls.size(), pool.size());
    if (model.space.periodic) find_touching_periodic(model, pool, out, reach);
    else find_touching(model, pool, out, reach);
  }

  std::vector<std::pair<std::string, std::string>> info() const override {
    return {{"pair slots", fmt::format("{} ({})", slot_count_, bytes_text(slot_count_))},
            {"memory limit", bytes_text(max_memory_) + " (BACKEND allpairs maxmem <bytes>)"},
            {"pair tests", fmt::format("{}", tests_)}};
  }

 private:
  // States what the slots need before taking it, and refuses above the limit.
  void reserve(std::size_t n, int parts) {
    const std::uint64_t slots = n < 2 ? 0 : static_cast<std::uint64_t>(n) * (n - 1) / 2;
    if (n == ball_count_ && row_split_.size() == static_cast<std::size_t>(parts) + 1) return;
    const std::uint64_t need = slots * sizeof(std::uint8_t);
    if (need > max_memory_)
      throw std::runtime_error(fmt::format(
          "backend allpairs: {} balls have {} pair slots, which need {}, above the limit of {}; raise it with "
          "BACKEND allpairs maxmem <bytes>, or use BACKEND serial or threaded",
          n, slots, bytes_text(need), bytes_text(max_memory_)));
    try {
      slots_.assign(slots, 0);
      slots_.shrink_to_fit();
    } catch (const std::bad_alloc&) {
      slots_.clear();
      slots_.shrink_to_fit();
      slot_count_ = 0;
      row_split_.clear();
      throw std::runtime_error(fmt::format("backend allpairs: could not allocate {} for {} pair slots of {} balls",
                                           bytes_text(need), slots, n));
    }
    slot_count_ = slots;
    ball_count_ = n;
    // Rows to threads by equal numbers of slots: the triangle's rows shorten as i grows.
    row_split_.assign(parts + 1, n);
    row_split_[0] = 0;
    std::size_t i = 0;
    for (int t = 1; t < parts; ++t) {
      const std::uint64_t target = slots * static_cast<std::uint64_t>(t) / static_cast<std::uint64_t>(parts);
      while (i < n && row_start(i, n) < target) ++i;
      row_split_[t] = i;
    }
    found_.resize(parts);
  }

  // Tests every pair; the touching ones, in (i, j) order, into pairs_.
  void find_touching(const Model& model, ThreadPool& pool, PairCandidates& pairs, double reach) {
    const Balls& b = model.balls;
    const std::size_t n = b.size();
    pool.run([&](int t) {
      PairCandidates& out = found_[t];
      out.clear();
      for (std::size_t i = row_split_[t]; i < row_split_[t + 1]; ++i) {
        const std::size_t count = n - 1 - i;
        std::uint8_t* slot = slots_.data() + row_start(i, n);
        if (test_row(b.x[i], b.y[i], b.z[i], b.rad[i], b.x.data() + i + 1, b.y.data() + i + 1, b.z.data() + i + 1,
                     b.rad.data() + i + 1, count, slot, reach) == 0)
          continue;
        std::size_t k = 0;
        for (; k + 8 <= count; k += 8) {   // skip eight empty slots at a time
          std::uint64_t word;
          std::memcpy(&word, slot + k, 8);
          if (word == 0) continue;
          for (std::size_t q = k; q < k + 8; ++q)
            if (slot[q]) out.push(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i + 1 + q));
        }
        for (; k < count; ++k)
          if (slot[k]) out.push(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i + 1 + k));
      }
    }, slot_count_ >= kParallelSlots);
    pairs.clear();
    for (const PairCandidates& part : found_) pairs.append(part);
    tests_ += slot_count_;
  }

  // Periodic space: every pair against j's nearest image (with every edge at least twice the largest
  // diameter no other image can touch), with find_periodic_pairs' arithmetic at skin 0. A row is
  // tested branch-free as in free space (test_row_periodic: nearest_image_within's arithmetic, which
  // the compiler vectorises); each pair it finds takes its image from nearest_image_within itself.
  void find_touching_periodic(const Model& model, ThreadPool& pool, PairCandidates& pairs, double reach) {
    const Balls& b = model.balls;
    const std::size_t n = b.size();
    const CellFrame f = cell_frame(model.space);
    const bool tilted = f.xy != 0 || f.xz != 0 || f.yz != 0;
    pool.run([&](int t) {
      PairCandidates& out = found_[t];
      out.clear();
      for (std::size_t i = row_split_[t]; i < row_split_[t + 1]; ++i) {
        const std::size_t count = n - 1 - i;
        std::uint8_t* slot = slots_.data() + row_start(i, n);
        if (test_row_periodic(f, tilted, b.x[i], b.y[i], b.z[i], b.rad[i], b.x.data() + i + 1, b.y.data() + i + 1,
                              b.z.data() + i + 1, b.rad.data() + i + 1, count, slot, reach) == 0)
          continue;
        for_each_set(slot, count, [&](std::size_t q) {
          const std::size_t j = i + 1 + q;
          std::int8_t ix, iy, iz;
          if (nearest_image_within(f, b, i, j, b.rad[i] + b.rad[j] + reach, ix, iy, iz)) {
            out.i.push_back(static_cast<std::uint32_t>(i));
            out.j.push_back(static_cast<std::uint32_t>(j));
            out.image_x.push_back(ix);
            out.image_y.push_back(iy);
            out.image_z.push_back(iz);
          }
        });
      }
    }, slot_count_ >= kParallelSlots);
    pairs.clear();
    for (const PairCandidates& part : found_) pairs.append(part);
    tests_ += slot_count_;
  }

  std::uint64_t max_memory_;
  std::vector<std::uint8_t> slots_;       // one per pair: touching at the last test
  std::uint64_t slot_count_ = 0;
  std::size_t ball_count_ = 0;            // the balls the slots and row_split_ are laid out for
  std::vector<std::size_t> row_split_;    // rows [row_split_[t], row_split_[t+1]) go to thread t
  std::vector<PairCandidates> found_;     // touching pairs per thread, in row order
  std::uint64_t tests_ = 0;
};

}  // namespace

std::uint64_t default_allpairs_memory() {
  const std::uint64_t four_gib = std::uint64_t{4} << 30;
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return four_gib;
  return std::min(four_gib, static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) / 2);
}

std::unique_ptr<Backend> make_allpairs_backend(std::uint64_t max_memory) {
  return std::make_unique<AllPairsBackend>(max_memory);
}

}  // namespace trubal
