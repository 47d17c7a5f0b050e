#include "cycle/bond_pass.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/edit.hpp"
#include "model/periodic_cell.hpp"
#include "physics/bond.hpp"

namespace trubal {

namespace {

constexpr std::uint32_t kNoBall = std::numeric_limits<std::uint32_t>::max();

// Whether the index in `scratch` is of this table and these balls: every bond's indices name its
// balls' ids (a cheap pass, so that no change of the table or the balls can leave it stale).
bool index_current(const Model& model, const StepScratch& scratch) {
  const Bonds& t = model.bonds;
  const Balls& b = model.balls;
  if (scratch.bond_ball_i.size() != t.size() || scratch.bond_run_begin.size() != b.size() + 1 ||
      scratch.bond_push.size() != t.size())
    return false;
  for (std::size_t q = 0; q < t.size(); ++q) {
    const std::uint32_t i = scratch.bond_ball_i[q], j = scratch.bond_ball_j[q];
    const bool i_ok = i == kNoBall ? find_ball(model, t.id_i[q]) < 0 : i < b.size() && b.id[i] == t.id_i[q];
    const bool j_ok = j == kNoBall ? find_ball(model, t.id_j[q]) < 0 : j < b.size() && b.id[j] == t.id_j[q];
    if (!i_ok || !j_ok) return false;
  }
  return true;
}

}  // namespace

bool has_intact_bonds(const Model& model) {
  return std::any_of(model.bonds.fate.begin(), model.bonds.fate.end(), [](std::uint8_t f) { return f == 0; });
}

void prepare_bonds(const Model& model, StepScratch& scratch) {
  if (index_current(model, scratch)) return;
  const Bonds& t = model.bonds;
  const std::size_t balls = model.balls.size(), bonds = t.size();
  scratch.bond_push.assign(bonds, BondPush{});
  scratch.bond_ball_i.resize(bonds);
  scratch.bond_ball_j.resize(bonds);
  // Each ball's bonds as i and as j, each a counting sort of the table by that ball, stable: as i in
  // ascending j, as j in ascending i (the table's order). A bond whose ball this model lacks (a
  // part's) is left out.
  for (std::size_t q = 0; q < bonds; ++q) {
    const std::int64_t i = find_ball(model, t.id_i[q]), j = find_ball(model, t.id_j[q]);
    scratch.bond_ball_i[q] = i < 0 || j < 0 ? kNoBall : static_cast<std::uint32_t>(i);
    scratch.bond_ball_j[q] = i < 0 || j < 0 ? kNoBall : static_cast<std::uint32_t>(j);
  }
  auto by_ball = [&](const std::vector<std::uint32_t>& ball, std::vector<std::uint32_t>& begin,
                     std::vector<std::uint32_t>& list) {
    begin.assign(balls + 1, 0);
    for (std::size_t q = 0; q < bonds; ++q)
      if (ball[q] != kNoBall) ++begin[ball[q] + 1];
    for (std::size_t b = 0; b < balls; ++b) begin[b + 1] += begin[b];
    std::vector<std::uint32_t> next(begin.begin(), begin.end() - 1);
    list.resize(begin[balls]);
    for (std::size_t q = 0; q < bonds; ++q)
      if (ball[q] != kNoBall) list[next[ball[q]]++] = static_cast<std::uint32_t>(q);
  };
  by_ball(scratch.bond_ball_i, scratch.bond_run_begin, scratch.bond_runs);
  by_ball(scratch.bond_ball_j, scratch.bond_partner_begin, scratch.bond_partners);
}

void bond_forces(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                 StepSums& sums) {
  Bonds& t = model.bonds;
  const Balls& b = model.balls;
  const bool periodic = model.space.periodic;
  const CellFrame cell = cell_frame(model.space);
  const bool cell_moving = periodic && cell.moving();
  const bool ghosts = !scratch.ghost.empty();
  ExactSum::Stream strain(sums.strain), lost(sums.bond_break);
  for (std::size_t q = begin; q < end; ++q) {
    BondPush& push = scratch.bond_push[q];
    push = BondPush{};
    const std::uint32_t i = scratch.bond_ball_i[q], j = scratch.bond_ball_j[q];
    if (t.fate[q] != 0 || i == kNoBall) continue;
    const bool owner = !(ghosts && scratch.ghost[i]);
    // x_j - x_i at j's nearest image, and the image's velocity where the cell moves.
    double dx = b.x[j] - b.x[i], dy = b.y[j] - b.y[i], dz = b.z[j] - b.z[i];
    double ivx = 0, ivy = 0, ivz = 0;
    if (periodic) {
      std::int8_t ix, iy, iz;
      nearest_image(cell, dx, dy, dz, ix, iy, iz);
      double ox, oy, oz;
      image_offset(cell, ix, iy, iz, ox, oy, oz);
      dx = image_delta(b.x[j], b.x[i], ox); dy = image_delta(b.y[j], b.y[i], oy); dz = image_delta(b.z[j], b.z[i], oz);
      if (cell_moving) image_velocity(cell, ix, iy, iz, ivx, ivy, ivz);
    }
    const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
    const double n[3] = {d > 0 ? dx / d : 0.0, d > 0 ? dy / d : 0.0, d > 0 ? dz / d : 1.0};
    // j's contact point against i's (the contact law's: V = v_j - v_i - (R_i w_i + R_j w_j) x n),
    // and the relative spin.
    const double ri = b.rad[i], rj = b.rad[j];
    const double sx = ri * b.wx[i] + rj * b.wx[j], sy = ri * b.wy[i] + rj * b.wy[j], sz = ri * b.wz[i] + rj * b.wz[j];
    const double v[3] = {b.vx[j] - b.vx[i] + ivx - (sy * n[2] - sz * n[1]), b.vy[j] - b.vy[i] + ivy - (sz * n[0] - sx * n[2]),
                         b.vz[j] - b.vz[i] + ivz - (sx * n[1] - sy * n[0])};
    const double w[3] = {b.wx[j] - b.wx[i], b.wy[j] - b.wy[i], b.wz[j] - b.wz[i]};
    const BondLaw law = bond_law(t, q);
    BondState s = bond_state(t, q);
    bond_update(law, s, n, v, w, k.dt_prev);
    set_bond_state(t, q, s);
    const BondFate fate = bond_fate(law, s);
    if (fate != BondFate::Intact) {
      t.fate[q] = static_cast<std::uint8_t>(fate);
      if (owner) lost.add(bond_strain_energy(law, s));
      continue;
    }
    if (owner) strain.add(bond_strain_energy(law, s));
    push.fx = s.fn * n[0] + s.fs[0]; push.fy = s.fn * n[1] + s.fs[1]; push.fz = s.fn * n[2] + s.fs[2];
    push.tx = n[1] * s.fs[2] - n[2] * s.fs[1];
    push.ty = n[2] * s.fs[0] - n[0] * s.fs[2];
    push.tz = n[0] * s.fs[1] - n[1] * s.fs[0];
    push.mx = s.mt * n[0] + s.mb[0]; push.my = s.mt * n[1] + s.mb[1]; push.mz = s.mt * n[2] + s.mb[2];
    if (k.sums_stiffness()) {
      const BondStiffness stiff = bond_stiffness(law, ri, rj);
      push.kmax = stiff.kmax;
      push.ks = stiff.ks;
    }
    if (!owner) continue;
    if (cell_moving) sums.image_power.add(-(push.fx * ivx + push.fy * ivy + push.fz * ivz));
    if (k.moments) {   // the force on j times the branch vector i -> j, and kn A l_a^2
      sums.force_moment[0].add(push.fx * dx); sums.force_moment[1].add(push.fy * dy); sums.force_moment[2].add(push.fz * dz);
      sums.force_moment[3].add(0.5 * (push.fx * dy + push.fy * dx));
      sums.force_moment[4].add(0.5 * (push.fx * dz + push.fz * dx));
      sums.force_moment[5].add(0.5 * (push.fy * dz + push.fz * dy));
      const double kn = law.kn * bond_section(law.radius).area;
      sums.stiffness_moment[0].add(kn * dx * dx); sums.stiffness_moment[1].add(kn * dy * dy);
      sums.stiffness_moment[2].add(kn * dz * dz);
    }
  }
}

void add_bonds(const Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end) {
  const Balls& b = model.balls;
  const bool stiffness = k.sums_stiffness();
  for (std::size_t i = begin; i < end; ++i) {
    PairForce sum{};
    const double inv_r = 1.0 / b.rad[i];
    for (std::size_t q = scratch.bond_partner_begin[i]; q < scratch.bond_partner_begin[i + 1]; ++q) {   // as j
      const BondPush& p = scratch.bond_push[scratch.bond_partners[q]];
      sum.fx += p.fx; sum.fy += p.fy; sum.fz += p.fz;
      sum.tx += p.tx - p.mx * inv_r; sum.ty += p.ty - p.my * inv_r; sum.tz += p.tz - p.mz * inv_r;
      sum.kmax += p.kmax; sum.ks += p.ks;
    }
    for (std::size_t q = scratch.bond_run_begin[i]; q < scratch.bond_run_begin[i + 1]; ++q) {   // as i
      const BondPush& p = scratch.bond_push[scratch.bond_runs[q]];
      sum.fx -= p.fx; sum.fy -= p.fy; sum.fz -= p.fz;
      sum.tx += p.tx + p.mx * inv_r; sum.ty += p.ty + p.my * inv_r; sum.tz += p.tz + p.mz * inv_r;
      sum.kmax += p.kmax; sum.ks += p.ks;
    }
    PairForce& total = scratch.ball_force[i];
    total.fx += sum.fx; total.fy += sum.fy; total.fz += sum.fz;
    total.tx += sum.tx; total.ty += sum.ty; total.tz += sum.tz;
    if (stiffness) { total.kmax += sum.kmax; total.ks += sum.ks; }
  }
}

}  // namespace trubal
