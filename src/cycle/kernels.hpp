// The specialised loops of one time step, chosen once per CYCLE for the features a scene uses.
// The pipeline calls them through ParallelStep (cycle/parallel_step.hpp): `cross` and
// `contacts` over pair blocks (the pairs of kContactBalls consecutive balls i), adding each pair to
// its balls' sums in partner order, then `motion` over blocks of kReduceBlock balls (law of
// motion). Each call returns its block's sums; they are added in ascending block order, so every
// backend and thread count rounds the totals alike.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "cycle/step_scratch.hpp"
#include "model/model.hpp"
#include "physics/contact/features.hpp"
#include "physics/contact_law.hpp"
#include "physics/pair_laws.hpp"
#include "physics/scene.hpp"

namespace trubal {

inline constexpr std::size_t kReduceBlock = 256;   // balls per block of the motion loop

// Reductions of one step. Sums are added block by block in ascending order; min/max are exact.
struct StepSums {
  double friction_work = 0, damping_work = 0, boundary_work = 0;
  double strain = 0;                        // spring energy at the start of the step
  double image_power = 0;                   // periodic: sum of -F_j . (velocity of j's image offset)
  // StepKernels::moments only: sum of F (x) l (symmetric part, xx yy zz xy xz yz) and of k_n l_a^2,
  // l the branch vector i -> j (image included), over the touching pairs: the servo's stress and
  // stiffness (physics/cell.hpp).
  std::array<double, 6> force_moment{};
  std::array<double, 3> stiffness_moment{};
  double kinetic = 0, potential = 0;        // at t: m v(t-dt/2).v(t+dt/2)/2 and -m g.x(t), for the guard
  double critical_dt = std::numeric_limits<double>::infinity();   // next step's estimate
  double fastest_speed2 = -1;               // |v|^2 + |R w|^2 of the fastest ball (NaN wins)
  std::size_t fastest_ball = 0;

  void add(const StepSums& o) {
    friction_work += o.friction_work; damping_work += o.damping_work;
    boundary_work += o.boundary_work; strain += o.strain; image_power += o.image_power;
    for (int a = 0; a < 6; ++a) force_moment[a] += o.force_moment[a];
    for (int a = 0; a < 3; ++a) stiffness_moment[a] += o.stiffness_moment[a];
    kinetic += o.kinetic; potential += o.potential;
    critical_dt = std::min(critical_dt, o.critical_dt);
    if (!(o.fastest_speed2 <= fastest_speed2)) { fastest_speed2 = o.fastest_speed2; fastest_ball = o.fastest_ball; }
  }
};

struct StepKernels;
// Pairs [begin, end) of the list (whole runs of i), adding each to its balls' sums in
// StepScratch::ball_force: ball i always, ball j if below own_end (a later thread owns the rest).
using ContactLoop = void (*)(Model&, StepScratch&, const StepKernels&, std::size_t begin, std::size_t end,
                             std::size_t own_end, StepSums&);
// Zeroes the sums of balls [ball_begin, ball_end) and adds the pairs they have with lower balls
// outside the range (cross pairs: `pairs`, `count` of them, in list order), before any ContactLoop.
using CrossLoop = void (*)(Model&, StepScratch&, const StepKernels&, std::size_t ball_begin, std::size_t ball_end,
                           const std::uint32_t* pairs, std::size_t count);
// What the wall contacts of one pair block add to each wall (ParallelStep adds the blocks in order).
struct WallLoad {
  double fx = 0, fy = 0, fz = 0;      // force on the wall
  double mx = 0, my = 0, mz = 0;      // its moment about the wall's spin point
  double normal_force = 0, stiffness = 0, work = 0;
  std::int64_t contacts = 0;
  void add(const WallLoad& o) {
    fx += o.fx; fy += o.fy; fz += o.fz; mx += o.mx; my += o.my; mz += o.mz;
    normal_force += o.normal_force; stiffness += o.stiffness; work += o.work; contacts += o.contacts;
  }
};
// Wall contacts [begin, end) of Model::wall_contacts (whole runs of balls, after all of their ball
// pairs): added to their balls' sums in wall order, to `loads` (one per wall) and to `sums`.
using WallLoop = void (*)(Model&, StepScratch&, const StepKernels&, std::size_t begin, std::size_t end, StepSums&,
                          WallLoad* loads);
using MotionLoop = void (*)(Model&, const StepScratch&, const StepKernels&, std::size_t begin, std::size_t end,
                            StepSums&);

// Pair blocks: the pairs of kContactBalls consecutive balls i (whole runs), the unit of the
// contact sums and of the work a thread takes. Defined by balls, so the same for every backend
// and thread count.
inline constexpr std::size_t kContactBalls = 256;

// How the motion loop estimates the next step.
enum class StepEstimate : unsigned { None = 0, Undamped = 1, Damped = 2 };

// What the motion loop computes, as a type (its template parameter), with the one encoding to its
// table's index.
struct MotionFeatures {
  bool rotation = false;                         // spins move
  bool loads = false;                            // gravity or applied loads
  DampKind damping = DampKind::None;             // mass-proportional or local damping
  StepEstimate estimate = StepEstimate::None;    // the next step's estimate
  bool write_forces = false;                     // also each ball's unbalanced force and moment (output reads them)

  static constexpr unsigned kCount = 2 * 2 * 3 * 3 * 2;
  constexpr unsigned index() const {
    return (rotation ? 1u : 0u) + (loads ? 2u : 0u) + 4 * static_cast<unsigned>(damping) +
           12 * static_cast<unsigned>(estimate) + (write_forces ? 36u : 0u);
  }
  static constexpr MotionFeatures from_index(unsigned i) {
    return {(i & 1u) != 0, (i & 2u) != 0, static_cast<DampKind>(i / 4 % 3), static_cast<StepEstimate>(i / 12 % 3),
            i >= 36};
  }
};

struct StepKernels {
  Features features;
  StepEstimate estimate = StepEstimate::Undamped;
  bool moments = false;                     // the contact loops sum StepSums::force_moment and
                                            // stiffness_moment (set while a servo runs)
  double dt = 0;                            // this step
  double beta = 0, alpha = 0, local = 0;    // damping
  std::array<double, 3> gravity{0, 0, 0};
  PairLaws laws;                            // by pair of ball types
  // The contact loop this step runs: contacts_full also writes the per-pair results measurements
  // read (ContactTable normal, overlap, forces, stiffness, work, state); contacts_lean writes only
  // what the next step needs (history, the sums per ball). run_cycles picks one per step; both
  // compute the same numbers.
  ContactLoop contacts = nullptr, contacts_full = nullptr, contacts_lean = nullptr;
  CrossLoop cross = nullptr;
  WallLoop walls = nullptr, walls_full = nullptr, walls_lean = nullptr;   // full: also the wall contacts' results
  MotionLoop motion = nullptr, motion_full = nullptr, motion_lean = nullptr;   // full: also Balls::fx.. mz
};

// The kernels for the model as it is now (materials, damping, fixities, loads).
StepKernels make_kernels(const Model& model);

}  // namespace trubal
