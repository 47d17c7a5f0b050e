// What every backend does with a new candidate pair list: carry the history over and index the
// gather. Shared so that backends differ only in how they find the pairs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "backends/pair_candidates.hpp"
#include "model/model.hpp"

namespace trubal {

// Makes `pairs` the contact table's pair list. Everything the old table knew about a pair (shear
// history above all) follows the pair: both lists are sorted by ball index, which is id order, so
// one merge matches them by the pair of ids. New pairs start with zeros. Then indexes the gather.
void install_pairs(ContactTable& table, const PairCandidates& pairs, std::size_t ball_count);

// The gather index: for each ball its pairs in ascending partner order (PHYSICS: forces are
// summed by partner id), +1 where the ball is j, -1 where it is i.
void build_gather(ContactTable& table, std::size_t ball_count);

}  // namespace trubal
