// Adding and removing balls while keeping the arrays sorted by id.
#pragma once

#include <cstdint>
#include <vector>

#include "model/model.hpp"

namespace trubal {

// Adds a ball at rest with no applied loads; returns its index. id <= 0 takes the next free id
// (one more than the largest). Throws std::invalid_argument if the id is taken or rad <= 0.
std::size_t add_ball(Model& model, std::int64_t id, int type, double x, double y, double z, double rad);

// Removes the balls whose flag is set, and the pairs that involve them; group lists keep only
// surviving ids. Returns how many were removed.
std::size_t remove_balls(Model& model, const std::vector<bool>& remove);

// After walls were added or removed (Model::walls, kept by ascending id): each wall contact's wall
// index is found again from its wall id, and the contacts of walls gone are dropped, so the table
// stays consistent (SAVE writes it; RESTART checks it).
void reindex_wall_contacts(Model& model);

// Index of the ball with this id, or -1.
std::int64_t find_ball(const Model& model, std::int64_t id);

}  // namespace trubal
