#include "cycle/bridge_pass.hpp"

#include <cmath>

#include "model/periodic_cell.hpp"
#include "physics/bridge.hpp"
#include "physics/walls.hpp"

namespace trubal {

void prepare_bridges(const Model& model, StepScratch& scratch) {
  const ContactTable& c = model.contacts;
  const std::size_t balls = model.balls.size(), pairs = c.size();
  scratch.pair_bridge.resize(pairs);
  scratch.wall_bridge.resize(model.wall_contacts.size());
  scratch.ball_bridge.resize(balls);
  if (scratch.partner_version == c.list_version && c.list_version != 0 && scratch.partner_pairs.size() == pairs &&
      scratch.partner_begin.size() == balls + 1)
    return;
  // A counting sort of the list by j, stable: each ball's pairs as partner j in list order, which
  // is ascending i.
  std::vector<std::uint32_t>& begin = scratch.partner_begin;
  begin.assign(balls + 1, 0);
  for (std::size_t p = 0; p < pairs; ++p) ++begin[c.j[p] + 1];
  for (std::size_t b = 0; b < balls; ++b) begin[b + 1] += begin[b];
  std::vector<std::uint32_t> next(begin.begin(), begin.end() - 1);
  scratch.partner_pairs.resize(pairs);
  for (std::size_t p = 0; p < pairs; ++p) scratch.partner_pairs[next[c.j[p]]++] = static_cast<std::uint32_t>(p);
  scratch.partner_version = c.list_version;
}

namespace {

// The bridge's state after this force pass, from its state before and the gap now: it forms where
// the pair touches and breaks beyond the rupture gap.
double bridge_state(const BridgeLaw& law, double before, double gap) {
  if (!law.on()) return 0;
  if (gap <= 0) return 1;
  return gap > law.rupture ? 0 : before;
}

}  // namespace

void bridge_pairs(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                  StepSums& sums) {
  ContactTable& c = model.contacts;
  const Balls& b = model.balls;
  const bool periodic = model.space.periodic;
  const CellFrame cell = cell_frame(model.space);
  const bool ghosts = !scratch.ghost.empty();
  for (std::size_t p = begin; p < end; ++p) {
    const std::size_t i = c.i[p], j = c.j[p];
    const BridgeLaw& law = k.laws.bridge(i, j);
    const auto [dx, dy, dz] = pair_separation(cell, periodic, b, c, p);   // (as the contact loops' gather)
    const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
    const double gap = d - (b.rad[i] + b.rad[j]);
    const double state = d > 0 ? bridge_state(law, c.bridge[p], gap) : 0.0;
    c.bridge[p] = state;
    std::array<double, 3>& f = scratch.pair_bridge[p];
    if (state == 0) {
      f = {0, 0, 0};
      continue;
    }
    if (k.writes_results() && c.state[p] == 0) {
      // Held apart by the bridge alone: the contact loops wrote no normal and no overlap (no
      // contact); the results give the pair's unit normal and its gap as a negative overlap, as
      // the contact law would (U = R_i + R_j - d).
      const double inv_d = 1.0 / d;
      c.nx[p] = dx * inv_d; c.ny[p] = dy * inv_d; c.nz[p] = dz * inv_d;
      c.overlap[p] = b.rad[i] + b.rad[j] - d;
    }
    // On j, toward i: -F n, n = d / |d| from i to j.
    const double pull = bridge_force(law, b.rad[i], b.rad[j], gap) / d;
    f = {-pull * dx, -pull * dy, -pull * dz};
    if (k.moments && !(ghosts && scratch.ghost[i])) {   // the force on j times the branch vector i -> j
      sums.force_moment[0].add(f[0] * dx); sums.force_moment[1].add(f[1] * dy); sums.force_moment[2].add(f[2] * dz);
      sums.force_moment[3].add(0.5 * (f[0] * dy + f[1] * dx));
      sums.force_moment[4].add(0.5 * (f[0] * dz + f[2] * dx));
      sums.force_moment[5].add(0.5 * (f[1] * dz + f[2] * dy));
    }
  }
}

void bridge_walls(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                  WallLoad* loads) {
  WallContacts& c = model.wall_contacts;
  const Balls& b = model.balls;
  for (std::size_t p = begin; p < end; ++p) {
    const std::size_t i = c.ball[p];
    const Wall& wall = model.walls[c.wall[p]];
    const BridgeLaw& law = k.laws.wall_bridge(i, c.wall[p]);
    // The wall as a partner of radius 2R (physics/walls.hpp): R* is the ball's radius, the gap the
    // contact law's.
    const WallLane lane = wall_lane(wall, {b.x[i], b.y[i], b.z[i]}, b.rad[i]);
    const double d = std::sqrt(lane.dx * lane.dx + lane.dy * lane.dy + lane.dz * lane.dz);
    const double gap = d - 2 * lane.r;
    const double state = d > 0 ? bridge_state(law, c.bridge[p], gap) : 0.0;
    c.bridge[p] = state;
    std::array<double, 3>& f = scratch.wall_bridge[p];
    if (state == 0) {
      f = {0, 0, 0};
      continue;
    }
    // On the ball, toward the wall: +F n; the wall takes -F n, a pull (negative compression).
    const double force = bridge_force(law, lane.r, lane.r, gap), pull = force / d;
    f = {pull * lane.dx, pull * lane.dy, pull * lane.dz};
    if (!k.wall_loads) continue;   // (the wall's loads: on the steps that form them)
    WallLoad& load = loads[c.wall[p]];
    const double ax = lane.point[0] - wall.spin_point[0], ay = lane.point[1] - wall.spin_point[1],
                 az = lane.point[2] - wall.spin_point[2];
    load.fx.add(-f[0]); load.fy.add(-f[1]); load.fz.add(-f[2]);
    load.mx.add(az * f[1] - ay * f[2]); load.my.add(ax * f[2] - az * f[0]); load.mz.add(ay * f[0] - ax * f[1]);
    load.normal_force.add(-force);
  }
}

void add_bridges(const Model& model, StepScratch& scratch, std::size_t begin, std::size_t end) {
  const Balls& b = model.balls;
  const bool walls = scratch.wall_run_begin.size() == b.size() + 1 && scratch.wall_bridge.size() == model.wall_contacts.size();
  for (std::size_t i = begin; i < end; ++i) {
    double fx = 0, fy = 0, fz = 0;
    for (std::size_t q = scratch.partner_begin[i]; q < scratch.partner_begin[i + 1]; ++q) {   // lower partners
      const std::array<double, 3>& f = scratch.pair_bridge[scratch.partner_pairs[q]];
      fx += f[0]; fy += f[1]; fz += f[2];
    }
    for (std::size_t p = scratch.run_begin[i]; p < scratch.run_begin[i + 1]; ++p) {   // higher partners
      const std::array<double, 3>& f = scratch.pair_bridge[p];
      fx -= f[0]; fy -= f[1]; fz -= f[2];
    }
    if (walls)
      for (std::size_t p = scratch.wall_run_begin[i]; p < scratch.wall_run_begin[i + 1]; ++p) {
        const std::array<double, 3>& f = scratch.wall_bridge[p];
        fx += f[0]; fy += f[1]; fz += f[2];
      }
    PairForce& total = scratch.ball_force[i];
    total.fx += fx; total.fy += fy; total.fz += fz;
    scratch.ball_bridge[i] = {fx, fy, fz, fx * b.vx[i] + fy * b.vy[i] + fz * b.vz[i]};
  }
}

void bridge_work(const Model& model, const StepScratch& scratch, const StepKernels& k, std::size_t begin,
                 std::size_t end, StepSums& sums) {
  const Balls& b = model.balls;
  const bool ghosts = !scratch.ghost.empty();
  ExactSum::Stream work(sums.capillary_work), ahead(sums.capillary_ahead);
  const double half = 0.5 * k.dt_mean;
  for (std::size_t i = begin; i < end; ++i) {
    if (ghosts && scratch.ghost[i]) continue;
    const BridgeSum& s = scratch.ball_bridge[i];
    const double after = s.fx * b.vx[i] + s.fy * b.vy[i] + s.fz * b.vz[i];
    work.add((s.power + after) * half);
    if (k.energies) ahead.add(after * half);   // (the part after t: where the step forms the energies)
  }
}

}  // namespace trubal
