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

// Whether the index in `scratch` is of this table and these balls: made for the pair list now (every
// change of the balls or the table between steps goes through Session::edit, which has the next
// step search afresh, a new list), of the same sizes, its first and last bonds naming their balls.
bool index_current(const Model& model, const StepScratch& scratch) {
  const Bonds& t = model.bonds;
  const Balls& b = model.balls;
  if (scratch.bond_version == 0 || scratch.bond_version != model.contacts.list_version ||
      scratch.bond_ball_i.size() != t.size() || scratch.bond_run_begin.size() != b.size() + 1 ||
      scratch.bond_push.size() != t.size() || scratch.bond_stiffness.size() != t.size())
    return false;
  for (std::size_t q : {std::size_t{0}, t.size() - 1}) {
    if (q >= t.size()) continue;
    const std::uint32_t i = scratch.bond_ball_i[q], j = scratch.bond_ball_j[q];
    if (i != kNoBall && (i >= b.size() || j >= b.size() || b.id[i] != t.id_i[q] || b.id[j] != t.id_j[q])) return false;
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
  // Each bond's share of its balls' stiffness sums (constant: its law and its balls' radii).
  scratch.bond_stiffness.resize(bonds);
  for (std::size_t q = 0; q < bonds; ++q)
    scratch.bond_stiffness[q] = scratch.bond_ball_i[q] == kNoBall
                                    ? BondStiffness{}
                                    : bond_stiffness(bond_law(t, q), model.balls.rad[scratch.bond_ball_i[q]],
                                                     model.balls.rad[scratch.bond_ball_j[q]]);
  by_ball(scratch.bond_ball_i, scratch.bond_run_begin, scratch.bond_runs);
  by_ball(scratch.bond_ball_j, scratch.bond_partner_begin, scratch.bond_partners);
  scratch.bond_version = model.contacts.list_version;
}

void bond_forces(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                 StepSums& sums) {
  Bonds& t = model.bonds;
  const Balls& b = model.balls;
  const bool periodic = model.space.periodic;
  const CellFrame cell = cell_frame(model.space);
  const bool cell_moving = periodic && cell.moving();
  const bool ghosts = !scratch.ghost.empty();
  const bool stiffness = k.sums_stiffness();
  ExactSum::Stream strain(sums.strain), lost(sums.bond_break);
  BondBatch B;
  std::uint32_t lane_bond[BondBatch::kSize];
  double ivx[BondBatch::kSize], ivy[BondBatch::kSize], ivz[BondBatch::kSize];
  std::size_t count = 0;
  // The batch's bonds stepped (physics/bond.hpp step_bonds), their state and push written back.
  double held[BondBatch::kSize], freed[BondBatch::kSize];
  auto flush = [&] {
    step_bonds(B, count, k.dt_prev);
    for (std::size_t q = 0; q < count; ++q) {   // the energies, the owners' only: the exact sums a batch at a time
      const bool owner = !(ghosts && scratch.ghost[scratch.bond_ball_i[lane_bond[q]]]);
      held[q] = owner && B.fate[q] == 0 ? B.energy[q] : 0.0;
      freed[q] = owner && B.fate[q] != 0 ? B.energy[q] : 0.0;
    }
    strain.add_block(held, count);
    lost.add_block(freed, count);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t bond = lane_bond[q];
      const std::uint32_t i = scratch.bond_ball_i[bond];
      t.fn[bond] = B.fn[q]; t.mt[bond] = B.mt[q];
      t.fsx[bond] = B.fsx[q]; t.fsy[bond] = B.fsy[q]; t.fsz[bond] = B.fsz[q];
      t.mbx[bond] = B.mbx[q]; t.mby[bond] = B.mby[q]; t.mbz[bond] = B.mbz[q];
      const bool owner = !(ghosts && scratch.ghost[i]);
      BondPush& push = scratch.bond_push[bond];
      if (B.fate[q] != 0) {   // broken: gone for good, its energy lost
        t.fate[bond] = static_cast<std::uint8_t>(B.fate[q]);
        continue;
      }
      push.fx = B.fx[q]; push.fy = B.fy[q]; push.fz = B.fz[q];
      push.tx = B.tx[q]; push.ty = B.ty[q]; push.tz = B.tz[q];
      push.mx = B.mx[q]; push.my = B.my[q]; push.mz = B.mz[q];
      if (stiffness) {
        push.kmax = scratch.bond_stiffness[bond].kmax;
        push.ks = scratch.bond_stiffness[bond].ks;
      }
      if (!owner) continue;
      if (cell_moving) sums.image_power.add(-(push.fx * ivx[q] + push.fy * ivy[q] + push.fz * ivz[q]));
      if (k.moments) {   // the force on j times the branch vector i -> j, and kn A l_a^2
        const double dx = B.dx[q], dy = B.dy[q], dz = B.dz[q];
        sums.force_moment[0].add(push.fx * dx); sums.force_moment[1].add(push.fy * dy); sums.force_moment[2].add(push.fz * dz);
        sums.force_moment[3].add(0.5 * (push.fx * dy + push.fy * dx));
        sums.force_moment[4].add(0.5 * (push.fx * dz + push.fz * dx));
        sums.force_moment[5].add(0.5 * (push.fy * dz + push.fz * dy));
        const double kn = t.kn[bond] * bond_section(t.radius[bond]).area;
        sums.stiffness_moment[0].add(kn * dx * dx); sums.stiffness_moment[1].add(kn * dy * dy);
        sums.stiffness_moment[2].add(kn * dz * dz);
      }
    }
    count = 0;
  };
  for (std::size_t q = begin; q < end; ++q) {
    scratch.bond_push[q] = BondPush{};
    const std::uint32_t i = scratch.bond_ball_i[q], j = scratch.bond_ball_j[q];
    if (t.fate[q] != 0 || i == kNoBall) continue;
    // x_j - x_i at j's nearest image, and the image's velocity where the cell moves.
    std::int8_t ix, iy, iz;
    const auto [dx, dy, dz] = nearest_separation(cell, periodic, b, i, j, ix, iy, iz);
    double ux = 0, uy = 0, uz = 0;
    if (cell_moving) image_velocity(cell, ix, iy, iz, ux, uy, uz);
    const std::size_t l = count++;
    lane_bond[l] = static_cast<std::uint32_t>(q);
    ivx[l] = ux; ivy[l] = uy; ivz[l] = uz;
    B.dx[l] = dx; B.dy[l] = dy; B.dz[l] = dz;
    B.vx[l] = b.vx[j] - b.vx[i] + ux; B.vy[l] = b.vy[j] - b.vy[i] + uy; B.vz[l] = b.vz[j] - b.vz[i] + uz;
    const double ri = b.rad[i], rj = b.rad[j];
    B.sx[l] = ri * b.wx[i] + rj * b.wx[j]; B.sy[l] = ri * b.wy[i] + rj * b.wy[j]; B.sz[l] = ri * b.wz[i] + rj * b.wz[j];
    B.wx[l] = b.wx[j] - b.wx[i]; B.wy[l] = b.wy[j] - b.wy[i]; B.wz[l] = b.wz[j] - b.wz[i];
    B.kn[l] = t.kn[q]; B.ks[l] = t.ks[q]; B.tension[l] = t.tension[q]; B.cohesion[l] = t.cohesion[q];
    B.tan_friction[l] = t.tan_friction[q]; B.radius[l] = t.radius[q]; B.mcf[l] = t.mcf[q];
    B.fn[l] = t.fn[q]; B.fsx[l] = t.fsx[q]; B.fsy[l] = t.fsy[q]; B.fsz[l] = t.fsz[q];
    B.mt[l] = t.mt[q]; B.mbx[l] = t.mbx[q]; B.mby[l] = t.mby[q]; B.mbz[l] = t.mbz[q];
    if (count == BondBatch::kSize) flush();
  }
  if (count) flush();
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
