// The specialised loops of one time step, chosen once per CYCLE for the features a scene uses.
// The pipeline calls them through ParallelStep (cycle/parallel_step.hpp): `cross` and
// `contacts` over pair blocks (the pairs of kContactBalls consecutive balls i), adding each pair to
// its balls' sums in partner order, then `motion` over blocks of kReduceBlock balls (law of
// motion). Each call adds to the sums it is given (exact sums, StepSums), so every backend, thread
// count and rank count rounds the totals alike.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
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
#include "support/exact_sum.hpp"

namespace trubal {

inline constexpr std::size_t kReduceBlock = 256;   // balls per block of the motion loop

// Adds every exact sum of `from` to the same one of `into` (StepSums, WallLoad: each_sum lists them
// in one fixed order).
template <class Sums>
void merge_exact_sums(Sums& into, Sums& from) {
  std::array<ExactSum*, 23> to{};   // (StepSums has the most: 23)
  std::size_t n = 0;
  into.each_sum([&](ExactSum& s) { to[n++] = &s; });
  n = 0;
  from.each_sum([&](ExactSum& s) { to[n++]->add(s); });
}

// Reductions of one step. The sums are exact (support/exact_sum.hpp): each ball adds its part
// (the pairs of its run, its motion, its wall contacts, each summed in their fixed order), and the
// total does not depend on how the balls are shared among threads or ranks; min and max are exact,
// and the fastest ball is the lowest index among equals.
struct StepSums {
  ExactSum friction_work, damping_work, boundary_work;
  ExactSum strain;                          // spring energy at the start of the step
  ExactSum image_power;                     // periodic: sum of -F_j . (velocity of j's image offset)
  // StepKernels::moments only: sum of F (x) l (symmetric part, xx yy zz xy xz yz) and of k_n l_a^2,
  // l the branch vector i -> j (image included), over the touching pairs: the servo's stress and
  // stiffness (physics/cell.hpp).
  std::array<ExactSum, 6> force_moment{};
  std::array<ExactSum, 3> stiffness_moment{};
  // The energy at t, the time of this step's force pass (doc/physics.md "Energy"): kinetic
  // m v(t-dt/2).v(t+dt/2)/2 (and I w.w for the spins), -m g.x(t); and the parts of the step's works
  // that lie after t (half of F(t).v(t+dt/2) dt for applied loads, damping in the law of motion,
  // fixed velocities and walls), which the balance at t leaves out.
  ExactSum kinetic_translation, kinetic_rotation, potential;
  ExactSum damping_ahead, boundary_ahead;
  ExactSum rolling_work;                    // dissipated by the rolling springs' limit
  // Scenes with capillary bridges (cycle/bridge_pass.hpp): the work the bridges' forces F(t) do on
  // the balls, F(t) . (v(t - dt/2) + v(t + dt/2)) / 2 dt_mean as the law of motion charges any
  // force, and its part after t.
  ExactSum capillary_work, capillary_ahead;
  // Scenes with bonds (cycle/bond_pass.hpp): the strain energy the bonds that broke this step held.
  ExactSum bond_break;
  double critical_dt = std::numeric_limits<double>::infinity();   // next step's estimate (NaN wins)
  double fastest_speed2 = -1;               // |v|^2 + |R w|^2 of the fastest ball (NaN wins)
  std::size_t fastest_ball = 0;

  // Every exact sum, in one fixed order (for merging and for the exchange between ranks).
  template <class F>
  void each_sum(F&& f) {
    for (ExactSum* s : {&friction_work, &damping_work, &boundary_work, &strain, &image_power}) f(*s);
    for (ExactSum& s : force_moment) f(s);
    for (ExactSum& s : stiffness_moment) f(s);
    for (ExactSum* s : {&kinetic_translation, &kinetic_rotation, &potential, &damping_ahead, &boundary_ahead, &rolling_work,
                        &capillary_work, &capillary_ahead, &bond_break})
      f(*s);
  }
  void take_step(double dt) {
    if (std::isnan(critical_dt)) return;
    if (std::isnan(dt) || dt < critical_dt) critical_dt = dt;
  }
  void take_fastest(double speed2, std::size_t ball) {
    const bool nan_new = std::isnan(speed2), nan_old = std::isnan(fastest_speed2);
    const bool better = nan_new != nan_old ? nan_new
                        : nan_new           ? ball < fastest_ball
                                            : speed2 > fastest_speed2 || (speed2 == fastest_speed2 && ball < fastest_ball);
    if (better) { fastest_speed2 = speed2; fastest_ball = ball; }
  }
  void add(StepSums& o) {
    merge_exact_sums(*this, o);
    take_step(o.critical_dt);
    take_fastest(o.fastest_speed2, o.fastest_ball);
  }
};

// StepSums rounded: what the cycle reads.
struct StepTotals {
  double friction_work = 0, damping_work = 0, boundary_work = 0, strain = 0, image_power = 0;
  std::array<double, 6> force_moment{};
  std::array<double, 3> stiffness_moment{};
  double kinetic_translation = 0, kinetic_rotation = 0, potential = 0, damping_ahead = 0, boundary_ahead = 0;
  double rolling_work = 0;
  double capillary_work = 0, capillary_ahead = 0;
  double bond_break = 0;
  double critical_dt = std::numeric_limits<double>::infinity();
  double fastest_speed2 = -1;
  std::size_t fastest_ball = 0;
  explicit StepTotals(const StepSums& s)
      : friction_work(s.friction_work.value()), damping_work(s.damping_work.value()),
        boundary_work(s.boundary_work.value()), strain(s.strain.value()), image_power(s.image_power.value()),
        kinetic_translation(s.kinetic_translation.value()), kinetic_rotation(s.kinetic_rotation.value()),
        potential(s.potential.value()), damping_ahead(s.damping_ahead.value()),
        boundary_ahead(s.boundary_ahead.value()), rolling_work(s.rolling_work.value()),
        capillary_work(s.capillary_work.value()), capillary_ahead(s.capillary_ahead.value()), bond_break(s.bond_break.value()),
        critical_dt(s.critical_dt),
        fastest_speed2(s.fastest_speed2), fastest_ball(s.fastest_ball) {
    for (int a = 0; a < 6; ++a) force_moment[a] = s.force_moment[a].value();
    for (int a = 0; a < 3; ++a) stiffness_moment[a] = s.stiffness_moment[a].value();
  }
};

struct StepKernels;
// Pairs [begin, end) of the list (whole runs of i), adding each to its balls' sums in
// StepScratch::ball_force: ball i always, ball j if below own_end (a later thread owns the rest).
// The pairs' parts of the global sums go to StepScratch::ball_parts (each ball's run).
using ContactLoop = void (*)(Model&, StepScratch&, const StepKernels&, std::size_t begin, std::size_t end,
                             std::size_t own_end);
// Zeroes the sums of balls [ball_begin, ball_end) and adds the pairs they have with lower balls
// outside the range (cross pairs: `pairs`, `count` of them, in list order), before any ContactLoop.
// `history`: their shear history before the step (count x, then count y, then count z; read where
// the scene has friction), copied before the pass, since the thread that owns a cross pair writes
// its new history over the table's meanwhile.
using CrossLoop = void (*)(Model&, StepScratch&, const StepKernels&, std::size_t ball_begin, std::size_t ball_end,
                           const std::uint32_t* pairs, std::size_t count, const double* history);
// What the wall contacts add to each wall (exact sums: each thread or rank keeps its own, and they
// merge to the same bits in any order).
struct WallLoad {
  ExactSum fx, fy, fz;                // force on the wall
  ExactSum mx, my, mz;                // its moment about the wall's spin point
  ExactSum normal_force, stiffness, work;
  ExactSum relative_kinetic;          // Wall::relative_kinetic
  std::int64_t contacts = 0;
  template <class F>
  void each_sum(F&& f) {
    for (ExactSum* s : {&fx, &fy, &fz, &mx, &my, &mz, &normal_force, &stiffness, &work, &relative_kinetic}) f(*s);
  }
  void add(WallLoad& o) {
    merge_exact_sums(*this, o);
    contacts += o.contacts;
  }
};
// Wall contacts [begin, end) of Model::wall_contacts (whole runs of balls, after all of their ball
// pairs): added to their balls' sums in wall order, to `loads` (one per wall) and to the balls'
// parts of the global sums (StepScratch::ball_parts).
using WallLoop = void (*)(Model&, StepScratch&, const StepKernels&, std::size_t begin, std::size_t end,
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
  // Whether this step forms the walls' loads (Wall::force, moment, normal_force, stiffness,
  // contacts): on the steps something reads them (run.cpp, StepPlan::wall_loads); the others leave
  // them as the last step that formed them did. Each wall's work is formed every step, its
  // relative_kinetic (the guard's) on the steps that form the energy terms (`energies`); a wall
  // whose surface stands still adds nothing to them.
  bool wall_loads = true;
  // Whether this step forms the energy terms at t (StepSums::kinetic_translation, kinetic_rotation,
  // potential, strain and the aheads, state quantities): on the steps the guard checks and those
  // that write or keep results (run.cpp, StepPlan::energies); the others leave them zero. `kinetic`
  // forms the kinetic terms alone (the step before each of the guard's regular checks, for its test
  // of velocities that flip sign). The works (friction, damping, boundary, rolling, capillary,
  // bond_break, image_power) are formed on every step.
  bool energies = true;
  bool kinetic = true;
  // The steps of central differences with a step that changes (doc/physics.md "Law of motion"):
  // positions move by v(t + dt/2) dt, this step; velocities by F(t)/m times dt_mean, the mean of the
  // step before and this one, and so does the work the law of motion charges a force with; a
  // contact's shear spring takes the relative velocity v(t - dt/2) over dt_prev, the step that
  // velocity moved the balls by. (With a step held fixed all three are the same number.)
  double dt = 0;                            // this step
  double dt_prev = 0;                       // the step before (this one on a model's first step)
  double dt_mean = 0;                       // (dt_prev + dt) / 2
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
  // Whether this step writes the per-pair results (run_cycles picked contacts_full).
  bool writes_results() const { return contacts == contacts_full; }
  // Whether the contact loops add the balls' stiffness sums (PairForce::kmax, ks): only the next
  // step's estimate reads them (FRAC); under TSTEP nothing does.
  bool sums_stiffness() const { return estimate != StepEstimate::None; }
};

// The kernels for the model as it is now (materials, damping, fixities, loads).
StepKernels make_kernels(const Model& model);
// The same with the scene's features given (scene_features: a distributed run going on from its
// parts has them from rank 0, whose model alone holds every ball's state).
StepKernels make_kernels(const Model& model, const Features& features);

}  // namespace trubal
