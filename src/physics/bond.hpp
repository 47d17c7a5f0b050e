// Parallel bonds (BOND; doc/physics.md "Parallel bonds"): the linear parallel bond of Potyondy and
// Cundall (2004, Int. J. Rock Mech. Min. Sci. 41:1329), a disc of cement of radius Rb = L min(Ri, Rj)
// between two balls, acting beside their contact law. It carries a normal force Fn (compression
// positive), a shear force Fs, a twisting moment Mt about the normal and a bending moment Mb, all
// built incrementally from the relative motion of the pair:
//   A = pi Rb^2,  I = pi Rb^4 / 4,  J = pi Rb^4 / 2,
//   dFn = -kn A dUn,  dFs = -ks A dUs,  dMt = -ks J dθn,  dMb = -kn I dθb,
// dU the relative displacement of j's contact point against i's over the step (dUn along the normal
// n from i to j, dUs the rest), dθ = (w_j - w_i) dt (dθn along n, dθb the rest); Fs and Mb are
// first turned onto the new contact plane at their old length. It breaks, for good, where
//   sigma = -Fn / A + mcf |Mb| Rb / I  >  T            (in tension; tested first)
//   tau   =  |Fs| / A + mcf |Mt| Rb / J  >  C - sigma_n tan(fa),  sigma_n = -Fn / A   (in shear).
// Forces and moments are those on ball j; ball i takes their opposites.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

#include "model/model.hpp"

namespace trubal {

// The parameters of one bond (Bonds' per-bond arrays).
struct BondLaw {
  double kn = 0, ks = 0;          // stiffness per unit area (stress per length)
  double tension = 0;             // T, tensile strength
  double cohesion = 0;            // C
  double tan_friction = 0;        // tan(fa)
  double radius = 0;              // Rb
  double mcf = 1;                 // moment contribution factor (0: moments do not load the bond)
};

// The cross-section of a bond of radius rb: area, second moment about a diameter, polar moment.
struct BondSection {
  double area, inertia, polar;
};
inline BondSection bond_section(double rb) {
  const double r2 = rb * rb;
  return {std::numbers::pi * r2, std::numbers::pi * r2 * r2 / 4, std::numbers::pi * r2 * r2 / 2};
}

// The state of one bond: forces and moments on ball j.
struct BondState {
  double fn = 0;                  // normal force, compression positive
  double fs[3] = {0, 0, 0};       // shear force, in the contact plane
  double mt = 0;                  // twisting moment about n
  double mb[3] = {0, 0, 0};       // bending moment, in the contact plane
};

// One step of the bond: Fs and Mb turned onto the plane normal to n (unit, i to j) at their old
// lengths, then the increments of the relative velocity v of j's contact point against i's and of
// the relative spin w = w_j - w_i over dt. (A batch of one: step_bonds's arithmetic.)
void bond_update(const BondLaw& law, BondState& s, const double n[3], const double v[3], const double w[3], double dt);

// The largest normal stress (tension positive) and shear stress on the bond's section.
struct BondStress {
  double sigma = 0, tau = 0;
  double sigma_n = 0;             // the mean normal stress -Fn / A (tension positive)
};
// The one arithmetic of the stresses (step_bonds, bond_stress): from Fn, |Fs|^2, Mt, |Mb|^2.
[[gnu::always_inline]] inline void bond_stresses(double rb, double mcf, double fn, double fs2, double mt, double mb2,
                                                 double& sigma_n, double& sigma, double& tau) {
  const double r2 = rb * rb, area = std::numbers::pi * r2, inertia = area * r2 / 4, polar = area * r2 / 2;
  sigma_n = -fn / area;
  sigma = sigma_n + mcf * std::sqrt(mb2) * rb / inertia;
  tau = std::sqrt(fs2) / area + mcf * std::abs(mt) * rb / polar;
}
BondStress bond_stress(const BondLaw& law, const BondState& s);

// Whether the bond holds: the codes Bonds::fate keeps.
enum class BondFate : std::uint8_t { Intact = 0, Tension = 1, Shear = 2 };
// The breakage rules on the state: tension first, then shear against C - sigma_n tan(fa).
BondFate bond_fate(const BondLaw& law, const BondState& s);
// The shear strength at this mean normal stress, C - sigma_n tan(fa) (may be negative in tension).
inline double bond_shear_strength(const BondLaw& law, double sigma_n) { return law.cohesion - sigma_n * law.tan_friction; }

// The energy the bond's springs hold: Fn^2 / (2 kn A) + |Fs|^2 / (2 ks A) + Mt^2 / (2 ks J) +
// |Mb|^2 / (2 kn I).
[[gnu::always_inline]] inline double bond_energy(double rb, double kn, double ks, double fn, double fs2, double mt,
                                                 double mb2) {
  const double r2 = rb * rb, area = std::numbers::pi * r2, inertia = area * r2 / 4, polar = area * r2 / 2;
  return fn * fn / (2 * kn * area) + fs2 / (2 * ks * area) + mt * mt / (2 * ks * polar) + mb2 / (2 * kn * inertia);
}
double bond_strain_energy(const BondLaw& law, const BondState& s);

// A batch of bonds stepped as one loop without branches (cycle/bond_pass.cpp gathers and scatters
// it), so that the compiler may make vector code of it; every lane is the same arithmetic, so the
// bits do not depend on which batch or lane a bond falls in.
struct BondBatch {
  static constexpr std::size_t kSize = 32;
  // In: x_j - x_i; v_j - v_i (the image's velocity included); R_i w_i + R_j w_j; w_j - w_i.
  alignas(64) double dx[kSize], dy[kSize], dz[kSize];
  alignas(64) double vx[kSize], vy[kSize], vz[kSize];
  alignas(64) double sx[kSize], sy[kSize], sz[kSize];
  alignas(64) double wx[kSize], wy[kSize], wz[kSize];
  // The law.
  alignas(64) double kn[kSize], ks[kSize], tension[kSize], cohesion[kSize], tan_friction[kSize], radius[kSize], mcf[kSize];
  // The state, in and out (BondState's).
  alignas(64) double fn[kSize], fsx[kSize], fsy[kSize], fsz[kSize], mt[kSize], mbx[kSize], mby[kSize], mbz[kSize];
  // Out: the unit normal, the fate (a BondFate's code), the strain energy of the new state (what a
  // breaking bond loses), and the push on j where it holds (0 where it broke): its force, n x Fs,
  // its moment Mt n + Mb.
  alignas(64) double nx[kSize], ny[kSize], nz[kSize], fate[kSize], energy[kSize];
  alignas(64) double fx[kSize], fy[kSize], fz[kSize], tx[kSize], ty[kSize], tz[kSize], mx[kSize], my[kSize], mz[kSize];
};
// Lanes [0, count) over dt: the relative velocity of j's contact point against i's, V = v - s x n
// (the contact law's), the increments, the breakage rules and the push.
void step_bonds(BondBatch& B, std::size_t count, double dt);

// A bond's share of its balls' stiffness sums for the time step (physics/timestep.hpp ball_omega2):
// kmax = max(kn A, ks A) as a contact's springs; ks = ks A plus the bending and twisting springs,
// which couple a ball's spin to its partner's as the rolling spring does, k_rot / Rmin^2 on either
// side counted at the spin row's share (kRollingSpinShare), k_rot = max(kn I, ks J).
struct BondStiffness {
  double kmax = 0, ks = 0;
};
BondStiffness bond_stiffness(const BondLaw& law, double ri, double rj);

// The bond's radius for two balls: L times the smaller radius (PFC's radius multiplier).
inline double bond_radius(double rmul, double ri, double rj) { return rmul * (ri < rj ? ri : rj); }

// The law and state of bond b of the table, and back.
BondLaw bond_law(const Bonds& bonds, std::size_t b);
BondState bond_state(const Bonds& bonds, std::size_t b);
void set_bond_state(Bonds& bonds, std::size_t b, const BondState& s);

// Counts over the table: intact, broken in tension, broken in shear.
struct BondCounts {
  std::size_t intact = 0, tension = 0, shear = 0;
  std::size_t broken() const { return tension + shear; }
};
BondCounts count_bonds(const Bonds& bonds);

}  // namespace trubal
