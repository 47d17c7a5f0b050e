// The kernel tables, one entry per combination of features (ContactFeatures and MotionFeatures own
// the encoding of an index). Each table lives in a file of its own (kernels_*.cpp), so that a
// parallel build compiles them side by side; make_kernels (kernels.cpp) picks from them.
#pragma once

#include "cycle/kernels.hpp"

namespace trubal::loops {

// The contact loop of ContactFeatures index i: details off (i < kCount / 2) or on.
ContactLoop contact_loop_lean(unsigned i);
ContactLoop contact_loop_full(unsigned i);
// The cross loop of index i (never with details: i < ContactFeatures::kCount / 2).
CrossLoop cross_loop_at(unsigned i);
WallLoop wall_loop_at(unsigned i);
// The motion loop of MotionFeatures index i: forces unwritten (i < kCount / 2) or written.
MotionLoop motion_loop_lean(unsigned i);
MotionLoop motion_loop_full(unsigned i);

}  // namespace trubal::loops
