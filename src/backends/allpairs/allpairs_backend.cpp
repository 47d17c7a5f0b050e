#include "backends/allpairs/allpairs_backend.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "backends/allpairs/pair_test.hpp"
#include "backends/pair_list.hpp"
#include "backends/periodic_pairs.hpp"
#include "model/periodic_cell.hpp"
#include "backends/threaded/parallel_step.hpp"
#include "support/thread_pool.hpp"
#include "physics/kernels.hpp"

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

// Fewer pair slots than this are tested on one thread: waking workers costs more.
constexpr std::uint64_t kParallelSlots = 1 << 16;

class AllPairsBackend final : public Backend {
 public:
  explicit AllPairsBackend(int threads)
      : pool_(threads > 0 ? threads : ThreadPool::hardware_threads()), max_memory_(default_allpairs_memory()) {}

  std::string name() const override { return "allpairs"; }
  int threads() const override { return pool_.size(); }
  void set_max_memory(std::uint64_t bytes) override {
    max_memory_ = bytes;
    row_split_.clear();   // check the slots against the new limit at the next step
  }

  void prepare(Model& model) override {
    const std::size_t n = model.balls.size();
    reserve(n);
    if (model.space.periodic) {
      check_periodic_cell(model);
      wrap_into_cell(model, nullptr, nullptr, nullptr);
      find_touching_periodic(model);
    } else {
      find_touching(model);
    }
    if (!valid_ || !same_list(model.contacts, n)) install_pairs(model.contacts, pairs_, n);
    valid_ = true;
    tested_ = true;
  }

  void step(Model& model, const StepKernels& kernels, StepSums& sums) override {
    const auto t0 = std::chrono::steady_clock::now();
    // The first step of a CYCLE follows the engine's prepare(): the balls have not moved since,
    // so every pair is not tested twice.
    if (!tested_) prepare(model);
    tested_ = false;
    model.timing.detect += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    step_.run(pool_, model, kernels, sums);
  }

  void invalidate() override { valid_ = false; tested_ = false; }

  std::vector<std::pair<std::string, std::string>> info() const override {
    return {{"pair slots", fmt::format("{} ({})", slot_count_, bytes_text(slot_count_))},
            {"memory limit", bytes_text(max_memory_) + " (BACKEND allpairs maxmem <bytes>)"},
            {"pair tests", fmt::format("{}", tests_)}};
  }

 private:
  // States what the slots need before taking it, and refuses above the limit.
  void reserve(std::size_t n) {
    const std::uint64_t slots = n < 2 ? 0 : static_cast<std::uint64_t>(n) * (n - 1) / 2;
    if (n == ball_count_ && row_split_.size() == static_cast<std::size_t>(pool_.size()) + 1) return;
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
    const int parts = pool_.size();
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
  void find_touching(const Model& model) {
    const Balls& b = model.balls;
    const std::size_t n = b.size();
    pool_.run([&](int t) {
      PairCandidates& out = found_[t];
      out.clear();
      for (std::size_t i = row_split_[t]; i < row_split_[t + 1]; ++i) {
        const std::size_t count = n - 1 - i;
        std::uint8_t* slot = slots_.data() + row_start(i, n);
        if (test_row(b.x[i], b.y[i], b.z[i], b.rad[i], b.x.data() + i + 1, b.y.data() + i + 1, b.z.data() + i + 1,
                     b.rad.data() + i + 1, count, slot) == 0)
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
    pairs_.clear();
    for (const PairCandidates& part : found_) {
      pairs_.i.insert(pairs_.i.end(), part.i.begin(), part.i.end());
      pairs_.j.insert(pairs_.j.end(), part.j.begin(), part.j.end());
    }
    pairs_.image_x.assign(pairs_.i.size(), 0);
    pairs_.image_y.assign(pairs_.i.size(), 0);
    pairs_.image_z.assign(pairs_.i.size(), 0);
    tests_ += slot_count_;
  }

  // Periodic space: every pair against j's nearest image (with every edge at least twice the largest
  // diameter no other image can touch), with find_periodic_pairs' arithmetic at skin 0.
  void find_touching_periodic(const Model& model) {
    const Balls& b = model.balls;
    const std::size_t n = b.size();
    const CellFrame f = cell_frame(model.space);
    pool_.run([&](int t) {
      PairCandidates& out = found_[t];
      out.clear();
      for (std::size_t i = row_split_[t]; i < row_split_[t + 1]; ++i)
        for (std::size_t j = i + 1; j < n; ++j) {
          std::int8_t ix, iy, iz;
          if (nearest_image_within(f, b, i, j, b.rad[i] + b.rad[j] + 0.0, ix, iy, iz)) {
            out.i.push_back(static_cast<std::uint32_t>(i));
            out.j.push_back(static_cast<std::uint32_t>(j));
            out.image_x.push_back(ix);
            out.image_y.push_back(iy);
            out.image_z.push_back(iz);
          }
        }
    }, slot_count_ >= kParallelSlots);
    pairs_.clear();
    for (const PairCandidates& part : found_) pairs_.append(part);
    tests_ += slot_count_;
  }

  // Whether the table already holds exactly these pairs (then nothing needs carrying over).
  bool same_list(ContactTable& table, std::size_t n) const {
    const std::size_t size = pairs_.i.size();
    bool consistent = table.run_begin.size() == n + 1;
    table.for_each_pair_array([&](auto& v) { consistent = consistent && v.size() == size; });
    if (!consistent) return false;
    for (std::size_t p = 0; p < size; ++p)
      if (table.image_x[p] != pairs_.image_x[p] || table.image_y[p] != pairs_.image_y[p] ||
          table.image_z[p] != pairs_.image_z[p])
        return false;
    return std::equal(pairs_.i.begin(), pairs_.i.end(), table.i.begin()) &&
           std::equal(pairs_.j.begin(), pairs_.j.end(), table.j.begin());
  }

  ThreadPool pool_;
  ParallelStep step_;
  std::uint64_t max_memory_;
  std::vector<std::uint8_t> slots_;       // one per pair: touching at the last test
  std::uint64_t slot_count_ = 0;
  std::size_t ball_count_ = 0;            // the balls the slots and row_split_ are laid out for
  std::vector<std::size_t> row_split_;    // rows [row_split_[t], row_split_[t+1]) go to thread t
  std::vector<PairCandidates> found_;     // touching pairs per thread, in row order
  PairCandidates pairs_;
  std::uint64_t tests_ = 0;
  bool valid_ = false;
  bool tested_ = false;   // the pairs were tested at the current positions
};

}  // namespace

std::uint64_t default_allpairs_memory() {
  const std::uint64_t four_gib = std::uint64_t{4} << 30;
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return four_gib;
  return std::min(four_gib, static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) / 2);
}

std::unique_ptr<Backend> make_allpairs_backend(int threads) { return std::make_unique<AllPairsBackend>(threads); }

}  // namespace trubal
