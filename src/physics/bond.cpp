#include "physics/bond.hpp"

#include <algorithm>

#include "physics/timestep.hpp"

namespace trubal {

void step_bonds(BondBatch& B, std::size_t count, double dt) {
  for (std::size_t q = 0; q < count; ++q) {
    const double dx = B.dx[q], dy = B.dy[q], dz = B.dz[q];
    const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
    // (Coincident centres have no direction: +z, as the contact law takes.)
    const double inv_d = d > 0 ? 1.0 / (d > 0 ? d : 1.0) : 0.0;
    const double nx = dx * inv_d, ny = dy * inv_d, nz = d > 0 ? dz * inv_d : 1.0;
    // j's contact point against i's, V = v_j - v_i - (R_i w_i + R_j w_j) x n, and the relative spin.
    const double sx = B.sx[q], sy = B.sy[q], sz = B.sz[q];
    const double vx = B.vx[q] - (sy * nz - sz * ny), vy = B.vy[q] - (sz * nx - sx * nz), vz = B.vz[q] - (sx * ny - sy * nx);
    const double wx = B.wx[q], wy = B.wy[q], wz = B.wz[q];
    const double vn = vx * nx + vy * ny + vz * nz, wn = wx * nx + wy * ny + wz * nz;
    const double rb = B.radius[q], r2 = rb * rb, area = std::numbers::pi * r2;
    const double inertia = area * r2 / 4, polar = area * r2 / 2;
    const double kn = B.kn[q], ks = B.ks[q];
    // Fs and Mb turned onto the new plane at their old lengths (the shear spring's rule,
    // physics/contact/tangential_spring.hpp): the projection, scaled back. (x * 1.0 is x.)
    auto turn = [&](double& ax, double& ay, double& az) {
      const double old2 = ax * ax + ay * ay + az * az, along = ax * nx + ay * ny + az * nz;
      const double px = ax - along * nx, py = ay - along * ny, pz = az - along * nz;
      const double new2 = px * px + py * py + pz * pz;
      const bool turned = old2 > 0, rescale = turned && new2 > 0;
      const double scale = rescale ? std::sqrt(old2 / (rescale ? new2 : 1.0)) : 1.0;
      ax = turned ? px * scale : ax;
      ay = turned ? py * scale : ay;
      az = turned ? pz * scale : az;
    };
    double fsx = B.fsx[q], fsy = B.fsy[q], fsz = B.fsz[q], mbx = B.mbx[q], mby = B.mby[q], mbz = B.mbz[q];
    turn(fsx, fsy, fsz);
    turn(mbx, mby, mbz);
    const double kn_a = kn * area * dt, ks_a = ks * area * dt, kn_i = kn * inertia * dt, ks_j = ks * polar * dt;
    const double fn = B.fn[q] - kn_a * vn, mt = B.mt[q] - ks_j * wn;
    fsx -= ks_a * (vx - vn * nx); fsy -= ks_a * (vy - vn * ny); fsz -= ks_a * (vz - vn * nz);
    mbx -= kn_i * (wx - wn * nx); mby -= kn_i * (wy - wn * ny); mbz -= kn_i * (wz - wn * nz);
    const double fs2 = fsx * fsx + fsy * fsy + fsz * fsz, mb2 = mbx * mbx + mby * mby + mbz * mbz;
    double sigma_n, sigma, tau;
    bond_stresses(rb, B.mcf[q], fn, fs2, mt, mb2, sigma_n, sigma, tau);
    const bool tension = sigma > B.tension[q];
    const bool shear = !tension && tau > B.cohesion[q] - sigma_n * B.tan_friction[q];
    B.fn[q] = fn; B.mt[q] = mt;
    B.fsx[q] = fsx; B.fsy[q] = fsy; B.fsz[q] = fsz;
    B.mbx[q] = mbx; B.mby[q] = mby; B.mbz[q] = mbz;
    B.nx[q] = nx; B.ny[q] = ny; B.nz[q] = nz;
    B.fate[q] = tension ? 1.0 : (shear ? 2.0 : 0.0);
    B.energy[q] = bond_energy(rb, kn, ks, fn, fs2, mt, mb2);
  }
  // The push on j where the bond holds (a loop of its own: g++ leaves one loop of all of it scalar).
  for (std::size_t q = 0; q < count; ++q) {
    const bool holds = B.fate[q] == 0;
    const double nx = B.nx[q], ny = B.ny[q], nz = B.nz[q], fsx = B.fsx[q], fsy = B.fsy[q], fsz = B.fsz[q];
    B.fx[q] = holds ? B.fn[q] * nx + fsx : 0.0;
    B.fy[q] = holds ? B.fn[q] * ny + fsy : 0.0;
    B.fz[q] = holds ? B.fn[q] * nz + fsz : 0.0;
    B.tx[q] = holds ? ny * fsz - nz * fsy : 0.0;
    B.ty[q] = holds ? nz * fsx - nx * fsz : 0.0;
    B.tz[q] = holds ? nx * fsy - ny * fsx : 0.0;
    B.mx[q] = holds ? B.mt[q] * nx + B.mbx[q] : 0.0;
    B.my[q] = holds ? B.mt[q] * ny + B.mby[q] : 0.0;
    B.mz[q] = holds ? B.mt[q] * nz + B.mbz[q] : 0.0;
  }
}

void bond_update(const BondLaw& law, BondState& s, const double n[3], const double v[3], const double w[3], double dt) {
  // A batch of one whose normal is n (unit separation) and whose spins make no contact-point velocity.
  BondBatch B;
  B.dx[0] = n[0]; B.dy[0] = n[1]; B.dz[0] = n[2];
  B.vx[0] = v[0]; B.vy[0] = v[1]; B.vz[0] = v[2];
  B.sx[0] = B.sy[0] = B.sz[0] = 0;
  B.wx[0] = w[0]; B.wy[0] = w[1]; B.wz[0] = w[2];
  B.kn[0] = law.kn; B.ks[0] = law.ks; B.tension[0] = law.tension; B.cohesion[0] = law.cohesion;
  B.tan_friction[0] = law.tan_friction; B.radius[0] = law.radius; B.mcf[0] = law.mcf;
  B.fn[0] = s.fn; B.fsx[0] = s.fs[0]; B.fsy[0] = s.fs[1]; B.fsz[0] = s.fs[2];
  B.mt[0] = s.mt; B.mbx[0] = s.mb[0]; B.mby[0] = s.mb[1]; B.mbz[0] = s.mb[2];
  step_bonds(B, 1, dt);
  s.fn = B.fn[0]; s.fs[0] = B.fsx[0]; s.fs[1] = B.fsy[0]; s.fs[2] = B.fsz[0];
  s.mt = B.mt[0]; s.mb[0] = B.mbx[0]; s.mb[1] = B.mby[0]; s.mb[2] = B.mbz[0];
}

BondStress bond_stress(const BondLaw& law, const BondState& s) {
  BondStress out;
  bond_stresses(law.radius, law.mcf, s.fn, s.fs[0] * s.fs[0] + s.fs[1] * s.fs[1] + s.fs[2] * s.fs[2], s.mt,
                s.mb[0] * s.mb[0] + s.mb[1] * s.mb[1] + s.mb[2] * s.mb[2], out.sigma_n, out.sigma, out.tau);
  return out;
}

BondFate bond_fate(const BondLaw& law, const BondState& s) {
  const BondStress st = bond_stress(law, s);
  if (st.sigma > law.tension) return BondFate::Tension;
  if (st.tau > bond_shear_strength(law, st.sigma_n)) return BondFate::Shear;
  return BondFate::Intact;
}

double bond_strain_energy(const BondLaw& law, const BondState& s) {
  const double kn = law.kn > 0 ? law.kn : 1.0, ks = law.ks > 0 ? law.ks : 1.0;   // (BOND asks for both > 0)
  return bond_energy(law.radius, kn, ks, s.fn, s.fs[0] * s.fs[0] + s.fs[1] * s.fs[1] + s.fs[2] * s.fs[2], s.mt,
                     s.mb[0] * s.mb[0] + s.mb[1] * s.mb[1] + s.mb[2] * s.mb[2]);
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
