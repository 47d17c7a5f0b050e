// A dump's balls and contact lines as rows of reals (DUMP vtk: io/vtk.hpp writes its balls' and
// contacts' files a row at a time, each value at its place in the file, so that no array is held
// whole; a distributed run's ranks send rank 0 the rows of their parts in the whole model's order).
//
// A ball's row: its place in the whole model (the rows' order), x y z, id (its bits), type,
// radius, vx vy vz, wx wy wz, fx fy fz. A touching pair's line's: its ball i's place, i's centre,
// the other end (j's centre, at the image the contact is with), the magnitude of the normal force,
// the force on j, the ids of i and j (their bits).
#pragma once

#include <cstddef>

#include "model/model.hpp"
#include "model/periodic_cell.hpp"

namespace trubal {

inline constexpr std::size_t kVtkBallRow = 16, kVtkLineRow = 13;
// Ball k's row, its place left 0.
void vtk_ball_row(const Balls& b, std::size_t k, double* row);
// Whether pair p is a line: it touches in the table's results.
bool vtk_line(const Model& model, std::size_t p);
// Pair p's row where it is a line (its place left 0); false where not.
bool vtk_line_row(const Model& model, const CellFrame& frame, std::size_t p, double* row);

}  // namespace trubal
