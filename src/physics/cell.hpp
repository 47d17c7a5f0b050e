// Control of the periodic cell (PHYSICS.md "Periodic space"): strain rates (compression positive)
// deform the cell about its centre; ball velocities are total velocities and carry the homogeneous
// field v_a = -rate_a (x_a - c_a), so a change of rate changes every ball's velocity; the servo
// turns each axis's rate toward a target average stress.
#pragma once

#include <array>

#include "model/model.hpp"

namespace trubal {

// Sets the normal strain rates (xx yy zz) and changes every ball's velocity by the change of the
// homogeneous field; the kinetic energy this adds is counted as boundary work.
void set_strain_rates(Model& model, const std::array<double, 3>& rates);

// Servo gain (strain rate per unit stress error) that the default uses for an axis: the stress
// would close kServoFraction of its error in one step if it followed the contact stiffness at once,
// sigma change = M rate dt with M_a = (1/V) sum k_n (l n_a)^2 over the touching contacts.
// Infinite when nothing touches (the rate is then the max rate).
inline constexpr double kServoFraction = 0.01;
double default_servo_gain(const Model& model, int axis, double dt);
// Default largest servo rate: rate dt <= 1e-4, the cell changes by at most 1e-4 of its size per step.
double default_servo_max_rate(double dt);

// Before a step in a periodic space: the servo's new rates (from the last force pass's stress).
void cell_before_step(Model& model, double dt);
// After a step: the work the cell did on the balls through image contacts (image_power: the
// contact loop's sum of -F_j . (image velocity), StepSums::image_power), the new cell edges
// (about the centre) and the accumulated strain.
void cell_after_step(Model& model, double dt, double image_power);

}  // namespace trubal
