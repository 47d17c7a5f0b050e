// A ball's index from its id, in tests: the model keeps its balls in its own order in memory
// (space order after a step, model/model.hpp), so a test that reads a ball after CYCLE finds it.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "model/model.hpp"

namespace trubal::test {

// The index of the ball with this id (a scan, so it holds for models built by hand too); throws
// where there is none.
inline std::size_t at(const Model& m, std::int64_t id) {
  for (std::size_t k = 0; k < m.balls.size(); ++k)
    if (m.balls.id[k] == id) return k;
  throw std::runtime_error("no ball " + std::to_string(id));
}

}  // namespace trubal::test
