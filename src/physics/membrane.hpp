// MEMBRANE (Rowe's triaxial test): a confining pressure as horizontal forces on the perimeter balls
// of a sample built of square layers (LATTICE fcc cut to octagons).
//
// Each ball of a layer owns the square cell of side d (its diameter) about it; the layer's cross
// section is the union of its cells (76 d^2 for Rowe's large layer, 37 d^2 for Cundall's). A cell
// face with no neighbour cell behind it is on the membrane, and the pressure on it, p times d times
// the layer's tributary height h, acts on the ball, inward. A ball on a straight side has one such
// face (force p d h normal to the side); a ball on a diagonal side has two (force sqrt(2) p d h at
// 45 degrees, normal to that side). So the forces on each side of the octagon add up to p times the
// side's area, and the lateral stress they put on the cross section's prism is exactly p.
//
// Only the outermost layers are loaded (Rowe's large layers): those reaching the sample's widest
// extent, to within half a radius. The smaller layers between them sit half a diameter inside,
// behind the membrane. A loaded layer's tributary height is half the distance to the loaded
// layers above and below (at the top and bottom: half the distance to the one neighbour), so the
// heights add up to the distance between the end layers' centres.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "model/model.hpp"

namespace trubal {

struct MembraneLoads {
  std::vector<std::size_t> balls;      // loaded balls, ascending index
  std::vector<double> fx, fy;          // the force on each
  std::size_t layers = 0, loaded_layers = 0;
  double cell = 0;                     // d
  double area = 0;                     // union of the cells of the largest loaded layer
  // What following the sample needs (Membrane): per loaded ball its open faces and loaded layer,
  // per loaded layer its centres' extent and its cells.
  std::vector<std::int8_t> face_x, face_y;
  std::vector<std::int32_t> layer;
  std::vector<double> extent_x, extent_y, layer_cells;
};

// The loads for pressure p on the selected balls (ascending indices). Throws std::runtime_error when
// the balls are not of one size or a loaded layer is not on a square grid of spacing d.
MembraneLoads membrane_loads(const Model& model, const std::vector<std::size_t>& selection, double pressure);

// MEMBRANE p follow: the same loads from the positions now. Each loaded layer's tributary height is
// taken from the loaded layers' heights now, and each face grows with its layer's extent across it
// (a face normal to x with the layer's y extent over the first one, and so on), so the forces on
// each side stay p times its area as the sample bulges; the area A of HIST ratio follows the widest
// layer's extent (its cells times both stretches). The balls' x and y applied loads are set.
void follow_membrane(Model& model);
// Its parts, for the ranks' parts (Pipeline::follow_membrane_on_parts): the loaded balls' centres
// by their place in Membrane::ids (present 0 where the ball is gone), and from them the x and y
// loads of each (0 where gone) and the area, every one made as follow_membrane makes it.
struct MembraneCentres {
  std::vector<double> x, y, z;
  std::vector<std::uint8_t> present;
};
struct MembraneFollow {
  std::vector<double> ax, ay;
  double area = 0;
};
MembraneFollow follow_loads(const Membrane& m, const MembraneCentres& at);

}  // namespace trubal
