// The loop over steps, its time step and its observers (cycle/run.hpp); the guard is
// cycle/energy_guard.cpp.
#include "cycle/run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "cycle/brick_step.hpp"
#include "cycle/energy_guard.hpp"
#include "cycle/kernels.hpp"
#include "cycle/pipeline.hpp"
#include "model/edit.hpp"
#include "physics/cell.hpp"
#include "physics/membrane.hpp"
#include "physics/scene.hpp"
#include "physics/timestep.hpp"
#include "physics/walls.hpp"
#include "support/comm.hpp"

namespace trubal {
namespace {

constexpr std::int64_t kSnapshotEvery = 500;   // a copy costs less than one step's memory traffic
constexpr double kProgressSeconds = 0.2;
constexpr std::int64_t kAgreeEvery = 16;   // steps between the ranks' checks of an interrupt

using Clock = std::chrono::steady_clock;

// The scene's features (scene_features) as rank 0 finds them, on every rank: a collective call,
// for a run going on from the ranks' parts (the others hold no ball's state but its type and radius).
Features features_from_root(const Model& model, Pipeline& pipeline) {
  Features f;
  // (Rank 0's whole model hollow: whether a ball spins or carries a load, from the parts.)
  std::optional<BallFlags> flags;
  if (pipeline.whole_hollow(model)) flags = pipeline.part_counts(model).flags();
  if (comm::root()) f = scene_features(model, flags);
  std::vector<std::int64_t> v{f.rotation, f.friction, f.hertz, f.rolling, f.bridges, f.bonds, f.stiffness_damping,
                              static_cast<std::int64_t>(f.mass_damping), f.gravity, f.applied, f.periodic};
  comm::broadcast(v);
  f.rotation = v[0] != 0; f.friction = v[1] != 0; f.hertz = v[2] != 0; f.rolling = v[3] != 0; f.bridges = v[4] != 0;
  f.bonds = v[5] != 0; f.stiffness_damping = v[6] != 0; f.mass_damping = static_cast<DampKind>(v[7]);
  f.gravity = v[8] != 0; f.applied = v[9] != 0; f.periodic = v[10] != 0;
  return f;
}

// START box (its bounded axes, in a mixed space): the first ball (by index) whose centre is outside
// across a `stop` face, and every ball outside across a `destroy` face (marked). A NaN centre is
// the guard's, not this.
struct Escapes {
  std::size_t stop_ball = ~std::size_t{0};
  int stop_axis = 0;
  std::vector<bool> destroy;
  std::size_t destroy_count = 0;
};
Escapes find_escapes(const Model& model) {
  Escapes e;
  const Space& s = model.space;
  const Balls& b = model.balls;
  const std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  // Every step: first whether any ball is out at all, axis by axis as a loop the compiler
  // vectorises (a NaN is out of neither side, as below).
  unsigned any = 0;
  for (int a = 0; a < 3; ++a) {
    if (s.wraps(a)) continue;
    const double* x = pos[a]->data();
    const double lo = s.lo[a], hi = s.hi[a];
    for (std::size_t k = 0; k < b.size(); ++k) any |= static_cast<unsigned>((x[k] < lo) | (x[k] > hi));
  }
  if (any == 0) return e;
  for (std::size_t k = 0; k < b.size(); ++k)
    for (int a = 0; a < 3; ++a) {
      if (s.wraps(a)) continue;   // a periodic axis wraps the ball instead
      const double x = (*pos[a])[k];
      if (!(x < s.lo[a] || x > s.hi[a])) continue;
      if (s.outside[a] == Outside::Stop) {
        if (e.stop_ball == ~std::size_t{0}) { e.stop_ball = k; e.stop_axis = a; }
      } else {
        if (e.destroy.empty()) e.destroy.assign(b.size(), false);
        e.destroy_count += !e.destroy[k];
        e.destroy[k] = true;
      }
    }
  return e;
}

// What one step of the CYCLE writes and keeps. The per-pair results measurements read are written
// only where someone will read them: the last step (PRINT, SOLVE; CYCLE's defers it:
// make_results), a step Ctrl-C ends, snapshot steps (Snapshot::restore finds them current where
// the next step fails; not where results are deferred, as the rescue takes the step again, nor
// where the copy is taken on the ranks' parts, which keeps none) and the
// cycles history and dumps record.
struct StepPlan {
  bool stopping = false;   // Ctrl-C was seen before this step: it is the last
  bool observed = false;   // an observer reads this step's contact results
  bool deferred = false;   // the CYCLE's last step, its results made when read (from a copy of the step before)
  bool details = false;    // the step writes the per-pair results
  // A deferred last step taken again on the parts (CycleControl::leave_results, results_onto_parts):
  // it writes its results there, and the parts keep them for the command that reads them; rank 0's
  // copy of the step before stays, should anything end the parts first.
  bool leave_results = false;
  // An output step whose observers read the parts' sums (CycleControl::after_step_on_parts): the
  // whole model is not gathered for it, and the results it writes on the parts are read there (and
  // the CYCLE's last step's kept there, as a step that leaves its results: Pipeline::end_cycle).
  bool observed_on_parts = false;
  bool last = false;   // the CYCLE's last step
  // The step forms the walls' loads (StepKernels::wall_loads): where it writes the results, at the
  // CYCLE's last step (deferred or not: what follows a CYCLE reads the walls), at each step a
  // rescue copy is taken after (the rescue may leave the model there: the 500th steps' and, where
  // the last step's results are deferred, the step before it), and while a wall servo runs
  // (advance).
  bool wall_loads = false;
  // The step forms the energy terms at t (StepKernels::energies) and the guard checks it: at the
  // guard's regular checks (cycles of the model's count on EnergyGuard::kCheckEvery), the CYCLE's
  // first step (the balance's reference), and every step that forms the walls' loads (those whose
  // state is written, kept in a rescue copy or left at the CYCLE's end). kinetic: the kinetic terms
  // alone, on the step before a regular check (the guard's test of velocities that flip sign).
  bool energies = false;
  bool kinetic = false;
  // Everything: the steps the rescue takes again.
  static StepPlan all() {
    StepPlan p;
    p.details = p.wall_loads = p.energies = p.kinetic = true;
    return p;
  }
};

// One CYCLE: n steps of the pipeline, each followed by the guard, the START box's faces, the
// observers, the rescue copy and the progress report (run()). Its members are what the steps share.
class CycleRun {
 public:
  CycleRun(Model& model, Pipeline& pipeline, std::int64_t n, const CycleControl& control);
  CycleResult run();

 private:
  StepPlan plan(std::int64_t s) const;
  StepTotals advance(const StepPlan& step);
  StepTotals retake_to(std::int64_t cycle);
  bool escapes(bool replay);
  bool sort_balls();   // whether any ball moved
  bool rescue(std::int64_t bad_cycle);
  CycleResult& unstable(const StepTotals& sums, std::int64_t s);
  void observe(const StepPlan& step);
  void report_progress(std::int64_t s);
  void defer_last_results();
  // The rescue copy of the state now (a distributed run's: each rank's of its part where the parts
  // are live, else gathered to rank 0 first, which alone keeps its balls and pairs).
  void take_copy() { pipeline_.take_rescue(model_); }
  CycleResult& finish();

  Model& model_;
  Pipeline& pipeline_;
  const std::int64_t n_;
  const CycleControl& control_;
  CycleResult result_;
  StepKernels kernels_;
  double cap_ = 0;         // the Hertz cap of the critical step
  double free_step_ = 0;   // the estimate between contact episodes (next_critical_step)
  bool servo_reads_table_ = false;
  // The servo's first reading where a distributed run makes it without the whole model's table on
  // every rank (nothing touches in rank 0's, or summed on the kept parts: CycleRun's constructor),
  // read at the run's first step in place of the table's.
  std::optional<ContactMoments> first_reading_;
  // A distributed run's output steps gather to rank 0 alone, which alone runs the observers.
  bool output_on_root_ = false, observes_ = true;
  std::optional<EnergyGuard> guard_;   // made once the masses and the step are known
  Clock::time_point loop_start_, last_progress_;
  std::int64_t start_cycle_ = 0;
  bool sorted_at_start_ = false;   // the first step's sort was done before the first search
  // The sort of the step about to be taken, made before its rescue copy (run(): a CYCLE's last
  // step whose results are deferred), at this cycle; advance() then makes none (-1: none made).
  std::int64_t sorted_ahead_ = -1;
};

CycleRun::CycleRun(Model& model, Pipeline& pipeline, std::int64_t n, const CycleControl& control)
    : model_(model), pipeline_(pipeline), n_(n), control_(control) {
  if (model.balls.size() == 0)
    throw std::runtime_error("there are no balls to cycle (GEN, BALL or LATTICE first)");
  // The parts a distributed CYCLE left (Pipeline::parts_live) are gone on from where nothing needs
  // the whole model first: the first step's sort, a servo's first reading of the contact table (a
  // step estimated afresh is estimated on the parts). Then the ranks other than 0 hold no more of the whole model than the
  // balls' ids, types and radii, and rank 0's is current; what changed the materials or the
  // fixities since the last CYCLE (PROP, FIX, FREE) changed them on the parts, which take the
  // materials and their masses from them at the start (Pipeline::parts_take_settings).
  const Space& cell = model.space;
  servo_reads_table_ =
      cell.periodic && (cell.servo_on[0] || cell.servo_on[1] || cell.servo_on[2]) && !cell.servo_measured_valid;
  // A setting changed since the last CYCLE deferred its last step's results (Session::settings):
  // this run's steps read the new one, so that step is not one its rescue could take again; the
  // results are of no use to it (but to a servo's first reading, which makes them as they were).
  if (pipeline.results_deferred(model) && !pipeline.deferred().same_settings(model.settings) && !servo_reads_table_)
    pipeline.clear_deferred();
  pipeline.refresh_whole(model, false);   // (stale; not where hollow: what follows reads its light arrays)
  // The first step's sort: on the parts (sort_balls), where rank 0's whole model is hollow; else
  // rank 0 alone sorts, the parts given back to it first (it holds the whole model already).
  // (Not where the parts were put in space order at this cycle: Pipeline::parts_from_records.)
  const bool presorted = pipeline.parts_in_space_order(model);
  if (pipeline.parts_live(model) && sort_due(model) && !pipeline.results_deferred(model) && !presorted &&
      !pipeline.whole_hollow(model))
    pipeline.release_parts(model);
  // A servo's first reading of the contact table where rank 0 alone holds the whole model (no
  // part kept, no step deferred): where nothing in its table touches and no capillary bridge holds,
  // the reading is of no force and no stiffness, as serial's is (a search makes no contact touch),
  // and no rank needs the whole model for it (GEN, SERVO and CYCLE: the first reading of most
  // servo decks). (Rank 0's answer, which the others take.)
  if (servo_reads_table_ && pipeline.distributed() && comm::size() > 1 && !pipeline.parts_live(model) &&
      !pipeline.results_deferred(model)) {
    std::int64_t none = 0;
    comm::on_root([&] { none = touches_nothing(model) ? 1 : 0; }, "reading the contact table");
    comm::broadcast(none);
    if (none != 0) {
      first_reading_ = ContactMoments{};
      servo_reads_table_ = false;
    }
  }
  // Where the ranks keep parts that alone hold the model (a SERVO between CYCLEs): the reading
  // summed on them, the results the last CYCLE deferred made there first, as serial's make_results
  // makes them for its reading (Pipeline::servo_reading_on_parts).
  if (servo_reads_table_ && pipeline.distributed() && comm::size() > 1) {
    first_reading_ = pipeline.servo_reading_on_parts(model);
    if (first_reading_) servo_reads_table_ = false;
  }
  // Else it needs the whole model's list searched on every rank: handed over first, from the parts
  // or from rank 0.
  if (servo_reads_table_) pipeline.share_whole(model);
  // (The parts' settings, materials and masses first: what follows reads them, a rebuild of their
  // lists too.)
  if (pipeline.parts_live(model)) pipeline.parts_take_settings(model);
  // The first step's sort (Model::order) before the run's first search; not where a step a CYCLE
  // deferred is to be taken again first (make_results: it is of the order before), which the first
  // step then sorts after.
  auto sort_at_start = [&] {
    if (sorted_at_start_ || !sort_due(model) || pipeline.results_deferred(model)) return;
    if (!presorted) sort_balls();
    sorted_at_start_ = true;
  };
  // (A step estimated afresh reads the pairs touching now: the parts' list made current first,
  // after the sort, as serial's sorts before its list is prepared: a wrap of a ball across a
  // periodic face in it would move a centre the sort reads.)
  if (pipeline.parts_live(model) && !(model.critical_dt > 0)) {
    sort_at_start();
    if (!pipeline.parts_go_on(model)) pipeline.share_whole(model);
  }
  // The ranks other than 0 may hold no more of the model than its balls' ids, types and radii, and
  // no part (after a command rank 0 alone ran: Pipeline::others_hollow): rank 0 then checks, sorts
  // and decides alone, and sends each rank its part at the split.
  const bool from_parts = pipeline.parts_live(model);
  const bool from_root = pipeline.others_hollow();
  const bool whole_here = !(from_parts || from_root) || comm::root();
  // (Rank 0's whole model hollow: the parts hold the masses, made from the materials as they are
  // now when they took the settings, above.)
  const bool hollow = pipeline.whole_hollow(model);
  check_ready(model);
  if (whole_here && !hollow) update_mass(model);
  auto check_masses = [&] {
    const Balls& b = model.balls;
    for (std::size_t k = 0; k < b.size(); ++k)
      if (std::string why = ball_mass_problem(b.id[k], b.mass[k], b.inertia[k], b.rad[k]); !why.empty())
        throw std::runtime_error(why);
  };
  if (from_root) comm::on_root(check_masses, "checking the balls' masses");
  else if (!from_parts) check_masses();
  sort_at_start();
  // The history parts the laws of this run use, zero where a law is new since the pairs were found.
  model.contacts.use_history(laws_with_history(model));
  kernels_ = from_parts || from_root ? make_kernels(model, features_from_root(model, pipeline)) : make_kernels(model);
  cap_ = hertz_step_cap(model);
  // The estimate between contact episodes, below which the held critical step is kept (the whole
  // model's, before a distributed run's parts take their balls; going on from them, rank 0's).
  if (hollow) free_step_ = pipeline.part_free_step(kernels_.features, cap_);
  else if (whole_here) free_step_ = contact_free_step(model, kernels_.features, cap_);
  if ((from_parts || from_root) && !hollow) {
    std::vector<double> free_step{free_step_};
    comm::broadcast(free_step);
    free_step_ = free_step[0];
  }
  // A servo not yet run reads its first stress from the contact table (cell_before_step): the whole
  // model's list is then searched before the first step, where a distributed run's parts would
  // search it at their split. (Parts gone on from need no search: their steps test their lists.)
  // Not where the first step sorts before anything reads the list (a CYCLE after one that deferred
  // its last step's results, on a cycle of the sort): the step prepares after its sort, as the
  // unbroken run's does. Prepared here, the balls across a periodic face were wrapped before the
  // sort, whose order (and so the sums' order) then differed from the unbroken run's.
  const bool sorts_first = sort_due(model) && !sorted_at_start_ && model.critical_dt > 0 && !servo_reads_table_;
  if (!from_parts && !sorts_first) pipeline.prepare(model, !servo_reads_table_);
  // (Before the critical step, which may leave the ranks other than 0 with their parts alone.)
  guard_.emplace(model);
  if (!(model.critical_dt > 0)) {
    try {
      model.critical_dt = pipeline.critical_timestep(model, kernels_.features, cap_);
    } catch (...) {   // (its search on the parts failed on a rank: the others' whole models come back)
      pipeline.sync_all(model);
      throw;
    }
  }
  if (servo_reads_table_) {
    make_results(model, pipeline);
    // (Under mpirun rank 0 alone may hold them, made for what a command read: every rank's servo
    // reads them, from the one list every rank searched.)
    if (pipeline.distributed() && comm::size() > 1) broadcast_results(model);
  }
  output_on_root_ = pipeline.distributed() && comm::size() > 1;
  observes_ = !output_on_root_ || comm::root();
  // A CYCLE right after one that deferred its last step's results: the rescue copy, of the step
  // before, is kept as this run's copy (the rescue takes that step again).
  if (!pipeline.results_deferred(model) && !control.replay) take_copy();
  pipeline.clear_deferred();
  if (control.defer_results || control.leave_results) {
    // Results not of this state are of no use (the servo has read them already); those left on
    // the parts are not made in rank 0's table.
    if (model.contacts.results_cycle != model.cycle && !servo_reads_table_) model.contacts.drop_results();
  } else {
    model.contacts.keep_results();
  }
  loop_start_ = last_progress_ = Clock::now();
  start_cycle_ = model.cycle;
  pipeline.times() = PhaseTimes{};
}

// The loop reads as a step's life: what it writes, the step, the guard, the START box's faces, the
// observers, the rescue copy, progress, Ctrl-C, and the deferred results of the last. An error
// mid-run (every rank meets it at the same step) leaves the model as the last step made it.
CycleResult CycleRun::run() {
  try {
    for (std::int64_t s = 1; s <= n_; ++s) {
      const StepPlan step = plan(s);
      if (step.deferred) {
        // The copy the results are made from later is of the order the step is taken in: the
        // step's sort first (on the ranks' parts it changes their edition, and a copy of the
        // order before could not be put back on them in place).
        bool sorted = false;
        if (sort_due(model_) && !(sorted_at_start_ && model_.cycle == start_cycle_)) {
          sorted = sort_balls();
          sorted_ahead_ = model_.cycle;
        }
        // (And the parts' lists rebuilt first where they are stale: a copy of the parts before
        // a rebuild in the step could not be put back in place.)
        const bool rebuilt = pipeline_.rebuild_before_copy(model_);
        if (sorted || rebuilt || pipeline_.rescue().cycle != model_.cycle) take_copy();
      }
      const StepTotals sums = advance(step);
      if (step.energies) {
        if (guard_->failed(model_, sums, s, result_)) return unstable(sums, s);
      } else if (step.kinetic) {
        guard_->note_kinetic(sums, model_.cycle);
      }
      result_.done = s;
      if (escapes(false)) {
        if (step.energies || !result_.left_box) return finish();
        // A ball left across a `stop` face at a step the guard did not check: an unstable step
        // is told as such (and the model put back), not as a ball that left. The steps from the
        // rescue copy are taken again (the same bits), this one with its energy terms.
        const StepTotals checked = retake_to(model_.cycle);
        if (guard_->failed(model_, checked, s, result_)) return unstable(checked, s);
        escapes(true);   // (its balls destroyed were counted the first time)
        return finish();
      }
      observe(step);
      // The rescue steps on to cycles on kSnapshotEvery. Not after the last step: the next CYCLE
      // takes its own copy at its start, and a deferred last step needs the copy of the step before.
      if (s < n_ && (s + 1) % kSnapshotEvery == 0) take_copy();
      report_progress(s);
      if (step.stopping) {   // seen before this step, which therefore wrote the details
        result_.interrupted = s < n_;
        break;
      }
      if (step.deferred) defer_last_results();
    }
  } catch (...) {
    // (Not a step taken again, which leaves the parts to its caller: results_onto_parts may drop
    // them for rank 0's model, the state before that step began.)
    if (!control_.replay) pipeline_.sync_all(model_);
    throw;
  }
  return finish();
}

StepPlan CycleRun::plan(std::int64_t s) const {
  StepPlan p;
  p.stopping = control_.interrupt && control_.interrupt->load(std::memory_order_relaxed);
  // Under mpirun every rank takes the same steps: they stop together, agreeing every kAgreeEvery
  // steps (a rank that stopped alone would leave the others waiting for its part).
  if (control_.interrupt && comm::size() > 1)
    p.stopping = s % kAgreeEvery == 0 && comm::any_all(control_.interrupt->load());
  p.observed = control_.after_step && (!control_.reads_contacts || control_.reads_contacts(model_.cycle + 1));
  p.deferred = control_.defer_results && s == n_ && !p.stopping && !p.observed;
  const bool parts_observe = p.observed && control_.after_step_on_parts && control_.keep_parts &&
                             pipeline_.distributed() && !p.stopping &&
                             !(control_.reads_whole && control_.reads_whole(model_.cycle + 1));
  p.leave_results = control_.leave_results && control_.keep_parts && pipeline_.distributed() && s == n_ &&
                    !p.stopping && !p.observed;
  // (A snapshot step's results serve a whole model's copy alone: a copy on the ranks' parts holds
  // none, and rank 0 gathers no whole model for it.)
  const bool copied = !control_.defer_results && (s + 1) % kSnapshotEvery == 0 && !pipeline_.rescue_on_parts();
  p.observed_on_parts = parts_observe && !copied;
  p.last = s == n_;
  p.details = (s == n_ && !p.deferred) || p.stopping || copied || p.observed || p.leave_results;
  p.wall_loads = p.details || s == n_ || (s + 1) % kSnapshotEvery == 0 || (control_.defer_results && s + 1 == n_);
  const std::int64_t reaches = model_.cycle + 1;   // the cycle this step reaches
  p.energies = s == 1 || p.wall_loads || reaches % EnergyGuard::kCheckEvery == 0;
  p.kinetic = p.energies || (reaches + 1) % EnergyGuard::kCheckEvery == 0;
  return p;
}

// One step: the cell and the walls before it, the pipeline's step, and what follows it (the cell's
// strain and tilt, the clock, the works, the next critical step, the energy terms at t).
// step: what it writes and forms (plan()).
StepTotals CycleRun::advance(const StepPlan& step) {
  const bool details = step.details;
  Model& model = model_;
  StepKernels& kernels = kernels_;
  const double dt = model.settings.fixed_dt > 0 ? model.settings.fixed_dt : model.settings.frac * model.critical_dt;
  // Before anything moves: a step that would shear or squash the periodic cell by more than half an
  // edge is refused (no tilt reduction could follow it; the run stays at its last step).
  check_cell_step(model.space, dt);
  kernels.dt = dt;
  // The step before, which moved the balls to where this step's forces are computed (Model::dt;
  // none before a model's first step).
  kernels.dt_prev = model.dt > 0 ? model.dt : dt;
  kernels.dt_mean = 0.5 * (kernels.dt_prev + dt);
  const Space& space = model.space;
  // A servo reads the stress and stiffness of each force pass: the contact loops sum them.
  kernels.moments = space.periodic && (space.servo_on[0] || space.servo_on[1] || space.servo_on[2]);
  kernels.contacts = details ? kernels.contacts_full : kernels.contacts_lean;
  kernels.motion = details ? kernels.motion_full : kernels.motion_lean;
  kernels.walls = details ? kernels.walls_full : kernels.walls_lean;
  // A wall servo reads its wall's loads before every step.
  kernels.wall_loads = step.wall_loads;
  kernels.energies = step.energies;
  kernels.kinetic = step.kinetic;
  for (const Wall& w : model.walls) kernels.wall_loads = kernels.wall_loads || w.servo_on;
  StepSums step_sums;
  const auto step_start = Clock::now();
  // The balls in space order (Model::order) on cycles of the absolute count and at the first step
  // after balls were added: the same steps however the run is cut, on every backend and rank.
  if (sort_due(model) && !(sorted_at_start_ && model.cycle == start_cycle_) && sorted_ahead_ != model.cycle) sort_balls();
  sorted_ahead_ = -1;
  // MEMBRANE follow: the perimeter forces from the positions now, on cycles of the absolute count
  // (the same steps however the run is cut).
  if (model.membrane.follow_every > 0 && model.cycle % model.membrane.follow_every == 0 &&
      !pipeline_.follow_membrane_on_parts(model)) {
    pipeline_.sync_all(model);
    follow_membrane(model);
    pipeline_.loads_changed(model);
  }
  // Periodic space: the servo's rates, from the last force pass (Space::servo_measured).
  FieldChange field;   // the servo's new rates change the balls' velocities: where the pipeline holds them
  cell_before_step(model, dt,
                   space.servo_measured_valid                                     ? &space.servo_measured
                   : first_reading_ && model.cycle == start_cycle_ ? &*first_reading_
                                                                   : nullptr,
                   &field);
  pipeline_.apply_field(model, field);
  if (!model.walls.empty()) walls_before_step(model, dt);
  pipeline_.step(model, kernels, step_sums);
  // A distributed run's ranks step their parts: the model is made current where it is read.
  // (Left: the CYCLE's end syncs, Pipeline::end_cycle. An output step read on the parts: no rank
  // reads its results in the whole model, which stays as a lean step leaves it.)
  const bool read_on_parts = step.observed_on_parts && pipeline_.parts_live(model);
  if (details && !step.leave_results && !read_on_parts) pipeline_.sync(model);
  const StepTotals sums(step_sums);
  model.space.servo_measured_valid = kernels.moments;
  if (kernels.moments) model.space.servo_measured = {sums.force_moment, sums.stiffness_moment};
  cell_after_step(model, dt, kernels.dt_mean, sums.image_power, false);   // periodic space: the cell's work, its new edges, the strain
  pipeline_.reduce_cell_tilt(model);                     // and its tilts, on every copy of the pairs
  pipeline_.times().step += std::chrono::duration<double>(Clock::now() - step_start).count();
  model.cycle += 1;
  if (details && !read_on_parts) model.contacts.results_cycle = model.cycle;
  model.time += dt;
  model.dt = dt;
  model.energy.friction_work += sums.friction_work;
  model.energy.rolling_work += sums.rolling_work;
  model.energy.damping_work += sums.damping_work;
  model.energy.boundary_work += sums.boundary_work;
  model.energy.capillary_work += sums.capillary_work;
  model.energy.bond_break_work += sums.bond_break;
  if (kernels.estimate != StepEstimate::None) {
    const double estimate = std::min(sums.critical_dt, cap_);
    if (std::isfinite(estimate))
      model.critical_dt = next_critical_step(model.critical_dt, estimate, model.settings.frac, free_step_,
                                             kernels.features.hertz);
  }
  // The energy terms at t, the time of this step's force pass: every term there (the works less
  // their parts after t; the cell moves on with the balls, so half its step's work is after t).
  // Formed on the steps plan() says; on the others they are marked as not the state's.
  EnergyAtStep& now = model.energy_at_step;
  now.valid = step.energies;
  if (!step.energies) return sums;
  now.kinetic_translation = sums.kinetic_translation;
  now.kinetic_rotation = sums.kinetic_rotation;
  now.strain = sums.strain;
  now.potential = sums.potential;
  now.damping_ahead = sums.damping_ahead;
  now.capillary_ahead = sums.capillary_ahead;
  now.boundary_ahead = sums.boundary_ahead + (model.space.periodic ? 0.5 * sums.image_power * kernels.dt_mean : 0.0);
  return sums;
}

// The balls in space order (Model::order). Where none moves (the first step's order, put before
// the run's first search: CycleRun's start), the pipeline keeps what it holds.
bool CycleRun::sort_balls() {
  // A distributed run's live parts: the ranks sort them where they are, and their lists stay.
  if (pipeline_.sorts_on_parts(model_)) {
    if (!pipeline_.sort_on_parts(model_)) return false;
    kernels_.laws = make_pair_laws(model_);   // (per-ball type indices)
    return true;
  }
  // (Parts not live: their state to rank 0, which alone sorts; the ranks split afresh.)
  if (pipeline_.distributed()) pipeline_.release_parts(model_);
  if (pipeline_.others_hollow()) {
    // Rank 0 alone holds the balls: it sorts them, and the others take their ids, types and radii
    // in the new order.
    std::int64_t moved = 0;
    comm::on_root([&] { moved = sort_in_space(model_) ? 1 : 0; }, "putting the balls in space order");
    comm::broadcast(moved);
    model_.order.pending = false;
    if (moved == 0) return false;
    broadcast_ball_names(model_.balls);
  } else {
    pipeline_.sync_all(model_);
    if (!sort_in_space(model_)) return false;
  }
  pipeline_.invalidate();
  kernels_.laws = make_pair_laws(model_);   // per-ball type indices
  return true;
}

// START box: balls outside a bounded axis's faces after a step are destroyed (`destroy`) or stop
// the run (`stop`: true, with the message). replay: a step the rescue takes again (it was reported
// the first time).
bool CycleRun::escapes(bool replay) {
  Model& model = model_;
  if (!(model.started && (!model.space.periodic || model.space.mixed()) && pipeline_.may_be_outside_box(model)))
    return false;
  pipeline_.sync_all(model);
  Escapes escaped = find_escapes(model);
  if (escaped.destroy_count > 0) {
    // What the leaving balls carry out is boundary work, so the balance stays closed.
    const Balls& b = model.balls;
    const auto& g = model.settings.gravity;
    for (std::size_t k = 0; k < b.size(); ++k)
      if (escaped.destroy[k])
        model.energy.boundary_work -=
            0.5 * b.mass[k] * (b.vx[k] * b.vx[k] + b.vy[k] * b.vy[k] + b.vz[k] * b.vz[k]) +
            0.5 * b.inertia[k] * (b.wx[k] * b.wx[k] + b.wy[k] * b.wy[k] + b.wz[k] * b.wz[k]) -
            b.mass[k] * (g[0] * b.x[k] + g[1] * b.y[k] + g[2] * b.z[k]);
    if (escaped.stop_ball != ~std::size_t{0} && escaped.destroy[escaped.stop_ball]) escaped.stop_ball = ~std::size_t{0};
    const double held = model.critical_dt;   // fewer balls make no contact stiffer: keep the step
    remove_balls(model, escaped.destroy);
    model.critical_dt = held;
    model.space.destroyed += static_cast<std::int64_t>(escaped.destroy_count);
    if (!replay) result_.destroyed += escaped.destroy_count;
    pipeline_.invalidate();
    kernels_.laws = make_pair_laws(model);   // per-ball type indices
    if (escaped.stop_ball != ~std::size_t{0}) escaped = find_escapes(model);
  }
  if (escaped.stop_ball == ~std::size_t{0}) return false;
  const std::size_t k = escaped.stop_ball;
  const int a = escaped.stop_axis;
  const double x = (a == 0 ? model.balls.x : a == 1 ? model.balls.y : model.balls.z)[k];
  result_.left_box = true;
  result_.message = fmt::format(
      "ball {} left the box through {} = {:.6g} at cycle {} (it is at {} = {:.9g}); the model is kept at that "
      "cycle: DELETE the ball, make the box larger, or let such balls go with START box ... destroy",
      model.balls.id[k], "xyz"[a], x < model.space.lo[a] ? model.space.lo[a] : model.space.hi[a], model.cycle,
      "xyz"[a], x);
  return true;
}

// The rescue from a failed step at bad_cycle: back to the copy. The copy of the CYCLE's start is
// its last good state as it is. The later copies are of the state a step before a multiple of
// kSnapshotEvery steps: the rescue takes that step again, writing the results, so the model is at
// the multiple and prints as it was then. The same bits as the first time: nothing in a step
// depends on when the pair list was made (the cut tests hold this), and the observers do not run
// again; so is a copy kept from the CYCLE before, of its last step's step before (defer_results).
// (Where the failing step is that step, the model stays at the copy.) Returns whether the results
// are those of the state it is left in (false only where a step after the copy overwrote them:
// Snapshot::restore).
bool CycleRun::rescue(std::int64_t bad_cycle) {
  if (control_.replay)
    throw std::logic_error(fmt::format("internal error: cycle {} taken again to make its contact results failed",
                                       model_.cycle + 1));
  bool current = pipeline_.restore_rescue(model_);
  pipeline_.invalidate();
  kernels_.laws = make_pair_laws(model_);   // the balls destroyed since the copy are back
  if (model_.cycle != start_cycle_ && model_.cycle + 1 < bad_cycle) {
    advance(StepPlan::all());
    escapes(true);
    current = true;
  }
  pipeline_.sync_all(model_);
  return current;
}

// Back to the rescue copy, and the steps from it to the one that reached `cycle` taken again (the
// same bits; the observers do not run again), the last with everything formed: its sums.
StepTotals CycleRun::retake_to(std::int64_t cycle) {
  result_.left_box = false;
  result_.message.clear();
  pipeline_.restore_rescue(model_);
  pipeline_.invalidate();
  kernels_.laws = make_pair_laws(model_);   // the balls destroyed since the copy are back
  while (model_.cycle + 1 < cycle) {
    StepPlan p;
    p.kinetic = model_.cycle + 2 == cycle;   // (the guard's test of velocities that flip sign)
    const StepTotals sums = advance(p);
    if (p.kinetic) guard_->note_kinetic(sums, model_.cycle);
    escapes(true);
  }
  return advance(StepPlan::all());
}

// The guard stopped step s: what it saw, then the rescue, then the message with what to try.
CycleResult& CycleRun::unstable(const StepTotals& sums, std::int64_t s) {
  const GuardStop stop = guard_->stop(model_, sums, s);
  const bool results_current = rescue(stop.bad_cycle);
  result_.unstable = true;
  result_.done = model_.cycle - start_cycle_;
  result_.message = guard_->message(stop, model_, results_current);
  return finish();
}

// The observers (histories, dumps). Rank 0 alone writes what an observer records (a history's
// rows, a dump's files): its failure (a full disk) is every rank's, agreed before the next step, so
// that no rank goes on alone into the next step's collective calls and waits there for ever.
void CycleRun::observe(const StepPlan& step) {
  if (!control_.after_step) return;
  const bool observed = step.observed;
  const auto output_start = Clock::now();
  if (step.observed_on_parts && pipeline_.parts_live(model_)) {
    // Every rank records from the sums merged over the parts (its failure agreed there). The
    // results this step wrote on the parts are then let go, as a lean step's, so that the next
    // stale list may still be rebuilt on the parts; but the CYCLE's last step's, which they keep
    // (Pipeline::end_cycle: results_on_parts).
    control_.after_step_on_parts(model_);
    if (!step.last) pipeline_.forget_part_results(model_);
  } else {
    if (comm::size() > 1 && observed)
      comm::together([&] { if (observes_) control_.after_step(model_); }, "recording the output");
    else if (observes_)
      control_.after_step(model_);
    if (output_on_root_ && observed && control_.share_output) control_.share_output();
  }
  pipeline_.times().output += std::chrono::duration<double>(Clock::now() - output_start).count();
}

void CycleRun::report_progress(std::int64_t s) {
  if (!control_.progress || (s & 7) != 0) return;
  const auto now = Clock::now();
  if (std::chrono::duration<double>(now - last_progress_).count() > kProgressSeconds) {
    control_.progress(s, n_);
    last_progress_ = now;
  }
}

// The last step's results are dropped, to be made again when read, which needs a copy of the step
// before (Pipeline::results_deferred).
void CycleRun::defer_last_results() {
  if (pipeline_.rescue().cycle + 1 != model_.cycle)
    throw std::logic_error(fmt::format(
        "internal error: the rescue copy is of cycle {}, not the step before cycle {} whose contact results it is "
        "to make", pipeline_.rescue().cycle, model_.cycle));
  model_.contacts.drop_results();
  pipeline_.defer_results(model_);
}

// Copies the timings into the result whichever way the loop ends.
CycleResult& CycleRun::finish() {
  pipeline_.end_cycle(model_, control_.keep_parts);   // a distributed run's last step, on every rank
  result_.seconds = std::chrono::duration<double>(Clock::now() - loop_start_).count();
  result_.times = pipeline_.times();
  if (!result_.unstable) result_.energy_warning = balance_warning(model_, result_, guard_->floor());
  return result_;
}

}  // namespace

CycleResult run_cycles(Model& model, Pipeline& pipeline, std::int64_t n, const CycleControl& control) {
  if (n <= 0) return {};
  CycleRun run(model, pipeline, n, control);
  return run.run();
}

}  // namespace trubal
