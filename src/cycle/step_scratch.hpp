// The working memory of a step, kept by the pipeline between steps and never saved: the index of
// the pair list the contact loops walk, the per-ball contact sums.
#pragma once

#include <array>

#include <cstdint>
#include <vector>

#include "model/model.hpp"
#include "physics/bond.hpp"

namespace trubal {

// The contact sums of one ball in one cache line: total contact force, sum of n x shear force
// (the moment is -R t), and the stiffness sums the time-step estimate uses.
struct alignas(64) PairForce {
  double fx, fy, fz, tx, ty, tz;
  // max(k_n, k_s) and k_s now, summed only where the next step is estimated (FRAC:
  // StepKernels::sums_stiffness); under TSTEP nothing reads them and they stay 0.
  double kmax, ks;
};

// A ball's sums of the contact dashpots' part of PairForce's fx fy fz tx ty tz (scenes with
// dashpots): the law of motion charges the dashpots with their force times the ball's velocity, as it
// does every force, so that their work is booked to second order however they start and stop.
struct DashpotForce {
  double fx = 0, fy = 0, fz = 0, tx = 0, ty = 0, tz = 0;
};

// A ball's sum of the rolling springs' moments (scenes with rolling resistance): a moment, not a
// force at the ball's surface, so it is summed apart from PairForce's t (whose moment is -R t); and
// the work they dissipated in its run of pairs and its wall contacts (kept here, not in BallParts,
// whose seven doubles the motion loop reads with a stride it vectorises compactly).
struct RollingMoment {
  double mx = 0, my = 0, mz = 0;
  double work = 0;
};

// A ball's sum of its capillary bridges' forces (scenes with bridges, cycle/bridge_pass.hpp), and
// their power at v(t - dt/2), for the work the law of motion's rule charges them with.
struct BridgeSum {
  double fx = 0, fy = 0, fz = 0, power = 0;
};

// A bond's law but its radius (scenes with bonds, cycle/bond_pass.hpp): kn, ks, tension, cohesion,
// tan_friction, mcf.
using BondLawRow = std::array<double, 6>;

// A bond's push this step (scenes with bonds, cycle/bond_pass.hpp), as each ball adds it: the force
// on j (i takes its opposite), and the moment over its own radius on j, t - M / R_j, and on i,
// t + M / R_i, where t = n x Fs (the moment on a ball b is -R_b t, as a contact's) and M = Mt n + Mb
// is the bond's moment on j. Zero where broken.
struct BondPush {
  double fx = 0, fy = 0, fz = 0, tjx = 0, tjy = 0, tjz = 0, tix = 0, tiy = 0, tiz = 0;
};

// One ball's parts of the step's global sums from its contacts: its run of pairs (those with
// higher partners, in list order), then its wall contacts in order. The motion loop adds its own
// and hands them to the exact sums (StepSums), ball by ball.
struct BallParts {
  double friction = 0, damping = 0, strain = 0, image = 0, boundary = 0;
  double damping_ahead = 0, boundary_ahead = 0;   // the parts after t (StepSums)
};

struct StepScratch {
  std::vector<std::uint32_t> run_begin;   // first pair with i >= b, for b = 0 .. balls
  std::uint64_t list_version = 0;         // the ContactTable::list_version this index is of
  // The contact sums per ball (sign for ball i included), added in the same order (lower partners
  // ascending, then higher ones) whichever thread adds them, so they are the same to the bit.
  std::vector<PairForce> ball_force;
  std::vector<double> ball_cn;            // the dashpot coefficients' sum (time step with dashpots)
  // Features::stiffness_damping only (sized by the pipeline, as ball_moments): DashpotForce.
  std::vector<DashpotForce> ball_dashpot;
  // Features::rolling only (sized as ball_dashpot): RollingMoment.
  std::vector<RollingMoment> ball_rolling;
  std::vector<BallParts> ball_parts;
  // Features::bridges only (cycle/bridge_pass.hpp, which sizes them): each pair's bridge force on j
  // and each wall contact's on its ball, made by the pair's owner; each ball's pairs as partner j
  // (ascending i: the first at partner_begin[b]), of the list partner_version; each ball's sum.
  std::vector<std::array<double, 3>> pair_bridge, wall_bridge;
  std::vector<std::uint32_t> partner_begin, partner_pairs;
  std::uint64_t partner_version = 0;
  std::vector<BridgeSum> ball_bridge;
  // Scenes with bonds only (cycle/bond_pass.cpp, which makes them, the table's rows put in the
  // step's order: its first places the bonds that held when the index was made, by their balls'
  // places in memory, so that the gather reads the balls as the contact loops do): each place's
  // balls as indices, whether it still holds, its push. Each ball's bonds as partner j (ascending i;
  // the first at bond_partner_begin[b]) and as i (ascending j, from bond_run_begin[b] in bond_runs),
  // as places: the order by ids, in which every ball sums. Each bond's share of the stiffness sums
  // (physics/bond.hpp) and each ball's sum of its intact bonds' (changed only where a bond breaks:
  // bond_broken).
  std::vector<std::uint32_t> bond_ball_i, bond_ball_j, bond_run_begin, bond_runs, bond_partner_begin, bond_partners;
  std::vector<std::uint8_t> bond_holds;
  std::vector<BondLawRow> bond_laws;           // the distinct laws but the radius: kn ks tension cohesion tan_friction mcf
  std::vector<std::uint32_t> bond_law_of;      // each place's
  std::vector<BondPush> bond_push;
  std::vector<BondStiffness> bond_stiffness, ball_bond_stiffness;
  std::vector<std::vector<std::uint32_t>> bond_broken;   // the places of the bonds each share broke this step
  std::uint64_t bond_edition = 0;              // the Bonds::edition the index is of
  std::uint64_t bond_version = 0;              // the ContactTable::list_version the bonds' index is of
  // StepKernels::moments only (sized by the pipeline for servo steps, empty otherwise): each ball's
  // run's sums of F (x) l (xx yy zz xy xz yz) and k_n l_a^2.
  std::vector<std::array<double, 9>> ball_moments;
  // The wall contacts' index: the first with ball >= b, for b = 0 .. balls.
  std::vector<std::uint32_t> wall_run_begin;
  // A rank's part of a spatially decomposed run (cycle/brick_step.hpp): 1 for a ball another rank
  // owns (a ghost: the motion loop skips it, its owner sends its new state). Empty otherwise.
  std::vector<std::uint8_t> ghost;
  std::uint64_t wall_list_version = 0;

  // Whether the index is of this table, for this many balls.
  bool fits(const ContactTable& table, std::size_t balls) const {
    return list_version != 0 && list_version == table.list_version && run_begin.size() == balls + 1;
  }
  bool fits_walls(const WallContacts& walls, std::size_t balls) const {
    return wall_list_version == walls.list_version && wall_run_begin.size() == balls + 1;
  }
  void index_walls(const WallContacts& walls, std::size_t balls);
  // Indexes the table's pair list (sorted by i, then j) for `balls` balls.
  void index(const ContactTable& table, std::size_t balls);
};

}  // namespace trubal
