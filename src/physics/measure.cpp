// Measurements from the balls and the contact table's last force pass.
#include "physics/measure.hpp"

#include "physics/bond.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/bond_table.hpp"
#include "model/periodic_cell.hpp"
#include "physics/bridge.hpp"
#include "physics/walls.hpp"
#include "physics/contact/energy.hpp"
#include "physics/contact/normal_hertz.hpp"
#include "physics/contact/normal_linear.hpp"

namespace trubal {
namespace {

bool is_hertz(const Model& model, std::size_t ball) {
  const auto it = model.materials.find(model.balls.type[ball]);
  return it != model.materials.end() && it->second.hertz();
}

// Adds the spring energy of a touching contact to `sum`: normal (tangent stiffness kn at overlap u),
// then shear.
void add_contact_strain(double& sum, bool hertz, double kn, double u, double fsx, double fsy, double fsz, double ks) {
  sum += hertz ? normal_spring_energy<HertzNormal>(HertzNormal::spring_force(kn, u), u)
               : normal_spring_energy<LinearNormal>(LinearNormal::spring_force(kn, u), u);
  sum += shear_spring_energy(fsx * fsx + fsy * fsy + fsz * fsz, ks);
}

}  // namespace

void add_dyad(Sym6& s, double ax, double ay, double az, double bx, double by, double bz) {
  s[0] += ax * bx; s[1] += ay * by; s[2] += az * bz;
  s[3] += 0.5 * (ax * by + ay * bx);
  s[4] += 0.5 * (ax * bz + az * bx);
  s[5] += 0.5 * (ay * bz + az * by);
}

Sym6 StressSums::over(double volume) const {
  Sym6 out;
  for (int k = 0; k < 6; ++k) out[k] = s[k].value() / volume;
  return out;
}

void StressSums::add(const StressSums& o) {
  for (int k = 0; k < 6; ++k) s[k].add(o.s[k]);
}

StressSums stress_sums(const Model& model, const std::vector<std::uint32_t>* pairs, const std::vector<std::uint32_t>* walls) {
  StressSums out;
  DyadSums d(out.s);
  const ContactTable& c = model.contacts;
  const Balls& b = model.balls;
  // Force on j times the branch vector i -> j: positive when the pair is pushed apart, so
  // compression comes out positive (soil-mechanics sign).
  each_row(pairs, c.size(), [&](std::size_t p) {
    if (!c.touching(p)) return;
    const double l = b.rad[c.i[p]] + b.rad[c.j[p]] - c.overlap[p];
    d.add(c.fx[p], c.fy[p], c.fz[p], l * c.nx[p], l * c.ny[p], l * c.nz[p]);
  });
  // The capillary bridges' part: each bridge the last force pass left (the state it pulled with),
  // its force on j, -F n, times the branch vector i -> j; at a wall, the force on the wall times
  // the branch from the ball's centre to the wall. The pass's gaps are not kept (a pair apart has
  // no results), so the gaps are the positions' now, one step on from that pass.
  const WallContacts& w = model.wall_contacts;
  if (has_bridges(model)) {
    const CellFrame cell = cell_frame(model.space);
    if (c.bridge.size() == c.size())
      each_row(pairs, c.size(), [&](std::size_t p) {
        if (c.bridge[p] == 0) return;
        const std::size_t i = c.i[p], j = c.j[p];
        const auto [dx, dy, dz] = pair_separation(cell, model.space.periodic, b, c, p);
        const double dist = std::sqrt(dx * dx + dy * dy + dz * dz);
        if (!(dist > 0)) return;
        const double f = -bridge_force(pair_bridge(model, i, j), b.rad[i], b.rad[j], dist - b.rad[i] - b.rad[j]) / dist;
        d.add(f * dx, f * dy, f * dz, dx, dy, dz);
      });
    if (w.bridge.size() == w.size())
      each_row(walls, w.size(), [&](std::size_t p) {
        if (w.bridge[p] == 0 || w.ball[p] >= b.size() || w.wall[p] >= model.walls.size()) return;
        const std::size_t i = w.ball[p];
        const Vec3 centre{b.x[i], b.y[i], b.z[i]};
        const WallLane lane = wall_lane(model.walls[w.wall[p]], centre, b.rad[i]);
        const double dist = std::sqrt(lane.dx * lane.dx + lane.dy * lane.dy + lane.dz * lane.dz);
        if (!(dist > 0)) return;
        const double f = -bridge_force(wall_bridge(model, i, w.wall[p]), lane.r, lane.r, dist - 2 * lane.r) / dist;
        d.add(f * lane.dx, f * lane.dy, f * lane.dz, lane.point[0] - centre[0], lane.point[1] - centre[1],
              lane.point[2] - centre[2]);
      });
  }
  // Ball-wall contacts: the force on the wall and the branch from the ball's centre to the contact point.
  if (w.fx.size() == w.size() && w.overlap.size() == w.size())
    each_row(walls, w.size(), [&](std::size_t p) {
      if (w.state[p] == 0 || w.ball[p] >= b.size()) return;
      const double l = b.rad[w.ball[p]] - w.overlap[p];
      d.add(w.fx[p], w.fy[p], w.fz[p], l * w.nx[p], l * w.ny[p], l * w.nz[p]);
    });
  return out;
}

Sym6 average_stress(const Model& model, double volume) { return stress_sums(model).over(volume); }

double EnergyReport::total() const {
  return kinetic_translation + kinetic_rotation + strain + potential + friction_work + rolling_work + damping_work +
         bond_break_work - boundary_work - capillary_work;
}

EnergyReport energy(const Model& model) {
  EnergyReport e;
  e.friction_work = model.energy.friction_work;
  e.rolling_work = model.energy.rolling_work;
  e.damping_work = model.energy.damping_work;
  e.boundary_work = model.energy.boundary_work;
  e.capillary_work = model.energy.capillary_work;
  e.bond_break_work = model.energy.bond_break_work;
  const EnergyAtStep& now = model.energy_at_step;
  if (now.valid) {   // all at t, the time of the last force pass (the step's own sums)
    e.at_step = true;
    e.kinetic_translation = now.kinetic_translation;
    e.kinetic_rotation = now.kinetic_rotation;
    e.strain = now.strain;
    e.potential = now.potential;
    e.damping_work -= now.damping_ahead;
    e.boundary_work -= now.boundary_ahead;
    e.capillary_work -= now.capillary_ahead;
    return e;
  }
  // No step since the balls last changed (or none yet): the state as it is.
  const Balls& b = model.balls;
  const auto& g = model.settings.gravity;
  for (std::size_t i = 0; i < b.size(); ++i) {
    e.kinetic_translation += 0.5 * b.mass[i] * (b.vx[i] * b.vx[i] + b.vy[i] * b.vy[i] + b.vz[i] * b.vz[i]);
    e.kinetic_rotation += 0.5 * b.inertia[i] * (b.wx[i] * b.wx[i] + b.wy[i] * b.wy[i] + b.wz[i] * b.wz[i]);
    e.potential -= b.mass[i] * (g[0] * b.x[i] + g[1] * b.y[i] + g[2] * b.z[i]);
  }
  const ContactTable& c = model.contacts;
  for (std::size_t p = 0; p < c.size(); ++p) {
    if (!c.touching(p)) continue;
    add_contact_strain(e.strain, is_hertz(model, c.i[p]), c.kn_eff[p], c.overlap[p], c.fsx[p], c.fsy[p], c.fsz[p],
                       c.ks_eff[p]);
    if (c.mrx.size() != c.size()) continue;   // (no rolling history: zero energy)
    const double ri = b.rad[c.i[p]], rj = b.rad[c.j[p]], rbar = ri * rj / (ri + rj);
    e.strain += shear_spring_energy(c.mrx[p] * c.mrx[p] + c.mry[p] * c.mry[p] + c.mrz[p] * c.mrz[p], c.ks_eff[p] * rbar * rbar);
  }
  const WallContacts& w = model.wall_contacts;
  if (w.kn_eff.size() == w.size() && w.overlap.size() == w.size())
    for (std::size_t p = 0; p < w.size(); ++p) {
      if (w.state[p] == 0 || w.ball[p] >= b.size()) continue;
      add_contact_strain(e.strain, is_hertz(model, w.ball[p]), w.kn_eff[p], w.overlap[p], w.fsx[p], w.fsy[p],
                         w.fsz[p], w.ks_eff[p]);
      const double r = b.rad[w.ball[p]];   // (Rbar of a ball on a wall: its radius)
      e.strain += shear_spring_energy(w.mrx[p] * w.mrx[p] + w.mry[p] * w.mry[p] + w.mrz[p] * w.mrz[p], w.ks_eff[p] * r * r);
    }
  const Bonds& bonds = model.bonds;
  for (std::size_t q : bond_rows_by_id(bonds))   // (by ids: the step keeps its own order)
    if (bonds.fate[q] == 0) e.strain += bond_strain_energy(bond_law(bonds, q), bond_state(bonds, q));
  return e;
}

std::size_t contact_count(const Model& model) {
  std::size_t n = 0;
  for (std::size_t p = 0; p < model.contacts.size(); ++p) n += model.contacts.touching(p);
  return n;
}

double coordination_number(const Model& model) { return contact_sums(model).coordination(model.balls.size()); }

double sliding_fraction(const Model& model) { return contact_sums(model).sliding_fraction(); }

Sym6 fabric_tensor(const Model& model) { return contact_sums(model).fabric_tensor(); }

Unbalanced unbalanced_force(const Model& model) { return contact_sums(model).unbalanced_ratio(); }

void ContactSums::add(const ContactSums& o) {
  for (int k = 0; k < 6; ++k) fabric[k].add(o.fabric[k]);
  contact_force.add(o.contact_force);
  unbalanced.add(o.unbalanced);
  unbalanced_max = std::max(unbalanced_max, o.unbalanced_max);
  touching += o.touching;
  sliding += o.sliding;
  contacts += o.contacts;
  free_balls += o.free_balls;
}

Sym6 ContactSums::fabric_tensor() const {
  Sym6 f;
  for (int k = 0; k < 6; ++k) f[k] = touching > 0 ? fabric[k].value() / touching : 0.0;
  return f;
}

double ContactSums::sliding_fraction() const { return touching > 0 ? sliding / touching : 0.0; }

Unbalanced ContactSums::unbalanced_ratio() const {
  Unbalanced u;
  const double sum = unbalanced.value(), contact_sum = contact_force.value();
  if (free_balls == 0 || sum == 0) return u;   // nothing free, or all in balance
  if (contacts == 0 || contact_sum == 0) {      // forces that no contact balances: SOLVE goes on
    u.mean_ratio = u.max_ratio = std::numeric_limits<double>::infinity();
    return u;
  }
  const double mean_contact = contact_sum / contacts;
  u.mean_ratio = sum / free_balls / mean_contact;
  u.max_ratio = unbalanced_max / mean_contact;
  return u;
}

ContactSums contact_sums(const Model& model, const std::vector<std::uint32_t>* pairs, const std::vector<std::uint32_t>* walls,
                         const std::vector<std::uint32_t>* balls) {
  ContactSums out;
  DyadSums fabric(out.fabric);
  ExactSum::Stream contact_force(out.contact_force), unbalanced(out.unbalanced);
  const ContactTable& c = model.contacts;
  const Balls& b = model.balls;
  each_row(pairs, c.size(), [&](std::size_t p) {
    if (p < c.state.size() && c.state[p] == 2) ++out.sliding;
    if (!c.touching(p)) return;
    fabric.add(c.nx[p], c.ny[p], c.nz[p], c.nx[p], c.ny[p], c.nz[p]);
    contact_force.add(std::sqrt(c.fx[p] * c.fx[p] + c.fy[p] * c.fy[p] + c.fz[p] * c.fz[p]));
    ++out.touching;
  });
  out.contacts = out.touching;
  const WallContacts& w = model.wall_contacts;   // a ball resting on a wall is balanced by it
  if (w.fx.size() == w.size())
    each_row(walls, w.size(), [&](std::size_t p) {
      if (w.state[p] == 0) return;
      contact_force.add(std::sqrt(w.fx[p] * w.fx[p] + w.fy[p] * w.fy[p] + w.fz[p] * w.fz[p]));
      ++out.contacts;
    });
  // Only free velocity components count: a fixed one's force is a reaction, not an imbalance.
  each_row(balls, b.size(), [&](std::size_t i) {
    if ((b.fixed[i] & kVel) == kVel) return;
    const double fx = (b.fixed[i] & kXVel) ? 0 : b.fx[i];
    const double fy = (b.fixed[i] & kYVel) ? 0 : b.fy[i];
    const double fz = (b.fixed[i] & kZVel) ? 0 : b.fz[i];
    const double f = std::sqrt(fx * fx + fy * fy + fz * fz);
    unbalanced.add(f);
    out.unbalanced_max = std::max(out.unbalanced_max, f);
    ++out.free_balls;
  });
  return out;
}

PlatenBalls platen_balls_of(const Model& model, const std::vector<std::size_t>& balls) {
  PlatenBalls p;
  const Balls& b = model.balls;
  for (std::size_t i : balls) {
    p.z.push_back(b.z[i]);
    p.fx.push_back(b.fx[i]);
    p.fy.push_back(b.fy[i]);
    p.fz.push_back(b.fz[i]);
  }
  return p;
}

std::array<double, 3> reaction_force(const Model& model, const std::vector<std::size_t>& balls) {
  return reaction_force(platen_balls_of(model, balls));
}

std::array<double, 3> reaction_force(const PlatenBalls& b) {
  std::array<double, 3> f{0, 0, 0};
  for (std::size_t i = 0; i < b.z.size(); ++i) {
    f[0] += b.fx[i];
    f[1] += b.fy[i];
    f[2] += b.fz[i];
  }
  return f;
}

Platens platens(const Model& model, const std::vector<std::size_t>& balls) {
  return platens(platen_balls_of(model, balls));
}

Platens platens(const PlatenBalls& b) {
  Platens out;
  const std::size_t n = b.z.size();
  if (n == 0) return out;
  double lo = b.z[0], hi = lo;
  for (std::size_t i = 0; i < n; ++i) lo = std::min(lo, b.z[i]), hi = std::max(hi, b.z[i]);
  const double mid = 0.5 * (lo + hi);
  double force_upper = 0, force_lower = 0, z_upper = 0, z_lower = 0;
  std::size_t upper = 0, lower = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (b.z[i] > mid) force_upper += b.fz[i], z_upper += b.z[i], ++upper;
    else force_lower += b.fz[i], z_lower += b.z[i], ++lower;
  }
  out.force = 0.5 * (force_upper - force_lower);
  out.two = upper > 0 && lower > 0 && hi > lo;
  if (out.two) out.gap = z_upper / static_cast<double>(upper) - z_lower / static_cast<double>(lower);
  return out;
}

}  // namespace trubal
