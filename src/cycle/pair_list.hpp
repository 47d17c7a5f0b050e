// What the cycle does with a backend's new candidate pair list: carry the history over, so that
// backends differ only in how they find the pairs.
#pragma once

#include "backends/pair_candidates.hpp"
#include "model/model.hpp"

namespace trubal {

// The order of a pair list (a ContactTable's or PairCandidates'): by i, then j, then image (the
// same two balls may touch across several periodic faces in a small cell). Pair p of `a` before
// pair q of `b`.
template <class A, class B> bool pair_before(const A& a, std::size_t p, const B& b, std::size_t q) {
  if (a.i[p] != b.i[q]) return a.i[p] < b.i[q];
  if (a.j[p] != b.j[q]) return a.j[p] < b.j[q];
  if (a.image_x[p] != b.image_x[q]) return a.image_x[p] < b.image_x[q];
  if (a.image_y[p] != b.image_y[q]) return a.image_y[p] < b.image_y[q];
  return a.image_z[p] < b.image_z[q];
}

// Makes `pairs` the contact table's pair list. Everything the old table knew about a pair (shear
// history above all) follows the pair: both lists are sorted by ball index, which is id order, so
// one merge matches them by the pair of ids (and image). New pairs start with zeros. The table
// gets a new list_version.
void install_pairs(ContactTable& table, const PairCandidates& pairs);

// A list version no table of this process has had (install_pairs' counter): for a list whose
// arrays were replaced wholesale (a distributed run's copy from rank 0).
std::uint64_t fresh_list_version();

// Whether the table already holds exactly these pairs (then nothing needs carrying over).
bool holds_pairs(const ContactTable& table, const PairCandidates& pairs);

}  // namespace trubal
