// What the cycle does with a backend's new candidate pair list: carry the history over, so that
// backends differ only in how they find the pairs.
#pragma once

#include "backends/pair_candidates.hpp"
#include "model/model.hpp"

namespace trubal {

// Makes `pairs` the contact table's pair list. Everything the old table knew about a pair (shear
// history above all) follows the pair: both lists are sorted by ball index, which is id order, so
// one merge matches them by the pair of ids (and image). New pairs start with zeros. The table
// gets a new list_version.
void install_pairs(ContactTable& table, const PairCandidates& pairs);
// `pairs` taken as the table's list, its history zero and its results dropped: for a caller that
// then writes every pair's history (a sync gathering the ranks' parts).
void install_pairs_zeroed(ContactTable& table, PairCandidates&& pairs);

// A list version no table of this process has had (install_pairs' counter): for a list whose
// arrays were replaced wholesale (a distributed run's copy from rank 0).
std::uint64_t fresh_list_version();

// A copy of the table's pair list (its pairs and images alone).
PairCandidates pair_list_of(const ContactTable& table);

// Whether the table already holds exactly these pairs (then nothing needs carrying over).
bool holds_pairs(const ContactTable& table, const PairCandidates& pairs);

}  // namespace trubal
