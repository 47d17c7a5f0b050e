// What people read after a run: where cycling time went (contact detection, forces, motion,
// output), one line after each CYCLE and a small table when the program ends (as LAMMPS's
// timing breakdown).
#pragma once

#include <cstdint>
#include <string>

#include "cycle/phase_times.hpp"

namespace trubal {

// "detect 12%, forces 55%, motion 28%, output 3%, other 2%" of `seconds`. A backend that does not
// split its step shows "detect+forces+motion" as one share.
std::string phase_split(const PhaseTimes& times, double seconds);

// The end-of-program table: cycles, wall time, ball-cycles/s and the phases in seconds and
// percent of the cycling time. Empty when nothing was cycled.
std::string run_summary(std::int64_t cycles, double ball_cycles, double cycling_seconds, double wall_seconds,
                        const PhaseTimes& times);

}  // namespace trubal
