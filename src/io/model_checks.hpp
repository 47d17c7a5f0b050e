// What must hold of a model for it to run, where a checksum cannot vouch for it (a save written by
// hand or by another program): RESTART refuses one that fails.
#pragma once

#include <string>

#include "model/model.hpp"

namespace trubal {

// "" when the model holds together, else what does not.
std::string invalid_model(const Model& m);
// Its checks one at a time, as a save read a piece at a time makes them (SavedTables): the ball
// ids given once each (their index made); ball k of `b`, the model's `at`th; pair p of `c`, the
// table's `at`th (sorted against pair p - 1 where p > 0; that its balls are the model's is
// checked before, as a damaged file's); wall contact p of `wc`, the table's `at`th, against the
// balls and walls of `m`; and all the rest but the bulk (the space, materials, settings,
// membrane, walls and sample).
std::string ids_problem(const Balls& b);
std::string ball_problem(const Balls& b, std::size_t k, std::size_t at);
std::string pair_problem(const ContactTable& c, std::size_t p, std::size_t at);
std::string wall_contact_problem(const WallContacts& wc, std::size_t p, std::size_t at, const Model& m);
std::string light_problem(const Model& m);

}  // namespace trubal
