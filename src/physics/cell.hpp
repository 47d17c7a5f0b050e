// Control of the periodic cell (doc/physics.md "Periodic space"): strain rates (compression positive)
// deform the cell about its centre, the shear rates as simple shear (the cell becomes a
// parallelepiped, backends/periodic.hpp); ball velocities are total velocities and carry the
// homogeneous field v = L (x - c), so a change of rate changes every ball's velocity; the servo
// turns each normal rate toward a target average stress.
#pragma once

#include <array>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "model/model.hpp"
#include "support/exact_sum.hpp"

namespace trubal {

// The change of the homogeneous velocity field that a change of strain rates makes: each free
// velocity component of a ball at x changes by sum_e g[a][e] (x_e - centre_e).
struct FieldChange {
  bool any = false;
  std::array<std::array<double, 3>, 3> g{};
  std::array<double, 3> centre{};
};
// Applies it to ball k, returning the kinetic energy it gains (`work`, its components in order) and
// that energy's magnitude (`gross`). The cycle applies it to every copy of a ball and sums the
// works of the balls it owns exactly (cycle/pipeline.hpp).
void apply_field_change(Balls& balls, const FieldChange& change, std::size_t k, double& work, double& gross);

// Sets the strain rates (xx yy zz xy xz yz; tensor components, compression positive) and changes
// every free velocity component by the change of the homogeneous field v = L (x - centre), L the
// velocity gradient (backends/periodic.hpp: simple shear for the shear rates); the kinetic energy
// this adds is counted as boundary work.
// With `defer`, the balls are left as they are and the change is handed back instead (the cycle's
// pipeline applies it where the balls are: cycle/pipeline.hpp).
void set_all_strain_rates(Model& model, const std::array<double, 6>& rates, FieldChange* defer = nullptr);
// The normal rates (xx yy zz) only; the shear rates stay.
void set_strain_rates(Model& model, const std::array<double, 3>& rates, FieldChange* defer = nullptr);

// The centre of the periodic cell, about which it deforms.
std::array<double, 3> cell_centre(const Space& space);

// The servo (doc/physics.md "Periodic space"): proportional-integral, per axis. The proportional
// rate is G (target - stress); by default G closes kServoFraction of the error in one step if the
// stress followed the contact stiffness at once, G = kServoFraction / (M dt) with
// M_a = (1/V) sum k_n (l n_a)^2 over the touching contacts (PFC's rule G = alpha A / (k_n N_c dt) in
// stress form). The integral term (Space::servo_integral, a rate) grows each step by
// kServoIntegral times the fraction f = G M dt the gain closes, times the proportional rate: with
// kServoIntegral = 1/4 the loop is critically damped on that ideal plant (both poles at 1 - f/2),
// and a steady loading (a strain on another axis, dilation under shear) is held with no offset.
// It does not grow while the rate limits cut the rate (no wind-up), and is 0 while nothing
// touches (the rate is then the max rate toward the target). Measured with tools/servo_hold.py.
inline constexpr double kServoFraction = 0.15;
inline constexpr double kServoIntegral = 0.25;
// One step of the PI law: the new rate from the error (target - measured), the proportional gain,
// the fraction of the error it closes per step, the integral term (updated), the largest rate and
// the rate now (the rate changes by at most a quarter of the largest per step). An infinite
// proportional rate (nothing touches) moves at the largest rate toward the target.
double servo_rate(double error, double gain, double closes, double& integral, double most, double old);
// The sums of M_a = (1/V) sum k_n (l n_a)^2 over the touching pairs of the contact table's results
// (the servo's first step, before a force pass summed them; `pairs`: the rows taken, every one
// where null), each an exact sum, so that merged over shares of the pairs (the ranks' parts) they
// are the whole table's bits.
std::array<ExactSum, 3> servo_stiffness_sums(const Model& model, const std::vector<std::uint32_t>* pairs = nullptr);
// Whether no pair or wall contact of the model's tables touches and no capillary bridge holds: a
// servo's first reading of the table is then of no force and no stiffness (Love's sums and
// servo_stiffness_sums read the touching contacts and the bridges alone). A search makes no
// contact touch.
bool touches_nothing(const Model& model);
// What a servo reads of a step from the contact table's sums, Love's (physics/measure.hpp
// stress_sums) and the stiffness's: their values, as a step's own sums give them.
ContactMoments table_moments(const std::array<ExactSum, 6>& force, const std::array<ExactSum, 3>& stiffness);
// Default largest servo rate: rate dt <= 1e-4, the cell changes by at most 1e-4 of its size per step.
double default_servo_max_rate(double dt);

// The most a step may change an edge or a tilt of the periodic cell, as a fraction of an edge: a
// rate beyond it is beyond any physical loading (STRAIN's rates, SERVO's max rate).
inline constexpr double kMostEdgeChangePerStep = 0.5;
// Throws std::runtime_error when the strain rates would change any edge or tilt of the periodic cell
// by more than kMostEdgeChangePerStep of an edge in one step of dt.
void check_cell_step(const Space& space, double dt);

// Before a step in a periodic space: the servo's new rates, from the last force pass's stress
// (`last`, or the contact table's per-pair results when it is null). Throws std::runtime_error, before
// it changes anything, when the servo's max rate times dt passes kMostEdgeChangePerStep.
// With `defer`, the velocity change of the new rates is handed back, not applied (set_all_strain_rates).
void cell_before_step(Model& model, double dt, const ContactMoments* last = nullptr, FieldChange* defer = nullptr);
// After a step of dt: the work the cell did on the balls through image contacts (image_power: the
// contact loop's sum of -F_j . (image velocity), StepSums::image_power, charged over work_dt, the
// mean of the step before and this one, as the law of motion charges every force), the new cell
// edges and tilts (about the centre, tilts kept within half an edge) and the accumulated strain.
// An edge L at the rate e becomes L exp(-e dt), so the strain summed, sum(e dt), is the natural
// strain -ln(L / L0), and rates whose trace is zero keep the volume to rounding.
// `reduce` false leaves the tilts to the caller (reduce_cell_tilt, which renumbers the pair images:
// the cycle's pipeline does it where the pairs are).
void cell_after_step(Model& model, double dt, double work_dt, double image_power, bool reduce = true);

}  // namespace trubal
