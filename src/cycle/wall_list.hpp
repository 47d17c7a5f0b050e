// The ball-wall candidates: every (ball, wall) whose gap is below R + reach, found by the pipeline
// for every backend (walls are few; each ball is tested against each wall), and installed with
// the shear history carried over by (ball id, wall id).
#pragma once

#include "model/model.hpp"
#include "support/thread_pool.hpp"

namespace trubal {

// Searches and installs Model::wall_contacts (sorted by ball, then wall). `reach`: the pair list's
// skin (0: only what touches now).
void find_wall_contacts(Model& model, double reach, ThreadPool& pool);

}  // namespace trubal
