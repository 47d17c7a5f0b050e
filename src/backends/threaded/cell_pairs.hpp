// The threaded backend's pair list build: the serial backend's boxes (BoxGrid), filled once, then
// each thread searches them for its own range of balls and the lists are joined: the serial list
// exactly.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "backends/serial/box_grid.hpp"
#include "backends/pair_candidates.hpp"
#include "support/thread_pool.hpp"
#include "model/model.hpp"

namespace trubal {

class CellPairs {
 public:
  void find(ThreadPool& pool, const Balls& balls, double min_size, const std::array<int, 3>& asked, double skin,
            PairCandidates& out);
  const BoxGrid& grid() const { return grid_; }

 private:
  BoxGrid grid_;
  std::vector<PairCandidates> parts_;   // per thread
};

}  // namespace trubal
