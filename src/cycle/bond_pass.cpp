#include "cycle/bond_pass.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <span>
#include <utility>

#include "model/bond_table.hpp"
#include "model/edit.hpp"
#include "model/periodic_cell.hpp"
#include "physics/bond.hpp"

namespace trubal {

namespace {

constexpr std::uint32_t kNoBall = std::numeric_limits<std::uint32_t>::max();

// Whether the index in `scratch` is of this table and these balls: made for the pair list now (every
// change of the balls or the table between steps goes through Session::edit, which has the next
// step search afresh, a new list) and for the table's edition now (Bonds::edition: any edit of its
// rows, a copy restored over it as where a step is taken again), its first and last bonds naming
// their balls. (Bonds that broke since the index was made are known to it: bond_holds.)
bool index_current(const Model& model, const StepScratch& scratch) {
  const Bonds& t = model.bonds;
  const Balls& b = model.balls;
  if (scratch.bond_version == 0 || scratch.bond_version != model.contacts.list_version ||
      scratch.bond_edition != t.edition.value() || scratch.bond_run_begin.size() != b.size() + 1)
    return false;
  const std::size_t places = scratch.bond_ball_i.size();
  for (std::size_t q : {std::size_t{0}, places - 1}) {
    if (q >= places) continue;
    const std::uint32_t i = scratch.bond_ball_i[q], j = scratch.bond_ball_j[q];
    if (q >= t.size() || i >= b.size() || j >= b.size() || b.id[i] != t.id_i[q] || b.id[j] != t.id_j[q]) return false;
  }
  return true;
}

// A ball's share of the stiffness sums: its intact bonds' as partner j, then as i, in that order.
BondStiffness ball_stiffness(const StepScratch& s, std::size_t ball) {
  BondStiffness sum;
  auto add = [&](const std::vector<std::uint32_t>& begin, const std::vector<std::uint32_t>& list) {
    for (std::size_t q = begin[ball]; q < begin[ball + 1]; ++q)
      if (s.bond_holds[list[q]]) { sum.kmax += s.bond_stiffness[list[q]].kmax; sum.ks += s.bond_stiffness[list[q]].ks; }
  };
  add(s.bond_partner_begin, s.bond_partners);
  add(s.bond_run_begin, s.bond_runs);
  return sum;
}

}  // namespace

void prepare_bonds(Model& model, StepScratch& scratch, int shares) {
  scratch.bond_broken.resize(static_cast<std::size_t>(std::max(shares, 1)));
  if (index_current(model, scratch)) return;
  Bonds& t = model.bonds;
  const Balls& b = model.balls;
  const std::size_t balls = b.size(), rows = t.size();
  // The table's rows in the step's order: the intact bonds whose balls this model has (a part's may
  // lack one) by ball i's place in memory, then j's; then the others by their ids.
  std::vector<std::uint32_t> ball_i(rows, kNoBall), ball_j(rows, kNoBall);
  std::vector<std::size_t> order;
  order.reserve(rows);
  for (std::size_t r = 0; r < rows; ++r) {
    if (t.fate[r] != 0) continue;
    const std::int64_t i = find_ball(model, t.id_i[r]), j = find_ball(model, t.id_j[r]);
    if (i < 0 || j < 0) continue;
    ball_i[r] = static_cast<std::uint32_t>(i);
    ball_j[r] = static_cast<std::uint32_t>(j);
    order.push_back(r);
  }
  const std::size_t places = order.size();
  auto by_balls = [&](std::size_t p, std::size_t q) { return ball_i[p] != ball_i[q] ? ball_i[p] < ball_i[q] : ball_j[p] < ball_j[q]; };
  std::sort(order.begin(), order.end(), by_balls);
  for (std::size_t r : bond_rows_by_id(t))
    if (ball_i[r] == kNoBall) order.push_back(r);
  bool moved = false;
  for (std::size_t k = 0; k < rows && !moved; ++k) moved = order[k] != k;
  if (moved)   // (the rows as the balls' order left them where it did not change)
    t.for_each_array([&](auto& v) {
      std::decay_t<decltype(v)> out(rows);
      for (std::size_t k = 0; k < rows; ++k) out[k] = v[order[k]];
      v.swap(out);
    });
  scratch.bond_ball_i.resize(places);
  scratch.bond_ball_j.resize(places);
  scratch.bond_stiffness.resize(places);
  for (std::size_t q = 0; q < places; ++q) {
    const std::uint32_t i = ball_i[order[q]], j = ball_j[order[q]];
    scratch.bond_ball_i[q] = i;
    scratch.bond_ball_j[q] = j;
    // (constant: its law and its balls' radii)
    scratch.bond_stiffness[q] = bond_stiffness(bond_law(t, q), b.rad[i], b.rad[j]);
  }
  // The laws but the radius, each once (BOND gives one to all the bonds it makes): a small table the
  // gather reads from the cache, not six arrays of the bonds' length from memory.
  std::map<BondLawRow, std::uint32_t> known;
  scratch.bond_laws.clear();
  scratch.bond_law_of.resize(places);
  for (std::size_t q = 0; q < places; ++q) {
    const BondLawRow law = {t.kn[q], t.ks[q], t.tension[q], t.cohesion[q], t.tan_friction[q], t.mcf[q]};
    const auto [at, made] = known.try_emplace(law, static_cast<std::uint32_t>(scratch.bond_laws.size()));
    if (made) scratch.bond_laws.push_back(law);
    scratch.bond_law_of[q] = at->second;
  }
  scratch.bond_holds.assign(places, 1);
  scratch.bond_push.assign(places, BondPush{});
  // Each ball's bonds as i and as j, each a counting sort by that ball of the rows by their ids: as
  // i in ascending j, as j in ascending i.
  const std::vector<std::size_t> by_id = bond_rows_by_id(t);
  auto by_ball = [&](const std::vector<std::uint32_t>& ball, std::vector<std::uint32_t>& begin,
                     std::vector<std::uint32_t>& list) {
    begin.assign(balls + 1, 0);
    for (std::size_t q = 0; q < places; ++q) ++begin[ball[q] + 1];
    for (std::size_t k = 0; k < balls; ++k) begin[k + 1] += begin[k];
    std::vector<std::uint32_t> next(begin.begin(), begin.end() - 1);
    list.resize(places);
    for (std::size_t q : by_id)
      if (q < places) list[next[ball[q]]++] = static_cast<std::uint32_t>(q);
  };
  by_ball(scratch.bond_ball_i, scratch.bond_run_begin, scratch.bond_runs);
  by_ball(scratch.bond_ball_j, scratch.bond_partner_begin, scratch.bond_partners);
  scratch.ball_bond_stiffness.resize(balls);
  for (std::size_t k = 0; k < balls; ++k) scratch.ball_bond_stiffness[k] = ball_stiffness(scratch, k);
  scratch.bond_edition = t.edition.value();
  scratch.bond_version = model.contacts.list_version;
}

void bond_forces(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                 StepSums& sums, int share) {
  Bonds& t = model.bonds;
  const Balls& b = model.balls;
  const bool periodic = model.space.periodic;
  const CellFrame cell = cell_frame(model.space);
  const bool cell_moving = periodic && cell.moving();
  const bool ghosts = !scratch.ghost.empty();
  std::vector<std::uint32_t>& broken = scratch.bond_broken[static_cast<std::size_t>(share)];
  broken.clear();
  ExactSum::Stream strain(sums.strain), lost(sums.bond_break);
  BondBatch B;
  std::uint32_t lane_place[BondBatch::kSize];
  double ivx[BondBatch::kSize], ivy[BondBatch::kSize], ivz[BondBatch::kSize];
  double inv_ri[BondBatch::kSize], inv_rj[BondBatch::kSize];
  std::size_t count = 0;
  // The batch's bonds stepped (physics/bond.hpp step_bonds), their state and push written back.
  double held[BondBatch::kSize], freed[BondBatch::kSize];
  // The table's arrays of the bonds' radius and state beside the batch's: a batch of places one
  // after another (no bond broken between them) is read and written as blocks.
  const std::pair<double*, double*> state[] = {{t.fn.data(), B.fn}, {t.fsx.data(), B.fsx}, {t.fsy.data(), B.fsy},
                                               {t.fsz.data(), B.fsz}, {t.mt.data(), B.mt}, {t.mbx.data(), B.mbx},
                                               {t.mby.data(), B.mby}, {t.mbz.data(), B.mbz}};
  const std::pair<double*, double*> radius[] = {{t.radius.data(), B.radius}};
  auto flush = [&] {
    const std::size_t first = lane_place[0];
    const bool block = count == BondBatch::kSize && lane_place[count - 1] - first + 1 == count;   // (copies of a known size)
    using Arrays = std::span<const std::pair<double*, double*>>;
    for (const Arrays rows : {Arrays(radius), Arrays(state)})
      for (const auto& [table, batch] : rows)
        if (block) std::memcpy(batch, table + first, sizeof(double) * BondBatch::kSize);
        else for (std::size_t q = 0; q < count; ++q) batch[q] = table[lane_place[q]];
    step_bonds(B, count, k.dt_prev);
    for (const auto& [table, batch] : state)
      if (block) std::memcpy(table + first, batch, sizeof(double) * BondBatch::kSize);
      else for (std::size_t q = 0; q < count; ++q) table[lane_place[q]] = batch[q];
    for (std::size_t q = 0; q < count; ++q) {   // the energies, the owners' only: the exact sums a batch at a time
      const bool owner = !(ghosts && scratch.ghost[scratch.bond_ball_i[lane_place[q]]]);
      held[q] = owner && B.fate[q] == 0 ? B.energy[q] : 0.0;
      freed[q] = owner && B.fate[q] != 0 ? B.energy[q] : 0.0;
    }
    if (k.energies) strain.add_block(held, count);   // (the energy at t: where the step forms it)
    lost.add_block(freed, count);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t at = lane_place[q];   // (the place is the table's row)
      BondPush& push = scratch.bond_push[at];
      if (B.fate[q] != 0) {   // broken: gone for good, its energy lost
        t.fate[at] = static_cast<std::uint8_t>(B.fate[q]);
        scratch.bond_holds[at] = 0;
        push = BondPush{};
        broken.push_back(static_cast<std::uint32_t>(at));
        continue;
      }
      push.fx = B.fx[q]; push.fy = B.fy[q]; push.fz = B.fz[q];
      push.tjx = B.tx[q] - B.mx[q] * inv_rj[q]; push.tjy = B.ty[q] - B.my[q] * inv_rj[q]; push.tjz = B.tz[q] - B.mz[q] * inv_rj[q];
      push.tix = B.tx[q] + B.mx[q] * inv_ri[q]; push.tiy = B.ty[q] + B.my[q] * inv_ri[q]; push.tiz = B.tz[q] + B.mz[q] * inv_ri[q];
      if (ghosts && scratch.ghost[scratch.bond_ball_i[at]]) continue;
      if (cell_moving) sums.image_power.add(-(push.fx * ivx[q] + push.fy * ivy[q] + push.fz * ivz[q]));
      if (k.moments) {   // the force on j times the branch vector i -> j, and kn A l_a^2
        const double dx = B.dx[q], dy = B.dy[q], dz = B.dz[q];
        sums.force_moment[0].add(push.fx * dx); sums.force_moment[1].add(push.fy * dy); sums.force_moment[2].add(push.fz * dz);
        sums.force_moment[3].add(0.5 * (push.fx * dy + push.fy * dx));
        sums.force_moment[4].add(0.5 * (push.fx * dz + push.fz * dx));
        sums.force_moment[5].add(0.5 * (push.fy * dz + push.fz * dy));
        const double kn = t.kn[at] * bond_section(t.radius[at]).area;
        sums.stiffness_moment[0].add(kn * dx * dx); sums.stiffness_moment[1].add(kn * dy * dy);
        sums.stiffness_moment[2].add(kn * dz * dz);
      }
    }
    count = 0;
  };
  for (std::size_t q = begin; q < end; ++q) {
    if (!scratch.bond_holds[q]) continue;
    const std::uint32_t i = scratch.bond_ball_i[q], j = scratch.bond_ball_j[q];
    // x_j - x_i at j's nearest image, and the image's velocity where the cell moves.
    std::int8_t ix, iy, iz;
    const auto [dx, dy, dz] = nearest_separation(cell, periodic, b, i, j, ix, iy, iz);
    double ux = 0, uy = 0, uz = 0;
    if (cell_moving) image_velocity(cell, ix, iy, iz, ux, uy, uz);
    const std::size_t l = count++;
    lane_place[l] = static_cast<std::uint32_t>(q);
    ivx[l] = ux; ivy[l] = uy; ivz[l] = uz;
    B.dx[l] = dx; B.dy[l] = dy; B.dz[l] = dz;
    B.vx[l] = b.vx[j] - b.vx[i] + ux; B.vy[l] = b.vy[j] - b.vy[i] + uy; B.vz[l] = b.vz[j] - b.vz[i] + uz;
    const double ri = b.rad[i], rj = b.rad[j];
    inv_ri[l] = 1.0 / ri; inv_rj[l] = 1.0 / rj;
    B.sx[l] = ri * b.wx[i] + rj * b.wx[j]; B.sy[l] = ri * b.wy[i] + rj * b.wy[j]; B.sz[l] = ri * b.wz[i] + rj * b.wz[j];
    B.wx[l] = b.wx[j] - b.wx[i]; B.wy[l] = b.wy[j] - b.wy[i]; B.wz[l] = b.wz[j] - b.wz[i];
    const BondLawRow& law = scratch.bond_laws[scratch.bond_law_of[q]];
    B.kn[l] = law[0]; B.ks[l] = law[1]; B.tension[l] = law[2]; B.cohesion[l] = law[3]; B.tan_friction[l] = law[4];
    B.mcf[l] = law[5];
    if (count == BondBatch::kSize) flush();
  }
  if (count) flush();
}

void settle_broken_bonds(StepScratch& scratch) {
  for (const std::vector<std::uint32_t>& list : scratch.bond_broken)
    for (std::uint32_t at : list) {
      for (std::uint32_t ball : {scratch.bond_ball_i[at], scratch.bond_ball_j[at]})
        scratch.ball_bond_stiffness[ball] = ball_stiffness(scratch, ball);
    }
}

void add_bonds(StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end) {
  const bool stiffness = k.sums_stiffness();
  const BondPush* pushes = scratch.bond_push.data();
  for (std::size_t i = begin; i < end; ++i) {
    double fx = 0, fy = 0, fz = 0, tx = 0, ty = 0, tz = 0;
    for (std::size_t q = scratch.bond_partner_begin[i]; q < scratch.bond_partner_begin[i + 1]; ++q) {   // as j
      const BondPush& p = pushes[scratch.bond_partners[q]];
      fx += p.fx; fy += p.fy; fz += p.fz;
      tx += p.tjx; ty += p.tjy; tz += p.tjz;
    }
    for (std::size_t q = scratch.bond_run_begin[i]; q < scratch.bond_run_begin[i + 1]; ++q) {   // as i
      const BondPush& p = pushes[scratch.bond_runs[q]];
      fx -= p.fx; fy -= p.fy; fz -= p.fz;
      tx += p.tix; ty += p.tiy; tz += p.tiz;
    }
    PairForce& total = scratch.ball_force[i];
    total.fx += fx; total.fy += fy; total.fz += fz;
    total.tx += tx; total.ty += ty; total.tz += tz;
    if (stiffness) { total.kmax += scratch.ball_bond_stiffness[i].kmax; total.ks += scratch.ball_bond_stiffness[i].ks; }
  }
}

}  // namespace trubal
