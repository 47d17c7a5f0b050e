// The parallel bonds' part of a step (physics/bond.hpp; doc/physics.md "Parallel bonds"), for
// scenes with bonds only (Features::bonds): a pass of its own beside the contact loops, as the
// capillary bridges' (cycle/bridge_pass.hpp), so that the contact kernel tables stay as they are.
//
// 1. bond_forces (bonds in any shares, after the contact loops): each intact bond's forces and
//    moments from the relative motion of its balls over the step before (positions at t, velocities
//    at t - dt/2, as the contact law's shear spring), then the breakage rules; a bond that breaks
//    books the strain energy it held as lost (StepSums::bond_break) and pushes no more. Its push
//    goes to the bond's scratch as each of its balls will add it, its strain energy to the step's,
//    its force to the servo's moments where a servo reads them. The bonds are stepped in the order of
//    their balls in memory (prepare_bonds puts the table in that order), so that the gather reads
//    the balls as the contact loops do and the bonds as blocks.
// 2. settle_broken_bonds (once, after every share): the stiffness sums of the balls whose bonds
//    broke, again over their bonds that hold.
// 3. add_bonds (per ball, before the law of motion): each ball's pushes summed in one order, its
//    bonds as partner j (ascending i), then as i (ascending j), by the balls' ids, and
//    joined to its contact sums; so every backend and thread count gives the same bits.
#pragma once

#include <cstddef>

#include "cycle/kernels.hpp"
#include "cycle/step_scratch.hpp"
#include "model/model.hpp"

namespace trubal {

// Puts the table's rows in the step's order (its intact bonds first, by their balls' places in
// memory) and indexes them by ball, again where the balls, the table's rows or which bonds hold
// changed; for `shares` shares of step 1.
void prepare_bonds(Model& model, StepScratch& scratch, int shares);
// How many bonds step 1 takes: the table's first rows, the places [0, count) of the step's order.
inline std::size_t bond_places(const StepScratch& scratch) { return scratch.bond_ball_i.size(); }
// Places [begin, end) of the step's order: step 1, as share `share`. `sums`: the strain energy, the
// energy lost at breakage, the servo's moments and the image power, where the bond's ball i is not
// a ghost.
void bond_forces(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                 StepSums& sums, int share);
// Step 2, after every share of step 1.
void settle_broken_bonds(StepScratch& scratch);
// Balls [begin, end): step 2.
void add_bonds(StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end);

}  // namespace trubal
