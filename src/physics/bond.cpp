#include "physics/bond.hpp"

#include <algorithm>

#include "physics/timestep.hpp"

namespace trubal {

namespace {

// v turned onto the plane normal to n at its old length (the shear spring's rule,
// physics/contact/tangential_spring.hpp): its projection, scaled back to |v|.
void turn_onto_plane(double v[3], const double n[3]) {
  const double old2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  if (!(old2 > 0)) return;
  const double along = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
  double p[3] = {v[0] - along * n[0], v[1] - along * n[1], v[2] - along * n[2]};
  const double new2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
  const double scale = new2 > 0 ? std::sqrt(old2 / new2) : 1.0;
  for (int a = 0; a < 3; ++a) v[a] = p[a] * scale;
}

double length(const double v[3]) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

}  // namespace

void bond_update(const BondLaw& law, BondState& s, const double n[3], const double v[3], const double w[3], double dt) {
  const BondSection sec = bond_section(law.radius);
  turn_onto_plane(s.fs, n);
  turn_onto_plane(s.mb, n);
  const double vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
  const double wn = w[0] * n[0] + w[1] * n[1] + w[2] * n[2];
  const double kn_a = law.kn * sec.area * dt, ks_a = law.ks * sec.area * dt;
  const double kn_i = law.kn * sec.inertia * dt, ks_j = law.ks * sec.polar * dt;
  s.fn -= kn_a * vn;
  s.mt -= ks_j * wn;
  for (int a = 0; a < 3; ++a) {
    s.fs[a] -= ks_a * (v[a] - vn * n[a]);
    s.mb[a] -= kn_i * (w[a] - wn * n[a]);
  }
}

BondStress bond_stress(const BondLaw& law, const BondState& s) {
  const BondSection sec = bond_section(law.radius);
  BondStress out;
  out.sigma_n = -s.fn / sec.area;
  out.sigma = out.sigma_n + law.mcf * length(s.mb) * law.radius / sec.inertia;
  out.tau = length(s.fs) / sec.area + law.mcf * std::abs(s.mt) * law.radius / sec.polar;
  return out;
}

BondFate bond_fate(const BondLaw& law, const BondState& s) {
  const BondStress st = bond_stress(law, s);
  if (st.sigma > law.tension) return BondFate::Tension;
  if (st.tau > bond_shear_strength(law, st.sigma_n)) return BondFate::Shear;
  return BondFate::Intact;
}

double bond_strain_energy(const BondLaw& law, const BondState& s) {
  const BondSection sec = bond_section(law.radius);
  const double fs2 = s.fs[0] * s.fs[0] + s.fs[1] * s.fs[1] + s.fs[2] * s.fs[2];
  const double mb2 = s.mb[0] * s.mb[0] + s.mb[1] * s.mb[1] + s.mb[2] * s.mb[2];
  const double kn = law.kn > 0 ? law.kn : 1.0, ks = law.ks > 0 ? law.ks : 1.0;   // (BOND asks for both > 0)
  return s.fn * s.fn / (2 * kn * sec.area) + fs2 / (2 * ks * sec.area) + s.mt * s.mt / (2 * ks * sec.polar) +
         mb2 / (2 * kn * sec.inertia);
}

BondStiffness bond_stiffness(const BondLaw& law, double ri, double rj) {
  const BondSection sec = bond_section(law.radius);
  const double kn = law.kn * sec.area, ks = law.ks * sec.area, rmin = std::min(ri, rj);
  return {std::max(kn, ks), ks + 2 * std::max(law.kn * sec.inertia, law.ks * sec.polar) / (rmin * rmin) * kRollingSpinShare};
}

BondLaw bond_law(const Bonds& b, std::size_t k) {
  return {b.kn[k], b.ks[k], b.tension[k], b.cohesion[k], b.tan_friction[k], b.radius[k], b.mcf[k]};
}

BondState bond_state(const Bonds& b, std::size_t k) {
  BondState s;
  s.fn = b.fn[k];
  s.fs[0] = b.fsx[k]; s.fs[1] = b.fsy[k]; s.fs[2] = b.fsz[k];
  s.mt = b.mt[k];
  s.mb[0] = b.mbx[k]; s.mb[1] = b.mby[k]; s.mb[2] = b.mbz[k];
  return s;
}

void set_bond_state(Bonds& b, std::size_t k, const BondState& s) {
  b.fn[k] = s.fn;
  b.fsx[k] = s.fs[0]; b.fsy[k] = s.fs[1]; b.fsz[k] = s.fs[2];
  b.mt[k] = s.mt;
  b.mbx[k] = s.mb[0]; b.mby[k] = s.mb[1]; b.mbz[k] = s.mb[2];
}

BondCounts count_bonds(const Bonds& b) {
  BondCounts c;
  for (std::uint8_t f : b.fate) {
    if (f == static_cast<std::uint8_t>(BondFate::Tension)) ++c.tension;
    else if (f == static_cast<std::uint8_t>(BondFate::Shear)) ++c.shear;
    else ++c.intact;
  }
  return c;
}

}  // namespace trubal
