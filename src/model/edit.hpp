// Adding and removing balls while keeping the arrays sorted by id.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "model/model.hpp"

namespace trubal {

// Adds a ball at rest with no applied loads; returns its index. id <= 0 takes the next free id
// (one more than the largest). Throws std::invalid_argument if the id is taken or rad <= 0.
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

// RENUMBER: the balls get the ids 1..N, in space order (the Morton order of cells one largest
// diameter wide, as LAMMPS's `reset_atoms id sort yes` numbers atoms by bins) or in their present
// order. Storage order is id order, so the balls' arrays are permuted with them: neighbours in space
// become neighbours in memory, which the contact loop reads faster. Everything the model keeps by
// index or by id follows its ball: the pair list (a pair whose balls change order is turned round:
// its shear history, normal, force and image change sign, so the physics is the same), the wall
// contacts, groups and the membrane's balls. The caller renumbers what it keeps of its own (Session:
// histories' platens, GEN's last balls) through the returned map.
enum class RenumberOrder { Space, Present };
struct Renumbering {
  std::vector<std::int64_t> old_ids;   // the ids before, ascending (by old index)
  std::vector<std::int64_t> new_ids;   // the new id of the ball at each old index
  double cell = 0;                     // the cells' width (space order)
  // The new id of the ball that had id `old`, or 0 where no ball had it.
  std::int64_t map(std::int64_t old) const;
};
Renumbering renumber_balls(Model& model, RenumberOrder order);

}  // namespace trubal
