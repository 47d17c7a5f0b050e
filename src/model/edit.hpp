// Adding, removing and reordering balls, with everything the model keeps by ball index.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "model/model.hpp"

namespace trubal {

// Adds a ball at rest with no applied loads, last in memory; returns its index. id <= 0 takes the
// next free id (one more than the largest). Throws std::invalid_argument if the id is taken or
// rad <= 0. The model is put in space order at its next step (Model::order).
std::size_t add_ball(Model& model, std::int64_t id, int type, double x, double y, double z, double rad);

// What is wrong with a ball's radius in this space, or "" where nothing is: the radius of a new
// ball (BALL) and of one changed (the Python module's radii) must be positive and at most the
// space's diagonal. A ball larger than that would cover the whole START region, every other
// centre inside it; and far larger ones overflow their mass (r^3) and inertia (r^5), which CYCLE
// could then only report as an unstable step.
std::string ball_radius_problem(const Space& space, double rad);

// Removes the balls whose flag is set, and the pairs that involve them; group lists keep only
// surviving ids. Returns how many were removed.
std::size_t remove_balls(Model& model, const std::vector<bool>& remove);

// After walls were added or removed (Model::walls, kept by ascending id): each wall contact's wall
// index is found again from its wall id, and the contacts of walls gone are dropped, so the table
// stays consistent (SAVE writes it; RESTART checks it).
void reindex_wall_contacts(Model& model);

// Index of the ball with this id, or -1.
std::int64_t find_ball(const Model& model, std::int64_t id);

// Puts the balls in the order `order` (new index k holds the ball at old index order[k]), and
// with them everything the model keeps by index: the pair list (a pair whose balls change order is
// turned round: its shear history, normal, force and image change sign, so the physics is the
// same) and the wall contacts. Ids, groups and the membrane's balls are by id and stay.
void reorder_balls(Model& model, const std::vector<std::size_t>& order);

// Of every array `visit` lists (visit(f) calls f on each) that is `n` long, the rows `rows` names
// kept, in that order (new position k holds old element rows[k]); arrays of another length
// (results not kept, a hollow model's arrays let go) are left alone.
template <class Visit, class Index> void keep_rows(Visit&& visit, const std::vector<Index>& rows, std::size_t n) {
  visit([&](auto& v) {
    if (v.size() != n) return;
    std::decay_t<decltype(v)> out(rows.size());
    for (std::size_t k = 0; k < rows.size(); ++k) out[k] = v[rows[k]];
    v.swap(out);
  });
}
// The arrays put in the order `order`, a permutation (keep_rows of every row).
template <class Visit, class Index> void permute_arrays(Visit&& visit, const std::vector<Index>& order) {
  keep_rows(visit, order, order.size());
}

// The space order's parts (sort_in_space), for a run whose balls are kept apart (a distributed
// run's parts: BrickStep::sort_in_space): the corner the cells are counted from, the least finite
// coordinate along each axis (infinite where none) of the balls `pick` names (all where null); a
// ball's key, its cell of the grid `cell` wide from `lo` as a Morton code (21 bits an axis), the
// last key where its centre is not finite. The order is by key, then by id; the cell is
// order_cell's, one largest diameter.
std::array<double, 3> space_corner(const Balls& b, const std::vector<std::uint32_t>* pick = nullptr);
std::uint64_t space_key(double x, double y, double z, const std::array<double, 3>& lo, double cell);
double order_cell(const Balls& b);

// The balls in space order (the Morton order of cells one largest diameter wide from the lowest
// centres, ties by id), as the run puts them at the cycles Model::order names. A function of the
// balls' centres and ids alone, so every backend, thread and rank count and cut of a run puts
// them in the same order, and so does a model that reached the same state another way. Returns whether any ball moved.
bool sort_in_space(Model& model);
// The same, returning the order the balls were put in (new index k holds the ball at old index
// order[k]), or nothing where none moved.
std::vector<std::size_t> sort_in_space_order(Model& model);

// Whether the step about to be taken puts the balls in space order first (Model::order).
inline bool sort_due(const Model& model) {
  return model.order.every > 0 && (model.order.pending || model.cycle % model.order.every == 0);
}

// RENUMBER: the balls get the ids 1..N, in space order (the Morton order of cells one largest
// diameter wide, as LAMMPS's `reset_atoms id sort yes` numbers atoms by bins) or in
// the order of their ids (compacting them); in space order the balls are put in that order in
// memory too (reorder_balls). Groups and the membrane's balls follow
// their balls' new ids. The caller renumbers what it keeps of its own (Session: histories'
// platens, GEN's last balls) through the returned map.
enum class RenumberOrder { Space, Present };
struct Renumbering {
  std::vector<std::int64_t> old_ids;   // the ids before, ascending
  std::vector<std::int64_t> new_ids;   // the new id of the ball that had old_ids[k]
  double cell = 0;                     // the cells' width (space order)
  // The new id of the ball that had id `old`, or 0 where no ball had it.
  std::int64_t map(std::int64_t old) const;
};
Renumbering renumber_balls(Model& model, RenumberOrder order);

}  // namespace trubal
