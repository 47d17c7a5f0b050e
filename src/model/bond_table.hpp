// Edits of the bond table (model/bonds.hpp): making bonds (BOND), deleting them, and keeping them
// by their balls' ids through deletions and renumbering; the table's check on RESTART.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "model/model.hpp"

namespace trubal {

// BOND's words: the largest gap of a pair bonded, and the law of each bond made (physics/bond.hpp).
struct BondSpec {
  double gap = 0;
  double kn = 0, ks = 0, tension = 0, cohesion = 0, tan_friction = 0;
  double rmul = 1, mcf = 1;
};

// The table's rows by (id_i, id_j) (each row with id_i < id_j): the order of every list, file and
// sum of the bonds outside the step.
std::vector<std::size_t> bond_rows_by_id(const Bonds& bonds);
// Sorts the table by (id_i, id_j).
void sort_bonds(Bonds& bonds);

// Bonds every pair of the balls `selected` (indices) whose gap at j's nearest image is at most
// spec.gap and that has no bond yet, intact or broken (a broken bond is gone for good). The bond's
// radius is spec.rmul times the smaller ball's; its forces start at zero. Returns how many were made.
std::size_t add_bonds(Model& model, const std::vector<std::size_t>& selected, const BondSpec& spec);

// Removes the bonds, intact or broken, that hold a ball of `selected` (indices). Returns how many.
std::size_t delete_bonds(Model& model, const std::vector<std::size_t>& selected);

// Removes the bonds whose balls are not both in the model (after balls were removed).
void drop_bonds_of_missing_balls(Model& model);

// The balls' ids changed (RENUMBER): each bond's ids through `map` (old id to new), turned round
// where they changed order (Fs and Mb change sign: Bonds::for_each_swapped), the table sorted again.
void renumber_bonds(Bonds& bonds, const std::function<std::int64_t(std::int64_t)>& map);

// What is wrong with the table of a model read from a file, or "" where nothing is: every array of
// its length, id_i < id_j naming balls of the model, no pair twice, the law's numbers finite
// with positive stiffness and radius, the fate a known code.
std::string bond_table_problem(const Model& model);

}  // namespace trubal
