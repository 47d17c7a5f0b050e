#include "physics/cell.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "backends/periodic.hpp"
#include "physics/engine.hpp"
#include "physics/measure.hpp"

namespace trubal {

void set_strain_rates(Model& model, const std::array<double, 3>& rates) {
  Space& s = model.space;
  Balls& b = model.balls;
  std::array<double, 3> change{}, centre{};
  bool any = false;
  for (int a = 0; a < 3; ++a) {
    change[a] = rates[a] - s.strain_rate[a];
    centre[a] = 0.5 * (s.lo[a] + s.hi[a]);
    any = any || change[a] != 0;
    s.strain_rate[a] = rates[a];
  }
  if (!any || !s.periodic) return;
  update_mass(model);   // STRAIN may come before the first CYCLE: the energy needs the masses
  std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  std::vector<double>* vel[3] = {&b.vx, &b.vy, &b.vz};
  double work = 0;
  for (std::size_t k = 0; k < b.size(); ++k)
    for (int a = 0; a < 3; ++a) {
      if (change[a] == 0) continue;
      if (b.fixed[k] & (a == 0 ? kXVel : a == 1 ? kYVel : kZVel)) continue;
      double& v = (*vel[a])[k];
      const double old = v;
      v -= change[a] * ((*pos[a])[k] - centre[a]);
      work += 0.5 * b.mass[k] * (v * v - old * old);
      s.gross_work += 0.5 * b.mass[k] * std::abs(v * v - old * old);
    }
  model.energy.boundary_work += work;
}

double default_servo_gain(const Model& model, int axis, double dt) {
  const ContactTable& c = model.contacts;
  const Balls& b = model.balls;
  const auto L = model.space.length();
  const double volume = L[0] * L[1] * L[2];
  const std::vector<double>* normal[3] = {&c.nx, &c.ny, &c.nz};
  double m = 0;
  for (std::size_t p = 0; p < c.size(); ++p) {
    if (c.state[p] == 0) continue;
    const double l = (b.rad[c.i[p]] + b.rad[c.j[p]] - c.overlap[p]) * (*normal[axis])[p];
    m += c.kn_eff[p] * l * l;
  }
  m /= volume;
  if (!(m > 0) || !(dt > 0)) return std::numeric_limits<double>::infinity();
  return kServoFraction / (m * dt);
}

double default_servo_max_rate(double dt) { return dt > 0 ? 1e-4 / dt : 0; }

void cell_before_step(Model& model, double dt) {
  Space& s = model.space;
  if (!s.periodic || !(s.servo_on[0] || s.servo_on[1] || s.servo_on[2])) return;
  const auto L = s.length();
  const Sym6 stress = average_stress(model, L[0] * L[1] * L[2]);
  std::array<double, 3> rates{s.strain_rate[0], s.strain_rate[1], s.strain_rate[2]};
  const double most = s.servo_max_rate > 0 ? s.servo_max_rate : default_servo_max_rate(dt);
  for (int a = 0; a < 3; ++a) {
    if (!s.servo_on[a]) continue;
    const double gain = s.servo_gain > 0 ? s.servo_gain : default_servo_gain(model, a, dt);
    const double error = s.servo_target[a] - stress[a];   // too little compression: compress (rate > 0)
    double r = gain * error;
    if (!std::isfinite(r)) r = error > 0 ? most : (error < 0 ? -most : 0);
    // The rate changes by at most a quarter of the max rate per step: a velocity field switched
    // within one step would be accounted with the spring energy its last step made still missing.
    const double slew = 0.25 * most, old = s.strain_rate[a];
    rates[a] = std::clamp(std::clamp(r, -most, most), old - slew, old + slew);
  }
  set_strain_rates(model, rates);
}

void cell_after_step(Model& model, double dt, double image_power) {
  Space& s = model.space;
  if (!s.periodic) return;
  const auto rate = image_rates(s);
  if (rate[0] == 0 && rate[1] == 0 && rate[2] == 0) return;
  // Energy into the balls through image contacts: the spring energy grows by -F_j . (image dL/dt) dt.
  const double work = image_power;
  model.energy.boundary_work += work * dt;
  s.gross_work += std::abs(work * dt);
  for (int a = 0; a < 3; ++a) {
    const double centre = 0.5 * (s.lo[a] + s.hi[a]);
    const double half = 0.5 * (s.hi[a] - s.lo[a]) * (1 - s.strain_rate[a] * dt);
    s.lo[a] = centre - half;
    s.hi[a] = centre + half;
    s.strain[a] += s.strain_rate[a] * dt;
  }
}

}  // namespace trubal
