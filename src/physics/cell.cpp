#include "physics/cell.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "model/periodic_cell.hpp"
#include "physics/scene.hpp"
#include "physics/timestep.hpp"
#include "physics/bridge.hpp"
#include "physics/measure.hpp"
#include "support/exact_sum.hpp"

namespace trubal {

std::array<double, 3> cell_centre(const Space& s) {
  return {0.5 * (s.lo[0] + s.hi[0]) + 0.5 * (s.tilt[0] + s.tilt[1]), 0.5 * (s.lo[1] + s.hi[1]) + 0.5 * s.tilt[2],
          0.5 * (s.lo[2] + s.hi[2])};
}

void apply_field_change(Balls& b, const FieldChange& change, std::size_t k, double& work, double& gross) {
  const auto& g = change.g;
  const auto& centre = change.centre;
  std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  std::vector<double>* vel[3] = {&b.vx, &b.vy, &b.vz};
  work = gross = 0;
  for (int a = 0; a < 3; ++a) {
    if (b.fixed[k] & (a == 0 ? kXVel : a == 1 ? kYVel : kZVel)) continue;
    double dv = 0;
    bool changes = false;
    for (int e = a; e < 3; ++e) {
      if (g[a][e] == 0) continue;
      dv += g[a][e] * ((*pos[e])[k] - centre[e]);
      changes = true;
    }
    if (!changes) continue;
    double& v = (*vel[a])[k];
    const double old = v;
    v += dv;
    work += 0.5 * b.mass[k] * (v * v - old * old);
    gross += 0.5 * b.mass[k] * std::abs(v * v - old * old);
  }
}

void set_all_strain_rates(Model& model, const std::array<double, 6>& rates, FieldChange* defer) {
  Space& s = model.space;
  Balls& b = model.balls;
  std::array<double, 6> change{};
  bool any = false;
  for (int a = 0; a < 6; ++a) {
    change[a] = rates[a] - s.strain_rate[a];
    any = any || change[a] != 0;
    s.strain_rate[a] = rates[a];
  }
  if (defer) *defer = FieldChange{};
  if (!any || !s.periodic) return;
  FieldChange field;
  field.any = true;
  field.centre = cell_centre(s);
  const auto g = velocity_gradient(change);   // the change of the homogeneous field v = L (x - centre)
  for (int a = 0; a < 3; ++a)
    for (int e = 0; e < 3; ++e) field.g[a][e] = g[a][e];
  if (defer) { *defer = field; return; }
  update_mass(model);   // STRAIN may come before the first CYCLE: the energy needs the masses
  // Summed exactly, as the step's field changes are: the same bits however the balls are shared
  // (a distributed run's kept parts sum their own, Pipeline::apply_field).
  ExactSum work, gross;
  for (std::size_t k = 0; k < b.size(); ++k) {
    double ball_work, ball_gross;
    apply_field_change(b, field, k, ball_work, ball_gross);
    work.add(ball_work);
    gross.add(ball_gross);
  }
  model.energy.boundary_work += work.value();
  s.gross_work += gross.value();
}

void set_strain_rates(Model& model, const std::array<double, 3>& rates, FieldChange* defer) {
  const auto& r = model.space.strain_rate;
  set_all_strain_rates(model, {rates[0], rates[1], rates[2], r[3], r[4], r[5]}, defer);
}

// kServoFraction / (M dt), M = (1/V) sum k_n l_a^2.
static double servo_gain_for(double m, double dt) {
  if (!(m > 0) || !(dt > 0)) return std::numeric_limits<double>::infinity();
  return kServoFraction / (m * dt);
}

std::array<ExactSum, 3> servo_stiffness_sums(const Model& model, const std::vector<std::uint32_t>* pairs) {
  const ContactTable& c = model.contacts;
  const Balls& b = model.balls;
  std::array<ExactSum, 3> m;
  each_row(pairs, c.size(), [&](std::size_t p) {
    if (!c.touching(p)) return;
    const double l = b.rad[c.i[p]] + b.rad[c.j[p]] - c.overlap[p];
    const double n[3] = {c.nx[p], c.ny[p], c.nz[p]};
    for (int a = 0; a < 3; ++a) {
      const double la = l * n[a];
      m[a].add(c.kn_eff[p] * la * la);
    }
  });
  return m;
}

bool touches_nothing(const Model& model) {
  const auto& walls = model.wall_contacts.state;
  return contact_count(model) == 0 && count_bridges(model.contacts) == 0 && count_bridges(model.wall_contacts) == 0 &&
         std::none_of(walls.begin(), walls.end(), [](std::uint8_t s) { return s != 0; });
}

ContactMoments table_moments(const std::array<ExactSum, 6>& force, const std::array<ExactSum, 3>& stiffness) {
  ContactMoments m;
  for (int a = 0; a < 6; ++a) m.force[a] = force[a].value();
  for (int a = 0; a < 3; ++a) m.stiffness[a] = stiffness[a].value();
  return m;
}

double default_servo_max_rate(double dt) { return dt > 0 ? 1e-4 / dt : 0; }

double servo_rate(double error, double gain, double closes, double& integral, double most, double old) {
  const double proportional = gain * error;
  double r;
  if (!std::isfinite(proportional)) {   // nothing touches: as fast as allowed, nothing learnt
    r = error > 0 ? most : (error < 0 ? -most : 0);
    integral = 0;
  } else {
    const double step = kServoIntegral * closes * proportional;   // the integral grows by a quarter of it
    r = proportional + integral + step;
    // No winding up: where the limits cut the rate, the integral does not grow past them.
    const double limited = std::clamp(r, -most, most);
    if (!(limited != r && (step > 0) == (r > limited))) integral += step;
    integral = std::clamp(integral, -most, most);
  }
  // The rate changes by at most a quarter of the max rate per step: a velocity field switched
  // within one step would be accounted with the spring energy its last step made still missing.
  const double slew = 0.25 * most;
  return std::clamp(std::clamp(r, -most, most), old - slew, old + slew);
}

void cell_before_step(Model& model, double dt, const ContactMoments* last, FieldChange* defer) {
  Space& s = model.space;
  if (!s.periodic || !(s.servo_on[0] || s.servo_on[1] || s.servo_on[2])) {
    s.servo_integral = {0, 0, 0};   // a servo switched on again starts afresh
    return;
  }
  const auto L = s.length();
  const double volume = L[0] * L[1] * L[2];
  // Where no step has summed them yet, the contact table's results (the same values: exact sums).
  const ContactMoments read = last ? *last : table_moments(stress_sums(model).s, servo_stiffness_sums(model));
  Sym6 stress;
  for (int a = 0; a < 6; ++a) stress[a] = read.force[a] / volume;
  std::array<double, 3> rates{s.strain_rate[0], s.strain_rate[1], s.strain_rate[2]};
  const double most = s.servo_max_rate > 0 ? s.servo_max_rate : default_servo_max_rate(dt);
  // STRAIN's rule (check_cell_step) for the rates the servo may choose: a max rate that would let
  // it change an edge by more than half in one step is refused before anything moves (1e9 made
  // edges of zero or infinite length, and tilts no reduction could bring back).
  if (!(most * dt <= kMostEdgeChangePerStep))
    throw std::runtime_error(fmt::format(
        "SERVO max rate {:.4g} would change a cell edge by {:.3g} of its length in one step of {:.3g} (at most {}): "
        "lower SERVO max (at most {:.3g} at this step)",
        most, most * dt, dt, kMostEdgeChangePerStep, kMostEdgeChangePerStep / dt));
  for (int a = 0; a < 3; ++a) {
    double& integral = s.servo_integral[a];
    if (!s.servo_on[a]) { integral = 0; continue; }
    const double m = read.stiffness[a] / volume;
    const double gain = s.servo_gain > 0 ? s.servo_gain : servo_gain_for(m, dt);
    const double error = s.servo_target[a] - stress[a];   // too little compression: compress (rate > 0)
    // The fraction of the error this gain closes per step where the stress follows the contact
    // stiffness at once: kServoFraction by default.
    const double closes = m > 0 && dt > 0 ? std::min(1.0, gain * m * dt) : 0.0;
    rates[a] = servo_rate(error, gain, closes, integral, most, s.strain_rate[a]);
  }
  set_strain_rates(model, rates, defer);
}

void check_cell_step(const Space& s, double dt) {
  if (!s.periodic) return;
  const CellFrame f = cell_frame(s);
  const double change[6] = {f.vlx * dt / f.lx, f.vly * dt / f.ly, f.vlz * dt / f.lz,
                            f.vxy * dt / f.lx, f.vxz * dt / f.lx, f.vyz * dt / f.ly};
  static const char* what[6] = {"x edge", "y edge", "z edge", "xy tilt", "xz tilt", "yz tilt"};
  for (int k = 0; k < 6; ++k)
    if (!(std::abs(change[k]) <= kMostEdgeChangePerStep))
      throw std::runtime_error(fmt::format(
          "the strain rates would change the cell's {} by {:.3g} of an edge in one step (at most 0.5); "
          "STRAIN asked for more than any loading can be: lower the rate", what[k], change[k]));
}

void cell_after_step(Model& model, double dt, double work_dt, double image_power, bool reduce) {
  Space& s = model.space;
  if (!s.periodic) return;
  const CellFrame f = cell_frame(s);
  if (!f.moving()) return;
  // Energy into the balls through image contacts: the spring energy grows by -F_j . (dH/dt n) dt,
  // summed by the contact loop (image_power).
  const double work = image_power * work_dt;
  model.energy.boundary_work += work;
  s.gross_work += std::abs(work);
  // The new cell, H + (dH/dt) dt, about its centre.
  const auto centre = cell_centre(s);
  s.tilt[0] += f.vxy * dt;
  s.tilt[1] += f.vxz * dt;
  s.tilt[2] += f.vyz * dt;
  const double tilt_shift[3] = {0.5 * (s.tilt[0] + s.tilt[1]), 0.5 * s.tilt[2], 0.0};
  for (int a = 0; a < 3; ++a) {
    const double middle = centre[a] - tilt_shift[a];
    // L exp(-e dt) as L + L expm1(-e dt): exp(-e dt) itself, rounded the same way every step of a
    // steady rate, would bias the volume by its rounding each step (3e-12 over 50,000 steps).
    const double old_half = 0.5 * (s.hi[a] - s.lo[a]);
    const double half = old_half + old_half * std::expm1(-s.strain_rate[a] * dt);
    s.lo[a] = middle - half;
    s.hi[a] = middle + half;
  }
  for (int a = 0; a < 6; ++a) s.strain[a] += s.strain_rate[a] * dt;
  if (reduce) reduce_cell_tilt(model);
}

}  // namespace trubal
