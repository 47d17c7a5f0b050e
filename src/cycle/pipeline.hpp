// The one step pipeline every run uses: wrap the balls into a periodic cell, keep the pair list
// (the backend finds pairs; the skin rule of cycle/verlet.hpp says when), install it with its
// history, then the contact loops and the law of motion over the thread pool (cycle/parallel_step.hpp).
// Threads are a setting of the pipeline; the backend is only its pair search.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "backends/backend.hpp"
#include "cycle/brick_step.hpp"
#include "cycle/kernels.hpp"
#include "cycle/parallel_step.hpp"
#include "cycle/phase_times.hpp"
#include "cycle/snapshot.hpp"
#include "cycle/step_policy.hpp"
#include "cycle/step_scratch.hpp"
#include "cycle/team.hpp"
#include "cycle/timed_choice.hpp"
#include "cycle/verlet.hpp"
#include "physics/overlap.hpp"
#include "physics/scene.hpp"
#include "support/thread_pool.hpp"

namespace trubal {

// Counters for tests and PRINT counters.
struct PipelineCounters {
  std::size_t rebuilds = 0;        // pair searches that built a new list
  int threads_used = 0;            // threads the steps share their work among (0 before the first)
  double skin = 0;                 // of the list now (0 for a backend that keeps none)
  std::uint64_t pair_tests = 0;    // the backend's count, where it keeps one
  std::int64_t results_made = 0;   // a CYCLE's last step taken again to make the contact results read
  std::int64_t results_gathered = 0;   // the results made on the parts, gathered whole to rank 0
  BrickStep::Counts parts;         // the spatial decomposition's (the ranks' or the threads')
  std::vector<double> cycle_peaks_mib;   // per rank: peak memory by the end of the last distributed CYCLE
  double whole_arrays_mib = 0, part_arrays_mib = 0;   // this rank's arrays in the last distributed step
  std::int64_t hand_overs = 0;     // the whole model handed to every rank for a command, from kept parts
  std::int64_t cycle_hand_overs = 0;   // and for a CYCLE (a periodic servo's first reading of the table, ...)
  std::int64_t copies_on_parts = 0;   // the parts put back to their rescue copies in place (restore_rescue_on_parts)
  std::int64_t parts_from_records = 0;   // the parts made from balls the ranks kept (parts_from_records)
  std::int64_t parts_from_saves = 0;     // the parts made from a save a RESTART read (parts_from_file)
};

class Pipeline {
 public:
  // threads <= 0: the backend's default. policy: its owner's, which outlives the pipeline (the
  // Session's); none: the pipeline keeps the defaults of its own.
  Pipeline(std::unique_ptr<Backend> backend, int threads, StepPolicy* policy = nullptr);

  const Backend& backend() const { return *backend_; }
  int threads() const { return pool_.size(); }

  // Brings the pair list and its index up to date for the current positions (wrapping balls into
  // a periodic cell first), without computing forces. A distributed run's ranks search a stale list
  // on their parts when they are made (parts_may_search: nothing reads the whole model's list before
  // the next step), so that the ranks other than 0 never hold the whole model's list in a CYCLE.
  void prepare(Model& model, bool parts_may_search = true);
  // One step: prepare, contact forces and each ball's sums, motion.
  void step(Model& model, const StepKernels& kernels, StepSums& sums);
  // The balls or the table were changed outside cycling: the next step searches afresh.
  void invalidate();
  // The model was put back to its state before the last step (make_results): the next step decides
  // on a search as that step did, so the list it makes (or keeps) is that step's.
  void rewind_step();
  // Makes the model current where a distributed run's ranks step their parts of it (BACKEND mpi,
  // cycle/brick_step.hpp): a collective call, made by every rank at the same step. Else nothing.
  // sync: rank 0's model alone (what rank 0 alone reads: the output, the rescue copy); sync_all:
  // every rank's (what every rank acts on: the whole model stepped through, the CYCLE's end).
  void sync(Model& model);
  void sync_all(Model& model);
  // At the CYCLE's end. keep_parts, in a distributed run on several ranks: sync (rank 0's model
  // made current but for the contact results a step taken again on the parts wrote, which stay
  // there: results_on_parts), and each rank keeps its part, which the next CYCLE goes on from
  // (parts_live); else share_whole.
  void end_cycle(Model& model, bool keep_parts = false);
  // sync_all, the parts released before rank 0 hands the whole model to the others (the next
  // CYCLE's prepare would drop them in any case): a collective call where parts_live.
  // for_command: a command needs the whole model (Session::whole_everywhere), counted where the
  // parts were kept (PipelineCounters::hand_overs).
  void share_whole(Model& model, bool for_command = false);
  // Rank 0's model made current from the kept parts, which every rank then releases (a collective
  // call where parts_live): a command that rank 0 alone runs changes the model next
  // (Session::model_on_zero).
  void release_parts(Model& model);
  // The ranks other than 0 hold the model's balls' ids, types and radii alone, and no part (after
  // release_parts, or the light state of a command rank 0 alone ran: Session::light_everywhere); the
  // same answer on every rank. Whatever needs the whole model on every rank (sync_all, share_whole,
  // a search or a step through it) hands it over first (hand_over_to_hollow, a collective call); a
  // CYCLE's split does not need it: rank 0 sends each rank its part.
  bool others_hollow() const { return others_hollow_; }
  void set_others_hollow() { others_hollow_ = comm_ranks_ > 1; }
  // Whether a distributed run's ranks hold their live parts of this model (between CYCLEs: after an
  // end_cycle that kept them), the ranks other than 0 no more of the whole model than the balls'
  // ids, types and radii (hollow). The same answer on every rank.
  // Before the copy of the step before a CYCLE's last step is taken, the step's results deferred
  // (a collective call where parts_live, the same answer on every rank): where the kept parts'
  // lists are stale or a ball is outside the cell, they go on now (parts_go_on: the wrap, the
  // rebuild), so that the copy is of the parts as the step goes on from them and can be put back
  // in place when the step is taken again (results_onto_parts; a copy of the parts before a
  // rebuild cannot, and the model would be gathered to rank 0 for it). Not a wrap where a periodic
  // servo drives the cell: the step wraps after the servo's new rates, which the wrap reads (nor
  // beside a following membrane). Whether the parts changed.
  bool rebuild_before_copy(Model& model);
  bool parts_live(const Model& model) const { return distributed() && comm_ranks_ > 1 && bricks().live_for(model); }
  // Rank 0's whole model no longer holds the parts' state (a failed make_results_to_read put it
  // part way back); refresh_whole, a collective call where parts_live, gathers it again.
  void mark_whole_stale() { whole_stale_ = true; }
  // The kept parts hold the contact results of the model's state, which rank 0's table lacks: the
  // step a CYCLE deferred, taken again on them (results_onto_parts, cycle/run.hpp), wrote them there
  // (its results deferred all the same: rank 0 keeps the copy of the step before, make_results'
  // way, should the parts end first). The same on every rank.
  bool results_on_parts(const Model& model) const { return parts_live(model) && bricks().results_left(); }
  // The results the parts' last step wrote were read there (CycleControl::after_step_on_parts):
  // no sync gathers them, and the next stale list may be rebuilt on the parts.
  void forget_part_results(const Model& model) {
    if (!parts_live(model)) return;
    for (auto& part : bricks_) part->forget_step_results();
  }
  // Where results_onto_parts has a step to take again: the parts kept, the CYCLE's results
  // deferred and not on them yet. The same on every rank.
  bool results_to_make_on_parts(const Model& model) const {
    return parts_live(model) && !bricks().results_left() && results_deferred(model);
  }
  // Those results into rank 0's table (a collective call where results_on_parts); the CYCLE's
  // results are then made, as make_results leaves them, and its copy of the step before freed.
  void gather_part_results(Model& model);
  // Rank 0 runs a command alone (OnRanks::RankZero) while the others serve its requests
  // (Session::run_on_root): serve_root, on the others, until rank 0's end_requests. What rank 0 may
  // ask, each after the results are made on the parts (results_onto_parts): nothing more
  // (request_results_onto_parts), the results gathered whole (request_part_results), or one array
  // of them (request_result_array).
  void start_requests() { serving_ = true; }
  void end_requests();
  void serve_root(Model& model);
  bool serving() const { return serving_; }
  // Rank 0, serving(): every rank gathers the parts' results (the others in serve_root).
  void request_part_results(Model& model);
  // Rank 0, serving(): the results made on the parts where the CYCLE deferred them
  // (results_onto_parts, cycle/run.hpp), every rank taking part (the others in serve_root).
  void request_results_onto_parts(Model& model);
  // Rank 0, serving(), where results_on_parts: array k of them (BrickStep::gather_result_array)
  // into *reals or *bytes, the parts keeping theirs (the others in serve_root).
  void request_result_array(Model& model, std::size_t k, std::vector<double>* reals, std::vector<std::uint8_t>* bytes);
  // Rank 0's whole model made current from the kept parts where it is stale (mark_whole_stale) or,
  // even_hollow, hollow (BrickStep::hollow_whole: a distributed CYCLE's end leaves it so); a
  // collective call where parts_live, else nothing.
  void refresh_whole(Model& model, bool even_hollow = true);
  // Whether refresh_whole has work (rank 0's answer; the others' may differ).
  bool whole_to_refresh(const Model& model) const {
    return parts_live(model) && (whole_stale_ || bricks().whole_hollow());
  }
  // Rank 0, serving(): refresh_whole where it has work, every rank taking part (the others in
  // serve_root).
  void request_whole(Model& model);
  // Sums over the ranks' kept parts of what each holds of its own (BrickStep::own_counts): a
  // collective call where parts_live, every rank given the sums; zeros elsewhere.
  struct PartCounts {
    std::size_t touching = 0, wall_touching = 0, bridges = 0, wall_bridges = 0, spinning = 0, applied = 0, moments = 0;
    // What scene_features reads of the balls, where rank 0's whole model does not hold it.
    BallFlags flags() const { return {spinning > 0, applied > 0, moments > 0}; }
  };
  // The contact-free step (physics/timestep.hpp contact_free_step) of the kept parts' balls, each
  // rank's own: the smallest over the ranks (a collective call where parts_live).
  double part_free_step(const Features& features, double cap) { return bricks().free_step(features, cap); }
  PartCounts part_counts(const Model& model);
  // Rank 0, serving(), where parts_live: part_counts, the results made on the parts first where a
  // CYCLE deferred them (every rank taking part: the others in serve_root).
  PartCounts request_part_counts(Model& model);
  // The largest overlap of the model (physics/overlap.hpp) from the kept parts, each rank's own
  // pairs and wall contacts, ties to the first in the whole model's tables (a collective call where
  // parts_live, every rank given the answer; elsewhere rank 0's whole model's).
  LargestOverlap largest_overlap_on_parts(const Model& model, double threshold);
  // Love's formula's sums (physics/measure.hpp stress_sums) over the kept parts, each rank's own
  // pairs and wall contacts, merged exactly: the whole model's bits (a collective call where
  // parts_live, every rank given the sums). request_stress: rank 0, serving(), the results made on
  // the parts first where a CYCLE deferred them (the others in serve_root).
  StressSums stress_on_parts(const Model& model);
  StressSums request_stress(Model& model);
  // The same of the contact measures' sums (physics/measure.hpp contact_sums).
  ContactSums contact_sums_on_parts(const Model& model);
  ContactSums request_contact_sums(Model& model);
  // And of a measurement sphere's sums (physics/measure_sphere.hpp sphere_sums), each rank's own
  // balls, pairs and wall contacts: the measurement, the whole model's bits (elsewhere rank 0's
  // whole model's). Throws as sphere_measurement, on every rank alike.
  SphereMeasurement sphere_on_parts(const Model& model, const MeasureSphere& sphere);
  SphereMeasurement request_sphere(Model& model, const MeasureSphere& sphere);
  // A periodic servo's first reading from the kept parts where rank 0's whole model is hollow (a
  // collective call, every rank given it): the results the CYCLE deferred made on them first
  // (results_onto_parts: serial's make_results), then Love's sums and the stiffness sums
  // (physics/cell.hpp servo_stiffness_sums) merged exactly, as ContactMoments (physics/cell.cpp
  // cell_before_step reads them as it reads a step's: the same bits as its reading of the whole
  // table). Empty where the parts do not hold the results.
  std::optional<ContactMoments> servo_reading_on_parts(Model& model);
  // Rank 0, serving(), where whole_hollow: the parts' state streamed for SAVE, every rank taking
  // part (the others in serve_root): the pairs SAVE keeps placed in the whole order (touching in
  // the results the parts hold, or with history) and the wall contacts, their counts; array k of a
  // table (BrickStep::stream_table: 0 the balls, 1 the placed pairs, 2 the wall contacts),
  // `write(chunk)` here for each chunk in turn; the places let go after.
  std::uint64_t request_place_pairs(Model& model);
  std::uint64_t request_place_walls(Model& model);
  void request_stream(Model& model, int table, std::size_t k, const std::function<void(const std::vector<double>&)>& write);
  void request_free_saved();
  // Rank 0, serving(), where whole_hollow: the bonds' state and fates the parts hold gathered into
  // rank 0's bond table (which a hollow whole model keeps), nothing else: PRINT bonds and a bonded
  // model's SAVE read the table there (BrickStep::bonds_to_root).
  void request_bonds(Model& model);
  // DELETE on the kept parts of a model with no bond (BrickStep::delete_balls): a collective call
  // where parts_live; the next step searches afresh, as serial's after remove_balls.
  std::size_t delete_on_parts(Model& model, const Range& range);
  // A bonded model's dump from the kept parts (a collective call where parts_live): the bonds'
  // state and the balls' centres into rank 0's hollow whole model, which its bonds' file reads
  // (BrickStep::bonds_to_root, centres_to_root).
  void bonds_and_centres_to_root(Model& model) {
    bricks().bonds_to_root(model);
    bricks().centres_to_root(model);
  }
  // Rank 0, serving(), where whole_hollow: PRINT balls' and contacts' rows from the parts, in order
  // (BrickStep::stream_ball_rows, stream_contact_rows), those of `range` (every one where empty),
  // take(row) here on each.
  void request_ball_rows(Model& model, const std::function<void(const double*)>& take, const Range& range = {});
  void request_contact_rows(Model& model, bool bridges, const std::function<void(const double*)>& take,
                            const Range& range = {});
  // INIT, APPLY, FIX, FREE and GROUP on the kept parts (BrickStep::change_balls, ids_where):
  // collective calls where parts_live.
  std::size_t change_balls_on_parts(const Model& model, const Range& range,
                                    const std::function<void(Balls&, std::size_t)>& change) {
    return bricks().change_balls(model, range, change);
  }
  std::vector<std::int64_t> ids_on_parts(const Model& model, const Range& range) { return bricks().ids_where(model, range); }
  // A ball's history item from the kept parts (BrickStep::own_ball_values): a collective call where
  // parts_live.
  std::vector<double> ball_on_parts(std::int64_t id, std::size_t count,
                                    const std::function<std::vector<double>(const Balls&, std::size_t)>& read) {
    return bricks().own_ball_values(id, count, read);
  }
  // HIST's platen balls of these ids from the kept parts (BrickStep::own_platen_balls): a
  // collective call where parts_live.
  PlatenBalls platens_on_parts(const std::vector<std::int64_t>& ids) { return bricks().own_platen_balls(ids); }
  // MEMBRANE follow where a distributed run's parts are live (a collective call): the loads made
  // from the loaded balls' centres on the parts, set there and in rank 0's whole model, whose
  // hollow arrays keep the applied loads (physics/membrane.hpp follow_loads). False, doing
  // nothing, elsewhere (the same answer on every rank).
  bool follow_membrane_on_parts(Model& model);
  // HIST bonds from the kept parts (BrickStep::own_bond_counts): a collective call where parts_live.
  BondCounts bond_counts_on_parts() { return bricks().own_bond_counts(); }
  // The balls' fixities from the kept parts into rank 0's hollow whole model, which keeps them (FIX
  // and FREE on the parts), a chunk at a time: a collective call where whole_hollow.
  void fixities_to_root(Model& model);
  // DUMP's rows from the kept parts, merged to rank 0 in the whole model's order (io/vtk.hpp;
  // BrickStep::vtk_ball_rows, vtk_line_rows; the lines' count is part_counts' touching):
  // collective calls where parts_live, every rank in them (a CYCLE's output step, or DUMP, which
  // every rank runs), take(row) on rank 0.
  void vtk_ball_rows(const std::function<void(const double*)>& take) { bricks().vtk_ball_rows(take); }
  void vtk_line_rows(const Model& model, const std::function<void(const double*)>& take) {
    bricks().vtk_line_rows(model, take);
  }
  // Whether rank 0's whole model holds none of the state but its light arrays: the kept parts
  // alone hold it (BrickStep::hollow_whole). The same answer on every rank.
  bool whole_hollow(const Model& model) const { return parts_live(model) && bricks().whole_hollow(); }
  // The settings (Model::settings: DAMP, FRAC, TSTEP, GRAV, which leave the parts kept) and the
  // materials (PROP) to each part from the model, its balls' masses made from them, at a CYCLE's
  // start from kept parts (a collective call: BrickStep::take_settings).
  void parts_take_settings(const Model& model) {
    for (auto& part : bricks_) part->take_settings(model);
  }
  // Whether the parts can take the next step as they are (a collective call; false where none is
  // live): the balls across a periodic face wrapped on the parts, a stale list rebuilt on them,
  // where they can; false where that step must go through the whole model.
  bool parts_go_on(Model& model);
  // The next step searches the lists afresh, on the parts where they are live (as serial's after an
  // edit between CYCLEs: Session::edit_walls).
  void search_next_step() { search_next_step_ = true; }
  // The bytes of this rank's part (0 where none is live).
  std::size_t part_bytes_now() const { return bricks().live() ? bricks().part_bytes() : 0; }
  // The bytes of the contact results this rank's part holds (0 where none is live).
  std::size_t part_result_bytes_now() const { return bricks().live() ? bricks().part_result_bytes() : 0; }
  // Between steps: the velocity field change of new strain rates (cell_before_step's, deferred), on
  // the balls wherever they are stepped; the tilts of the cell kept within half an edge
  // (reduce_cell_tilt) on every copy of the pair list.
  void apply_field(Model& model, const FieldChange& change);
  // Between CYCLEs, on kept parts (parts_live): the change on the parts' balls (their work summed,
  // a collective call) and on rank 0's whole model alike, so that it stays current without a gather
  // (which would bring the parts' unbalanced forces of a lean last step over those rank 0 made).
  void apply_field_kept(Model& model, const FieldChange& change);
  // The balls' applied loads changed between steps (a following membrane's): on every copy.
  void loads_changed(Model& model);
  void reduce_cell_tilt(Model& model);
  // Whether some ball may be outside a bounded axis of the START box after the last step (false
  // only where a distributed run's ranks found none; the caller then need not sync to look).
  bool may_be_outside_box(const Model& model) const;

  // How the steps are shared where the default is a timed choice, and the faults a test injects
  // (cycle/step_policy.hpp): read at each step, by this pipeline and its parts.
  StepPolicy& policy() { return *policy_; }
  const StepPolicy& policy() const { return *policy_; }

  PipelineCounters counters() const;
  std::vector<std::pair<std::string, std::string>> info() const;
  // Time spent in each phase since reset_times().
  const PhaseTimes& times() const { return times_; }
  PhaseTimes& times() { return times_; }

  // run_cycles' rescue copy of the state, kept between CYCLEs (cycle/snapshot.hpp). In a distributed
  // run only rank 0 holds its balls and pairs (the others, the rest: Snapshot::take_light); taking it
  // follows sync(), and putting it back is a collective call, rank 0 handing the state to the others.
  // Where the ranks' parts are live (a CYCLE's copies after its split), each rank keeps its own
  // part's copy instead (BrickStep::keep_copy) and the light state: no rank holds a copy of the
  // whole model, and putting it back gathers the parts' copies to rank 0 first.
  const Snapshot& rescue() const { return rescue_; }
  void take_rescue(Model& model);
  // Whether the copy is the ranks' parts' (the same answer on every rank).
  bool part_rescue() const { return part_rescue_; }
  // The bytes of the copy's arrays this rank holds (PRINT info).
  std::size_t rescue_bytes() const { return rescue_.bytes() + bricks().copy_bytes(); }
  // Where part_rescue: rank 0's whole model put back to the copy (a collective call), the others'
  // models left as they are; make_results_alone then takes the step again on rank 0 alone.
  void rescue_to_root(Model& model);
  // Where part_rescue and the parts are live and changed only by steps since the copy
  // (BrickStep::restore_copy_in_place): every rank's part and light state put back to the copy in
  // place, the parts staying live (a collective call; rank 0's whole model then holds the state
  // after, the parts' state gathered again at their next sync). Returns false, changing nothing,
  // where they cannot be (the same answer on every rank).
  bool restore_rescue_on_parts(Model& model);
  // Returns Snapshot::restore's answer (rank 0's). The next step searches afresh.
  bool restore_rescue(Model& model);
  // The copy put back on rank 0 alone, the others taking its light state and its balls' ids, types
  // and radii (they hold no balls: others_hollow); the parts dropped (a collective call).
  void restore_rescue_on_root(Model& model);
  // The parts released without a sync (a step taken again on them failed part way: rank 0's whole
  // model, which it did not touch, holds the state), the others left their light state (a
  // collective call); the contact results dropped, not made.
  void drop_parts_unsynced(Model& model);
  // The decomposition's counts (PipelineCounters::parts) set back to `c` on every part.
  void set_part_counts(const BrickStep::Counts& c) {
    for (auto& part : bricks_) part->set_counts(c);
  }
  // The copy's arrays freed (Snapshot::release), after a one-process restore_rescue that needs
  // them no more (make_results).
  void release_rescue() {
    rescue_.release();
    bricks().free_copy();
    part_rescue_ = false;
  }
  bool distributed() const { return mode_ == StepMode::Ranks; }
  // The critical step of the model's state (physics/timestep.hpp, `cap` the Hertz cap), before the
  // CYCLE's first step: where a distributed run's list is to be searched on the parts, they are made
  // and searched now and each rank's own balls give their steps (a collective call), so that no rank
  // but 0 holds the whole list; the ranks other than 0 then hold their part alone.
  double critical_timestep(Model& model, const Features& features, double cap);
  // The ranks' parts made from the balls each rank keeps of a batch deck's BALL lines
  // (Session::place_held_as_parts; BrickStep::split_from_records says what `model` and `records`
  // hold) and their lists searched, rank 0's whole model hollow: as a CYCLE's first split leaves
  // them, the balls never gathered whole. A collective call.
  void parts_from_records(Model& model, std::vector<double>& records);
  // The ranks' parts made from a save a RESTART reads (BrickStep::split_from_file says what `model`
  // and `file` hold; `results`: the save's contact results are its model's state's) and their
  // lists searched, rank 0's whole model hollow: as a CYCLE's end leaves them, the contact results
  // on the parts (results_on_parts). A collective call; on a failure no part is live.
  void parts_from_file(Model& model, TablePieces* file, bool results);
  // Whether the balls are put in space order on the ranks' parts (sort_on_parts): a distributed
  // run's ranks, their parts live. The same answer on every rank.
  bool sorts_on_parts(const Model& model) const { return distributed() && comm_ranks_ > 1 && parts_live(model); }
  // The balls put in space order on the parts (BrickStep::sort_in_space; a collective call, where
  // sorts_on_parts), the whole model's light arrays and the list's reference with them, every
  // rank's whole model hollow: no rank gathers the whole model, and the parts and their lists
  // stay. Returns whether any ball moved (the same on every rank).
  bool sort_on_parts(Model& model);
  // Whether a rescue copy taken in a CYCLE is taken on the ranks' parts (take_rescue: no rank
  // holds the whole model's copy, nor needs the contact results of the step before it).
  bool rescue_on_parts() const { return distributed() && comm_ranks_ > 1 && !policy_->whole_rescue; }
  // Whether the kept parts were put in space order at this cycle and have not changed since
  // (parts_from_records sorted them): a CYCLE's first sort has nothing to do.
  bool parts_in_space_order(const Model& model) const {
    return parts_live(model) && sorted_cycle_ == model.cycle && sorted_edition_ == bricks().edition();
  }

  // A CYCLE that left its last step's results to be made when read (CycleControl::defer_results):
  // the rescue copy is then of the step before, and taking that step again makes them
  // (make_results, cycle/run.hpp). What the step left is noted to check the step taken again.
  struct Deferred {
    const Model* model = nullptr;
    std::int64_t cycle = -1;
    double time = 0, friction_work = 0, damping_work = 0, boundary_work = 0, kinetic = 0;
    // The settings the step was taken with, which it is taken again with (a setting changed since,
    // DAMP say, need not make the results first: Session::settings).
    Settings settings;
    static Deferred of(const Model& m) {
      return {&m, m.cycle, m.time, m.energy.friction_work, m.energy.damping_work, m.energy.boundary_work,
              m.energy_at_step.kinetic_translation + m.energy_at_step.kinetic_rotation, m.settings};
    }
    // Bit for bit (a NaN compares unequal, so the test is on the bits); not the settings.
    bool same(const Deferred& o) const;
    // Whether the model's settings are those the step was taken with, bit for bit.
    bool same_settings(const Settings& s) const;
  };
  void defer_results(const Model& model) { deferred_ = Deferred::of(model); }
  // Whether the model's results wait for the step before to be taken again, from the rescue copy.
  bool results_deferred(const Model& model) const {
    return deferred_.model == &model && deferred_.cycle == model.cycle && rescue_.cycle + 1 == model.cycle;
  }
  const Deferred& deferred() const { return deferred_; }
  void clear_deferred() { deferred_ = {}; }
  // make_results took a CYCLE's last step again (PRINT info counts them).
  void count_results_made() { ++results_made_; }

 private:
  // What the pipeline holds between calls: two enums and two bools, each of which the others do not
  // determine.
  //
  // The pair list against the balls' positions (list_):
  //   Unchecked      the balls may have moved since the list was tested (the skin rule, prepare)
  //   Measured       so they may, and the step that moved them measured how far (step_.moved2()),
  //                  so that the test costs no pass over the balls
  //   Current        tested at the current positions, and searched again where it was stale
  //   PartsToSearch  tested at the current positions and found stale; the search is left to the
  //                  parts at their split (a distributed run's: no rank but 0 then holds the whole
  //                  model's list), or to rebuild where a whole step comes first
  //
  //   invalidate, rewind_step                        any -> Unchecked
  //   prepare (the test; rebuild where stale)        any -> Current, or PartsToSearch where the
  //                                                  ranks' parts may search and the next step is
  //                                                  not on the whole model
  //   whole_step (prepare first unless Current or    -> Measured where the backend keeps a list,
  //     PartsToSearch; rebuild from PartsToSearch)      else Unchecked
  //   split_parts (critical_timestep, brick_step)    PartsToSearch -> Current (rebuild_parts)
  //   brick_step (through prepare and split_parts    -> Unchecked (the parts measure their own
  //     where its parts cannot go on)                   displacements)
  // list_from_parts_: the model's list was last written by the parts (sync, sync_all, end_cycle),
  // not searched through the whole model (rebuild) nor put back (restore_rescue, invalidate): it
  // is current though its index is older, so that prepare's test in a distributed run does not
  // take the index's misfit for a change made outside. Not a value of list_: the parts write the
  // list in any of its states (Unchecked while they step, PartsToSearch where prepare synced them
  // and found the list stale, Current where it did not).
  //
  // How the steps are shared (mode_):
  //   Numbers    the whole model, its balls shared among the pool's threads by their numbers (a
  //              pool of one: serially)
  //   OneThread  the whole model on this thread alone: the split in space's timed verdict (the
  //              pool's other threads would wake at every step and spin beside another program)
  //   Space      the threads share in space, a part of the decomposition each
  //   Ranks      BACKEND mpi on several ranks: every step by the decomposition, a part per rank
  //
  //   constructor                                    -> Ranks (a distributed backend on several
  //                                                     ranks), else Numbers
  //   step on a pool of several threads              -> Space or OneThread where the parts are live
  //                                                     or the list is better shared in space
  //                                                     (timed_choice.hpp between the two), else
  //                                                     Numbers; brick_step -> Numbers where the
  //                                                     list it searched is better shared by numbers
  //   step with whole_next_                          OneThread -> Numbers (the whole pool takes
  //                                                  it); the others stay
  // whole_next_: the next step on the whole model (rewind_step sets it; step and invalidate clear
  // it). A bool beside the mode, not a mode: it overrides any of them for one step and the mode
  // goes on after it (a distributed CYCLE whose servo read the contact table first steps by the
  // ranks after that step; PRINT info and counters report how the CYCLE's steps were shared, not
  // how its last step was taken again to make the results read). Ranks is never Space or OneThread
  // (a distributed pipeline holds one part), and a pool of one is always Numbers.
  enum class ListState : std::uint8_t { Unchecked, Measured, Current, PartsToSearch };
  enum class StepMode : std::uint8_t { Numbers, OneThread, Space, Ranks };

  void rebuild(Model& model);
  bool needs_rebuild(const Model& model);
  bool any_outside(const Model& model);
  // A step by the spatial decomposition (a distributed run's, or the threads' where it applies).
  void brick_step(Model& model, const StepKernels& kernels, StepSums& sums);
  // A step on the whole model, its contacts and motion shared among the threads by ball numbers.
  // (On this thread alone in StepMode::OneThread: the split in space's timed fallback.)
  void whole_step(Model& model, const StepKernels& kernels, StepSums& sums);
  // A rank other than 0 of a distributed run, its part live: frees the whole model's arrays but the
  // balls' ids and radii (BrickStep::share and restore_rescue hand them over again).
  void hollow(Model& model);
  // Rank 0's whole model let go where the ranks' parts are live (BrickStep::hollow_whole), and with
  // it the pipeline's index of its arrays and the list's reference positions.
  void hollow_whole(Model& model);
  // The parts made from the whole model (split), and where prepare() left the list stale, searched
  // on them (rebuild_local), the ranks other than 0 hollow first.
  void split_parts(Model& model);
  // The skin of a new pair list for the model now (the periodic cell checked first); a list made
  // by every part (BrickStep::rebuild_local) with it: whether they could (the same on every member;
  // where not, nothing changed).
  double list_skin(const Model& model) const;
  // How far the pair search reaches: the skin, and beyond it the farthest gap a capillary bridge
  // holds at (physics/bridge.hpp), so that the list holds every pair a bridge may pull before the
  // next rebuild; the rebuild rule stays the skin's (a ball moved half the skin).
  double list_reach(const Model& model, double skin) const;
  bool rebuild_parts(const Model& model, double skin);
  // The lists of parts just made searched on them, or where they cannot be, through the whole
  // model, gathered from them, and the parts made afresh (split_parts, parts_from_records).
  void search_new_parts(Model& model, double skin);
  void hand_over_to_hollow(Model& model);
  std::size_t held_whole_ = 0, held_part_ = 0;   // bytes of arrays in the last distributed step (PRINT info)
  std::vector<double> cycle_peaks_;              // per rank: peak MiB by the end of the last distributed CYCLE

  // Whether the threads of this process share the step in space (the decomposition, one part per
  // thread) rather than by ball numbers: decided for each pair list (StepPolicy::split_rule, kSpaceBalls).
  bool threads_in_space(const Model& model);
  // f(part, member) on every part of the decomposition: this rank's alone, or each thread's on its thread.
  template <class F> void each_part(F&& f);
  // The threads of the search and the step's tests: one where the split in space's trial found one
  // thread faster (the pool's others would wake at every step and spin beside another program).
  ThreadPool& pool_now() { return mode_ == StepMode::OneThread ? *solo_pools_[0] : pool_; }
  // Whether prepare() has brought the list up to date for the model's current positions.
  bool prepared_for(const Model& model) const {
    return model_ == &model && (list_ == ListState::Current || list_ == ListState::PartsToSearch);
  }
  BrickStep& bricks() { return *bricks_[0]; }
  const BrickStep& bricks() const { return *bricks_[0]; }
  // The walls' motion over a step, and how far any wall's surface may have gone since the search.
  void move_walls(Model& model, double dt);

  std::unique_ptr<StepPolicy> own_policy_;   // where no owner gave one
  StepPolicy* policy_;
  std::unique_ptr<Backend> backend_;
  ThreadPool pool_;
  StepScratch scratch_;
  ParallelStep step_;
  // The decomposition's parts held here: this rank's (one), or one per thread of the pool.
  std::vector<std::unique_ptr<BrickStep>> bricks_;
  std::unique_ptr<ThreadTeam::Shared> thread_team_;
  std::vector<std::unique_ptr<ThreadTeam>> thread_members_;
  std::vector<std::unique_ptr<ThreadPool>> solo_pools_;   // per thread: its part's pool of one
  std::vector<PhaseTimes> member_times_;                 // threads 1..: their parts' times (not reported)
  StepMode mode_ = StepMode::Numbers;
  int comm_ranks_ = 1;              // the ranks of the run (comm::size() when made)
  bool whole_stale_ = false;        // mark_whole_stale (rank 0's word counts)
  bool others_hollow_ = false;      // others_hollow
  std::int64_t hand_overs_ = 0;     // PipelineCounters::hand_overs
  std::int64_t cycle_hand_overs_ = 0;   // PipelineCounters::cycle_hand_overs
  bool whole_next_ = false;         // the next step on the whole model, on every rank (rewind_step)
  // threads_in_space's answer for one list (a memo of a function of the list, not a state).
  struct SpaceVerdict {
    const Model* model = nullptr;
    std::uint64_t list_version = 0;
    bool in_space = false;
  } space_verdict_;
  TimedChoice space_choice_;        // where the list says in space: whether in space or on one thread
  std::string shared_by_;           // how the last step was shared (PRINT info)
  VerletReference ref_;
  PairCandidates pairs_;
  PhaseTimes times_;
  std::vector<double> partial_;     // per thread: a test's partial answer
  const Model* model_ = nullptr;    // the model the list and index were made for
  ListState list_ = ListState::Unchecked;
  bool list_from_parts_ = false;
  double wall_travel_ = 0;          // how far any wall's surface may have moved since the search
  double wall_travel_at_step_ = 0;  // wall_travel_ when the last step began (rewind_step)
  // The balls were put in a new order on the parts, whose lists could not be searched afresh there
  // (sort_on_parts): the next step searches afresh (on the parts where they can, else through the
  // whole model). As serial's are after its sort (invalidate), so that the lists, and the steps at
  // which each is searched again, are serial's (a step does not depend on its list; a save holds it).
  bool search_next_step_ = false;
  // The parts were made from a save, whose wall contacts they keep as it holds them until the next
  // step finds them afresh (parts_from_file), as serial's RESTART keeps its table until its first
  // step's search: a save written between holds the file's. (Their pair list, searched at the
  // same positions, is the one serial's first step finds.)
  bool walls_next_step_ = false;
  // The light state and the parts' copies of the rescue, put back to rank 0's whole model.
  void whole_from_part_copies(Model& model);
  Snapshot rescue_;
  bool part_rescue_ = false;   // (part_rescue)
  double rescue_wall_travel_ = 0;   // wall_travel_ when the parts' copies were taken
  std::int64_t copies_on_parts_ = 0;   // (PipelineCounters::copies_on_parts)
  Deferred deferred_;
  std::int64_t results_made_ = 0;
  std::int64_t results_gathered_ = 0;
  bool serving_ = false;   // (start_requests)
  std::int64_t sorted_cycle_ = -1;      // (parts_in_space_order)
  std::int64_t parts_from_records_ = 0;   // (PipelineCounters::parts_from_records)
  std::int64_t parts_from_saves_ = 0;     // (PipelineCounters::parts_from_saves)
  std::uint64_t sorted_edition_ = 0;
};

// A pipeline with the backend of that name (BACKEND's words; throws std::invalid_argument), both
// reading `policy` where given (Pipeline's constructor).
std::unique_ptr<Pipeline> make_pipeline(std::string_view backend, int threads = 0, std::uint64_t max_memory = 0,
                                        StepPolicy* policy = nullptr);

}  // namespace trubal
