// BACKEND mpi's spatial decomposition: each rank steps only the balls it owns, with ghost copies of
// their partners, and the ranks exchange only the ghosts' new state each step (doc/distributed.md).
//
// How the answer stays the serial one, bit for bit, for any rank count:
// - The owners are a recursive bisection of the balls (any split gives the same bits; the split
//   only decides the speed), each member's share of the balls in proportion to the speed it stepped
//   its own balls at since the split before (equal shares at first). It is made again at every
//   pair-list rebuild.
// - A rank's part is a Model of its own balls and their partners in the pair list (the ghosts),
//   numbered in the order of the whole model's indices, with the whole list's pairs that touch an
//   owned ball, in list order. So every owned ball meets its partners in the serial order and sums
//   its contacts in the same additions; a pair between two ranks is computed on both, from the
//   same inputs, and both keep the same history.
// - The motion loop moves owned balls only (StepScratch::ghost); the global sums are exact sums of
//   each owned ball's part, merged over the ranks (kernels.hpp).
// - A stale pair list is rebuilt on the parts where it can be (rebuild_local: the ranks of a run
//   by the decomposition): a ball now in another rank's brick of the split's bisection moves there
//   with its pairs' and wall contacts' history, each rank keeps its other balls, receives from the others the balls in the
//   bins next to its own balls' bins, searches them with the serial search's test and carries its
//   pairs' history over; a ball leaving the periodic cell is wrapped on every part that holds it
//   (wrap); the whole model's list is made from the ranks' lists at the next sync.
// - Bonds (model/bonds.hpp) go with the balls: a part holds the intact bonds of its owned balls,
//   their other balls as ghosts however far (a bond is kept by topology, not found in the list's
//   reach). A bond between two members' balls is stepped on both, from the same inputs, as a pair
//   across them is, and both keep the same state; its owner is the owner of its ball i (the rule
//   of LAMMPS's bonds, kept by the atom whose tag comes first there): that member alone books its
//   energies and the servo's moments, and reports its state and fate to sync(). A broken bond
//   carries nothing and stays in the whole model's table. The parts' bonds are those intact at
//   the split until the next one: a ball that changes owner at a rebuild on the parts takes its
//   bonds with it (broken or not), and where some intact bond is longer than the list's reach
//   (its other ball may be outside the halo a rebuild receives) the list is rebuilt through the
//   whole model instead.
// - Anything else the step cannot do on its own part (a ball outside a START box, an edit between
//   steps, a decomposition whose balls have spread) goes
//   through the whole model: sync() gathers every rank's balls, pairs and wall contacts into rank
//   0's, share() hands that to the others, the serial rules act on it, and the parts are made
//   afresh from it. What rank 0 alone reads (the output, the rescue copy) needs only sync(); the
//   other ranks step without the whole model's arrays meanwhile (Pipeline::hollow).
#pragma once

#include <bit>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cycle/kernels.hpp"
#include "physics/bond.hpp"
#include "physics/cell.hpp"
#include "physics/measure.hpp"
#include "physics/measure_sphere.hpp"
#include "physics/membrane.hpp"
#include "support/exact_sum.hpp"
#include "cycle/parallel_step.hpp"
#include "cycle/phase_times.hpp"
#include "cycle/snapshot.hpp"
#include "cycle/step_policy.hpp"
#include "cycle/step_scratch.hpp"
#include "cycle/team.hpp"
#include "cycle/verlet.hpp"
#include "backends/backend.hpp"
#include "model/model.hpp"
#include "model/range.hpp"
#include "model/table_pieces.hpp"
#include "support/thread_pool.hpp"

namespace trubal {

// A change of the cell's velocity field on balls [begin, end), every copy changed; the kinetic
// energy the balls not marked in `skip` gain, summed exactly ball by ball.
void apply_field_change(Balls& balls, const FieldChange& change, std::size_t begin, std::size_t end,
                        const std::uint8_t* skip, ExactSum& work, ExactSum& gross);

// The bytes of a model's arrays of balls, pairs and wall contacts (their capacity).
std::size_t array_bytes(const Model& m);
// Rank 0's arrays of balls, pairs (their results where kept, and with_results) and wall contacts,
// to every rank (a collective call); the others' pair and wall lists take fresh versions. Without
// the results, the others' are dropped (ContactTable::results_kept false): rank 0 alone prints and
// writes what they feed.
void broadcast_arrays(Model& m, bool with_results = true);
// Rank 0's contact results to every rank, whose pair list is rank 0's (a collective call).
void broadcast_results(Model& m);
// Rank 0's whole model to every rank without the contact results (broadcast_arrays), and the
// positions its pair list was made at, where `ref` holds them for its balls (the same answer on
// every rank).
void broadcast_whole(Model& m, VerletReference* ref);
// Rank 0's balls' ids, types and radii to every rank, indexed by id there (what a rank that holds
// no balls keeps of them: Pipeline::hollow).
void broadcast_ball_names(Balls& b);

class BrickStep {
 public:
  // policy: the pipeline's (StepPolicy: local_rule, slow_member, the faults), outliving this.
  explicit BrickStep(StepPolicy& policy) : policy_(&policy), step_(policy) {}

  // The members sharing the step: the ranks of the MPI run (the default), or the threads of one
  // process, one BrickStep each (cycle/team.hpp).
  void set_team(Team& team) { team_ = &team; }

  // The parts hold the current state of `full` (which may be older).
  bool live_for(const Model& full) const;
  bool live() const { return live_; }
  // The whole model's settings and materials to the part (they change between CYCLEs on the kept
  // parts), and its balls' (its own and its ghosts') masses and inertias from their types, as a
  // CYCLE's start sets the whole model's (a collective call: a ball too light for a step is every
  // rank's failure).
  void take_settings(const Model& full);
  // The whole model holds the part's state again (Pipeline::apply_field_kept made the same change there).
  void mark_current() { current_ = true; }
  // The whole model no longer holds the part's state: the next sync gathers it again.
  void mark_stale() { current_ = false; }
  // Makes this member's part of `full` (current, its list installed; `ref` the list's reference
  // positions). Threads: every member computes every member's owners from the one whole model.
  // Ranks: rank 0 makes every rank's part and sends it (scatters); the others need no more of
  // `full` than its light state and the balls' count.
  void split(const Model& full, const VerletReference& ref);
  // The ranks' split made from balls each rank keeps apart from `full` (a batch deck's held BALL
  // lines: Session::place_held_as_parts). `full` holds, on rank 0, the balls' ids, types, radii,
  // fixities and centres in the whole model's order and no pair, wall contact or bond; `records`,
  // this rank's balls, 7 numbers each (the whole model's index, the id's bits, type, x, y, z,
  // radius), go to their owners, each of which makes its part of its own: no ghost, as no pair is
  // found yet. A collective call; `records` is let go once sent.
  void split_from_records(const Model& full, std::vector<double>& records);
  static constexpr std::size_t kRecord = 7;
  // The ranks' split made from a save a distributed RESTART reads (cycle/brick_from_file.cpp):
  // `full` holds, on rank 0, the balls' ids, types, fixities, radii and centres in the whole
  // model's order and no pair, wall contact or bond (the others, the ids, types and radii); rank 0
  // decomposes it and reads each array of the save's balls, pairs and wall contacts a piece at a
  // time from `file` (rank 0's; null on the others), sending each rank its own: its balls, the
  // pairs of which it owns a ball, its balls' wall contacts. The pairs and wall contacts wait,
  // in the whole model's numbers, for the part's first list (rebuild_local carries their history
  // and results into it). A collective call; `results`: the save's contact results are the
  // model's (the parts hold them after their first list: results_left).
  void split_from_file(const Model& full, TablePieces* file, bool results);
  // The part's list reference positions its balls' own where it holds none (a part made by
  // split_from_records, whose search goes through the whole model: a sync gathers them).
  void reference_at_balls() {
    if (ref_.x.size() == part_.balls.size()) return;
    ref_.x = part_.balls.x;
    ref_.y = part_.balls.y;
    ref_.z = part_.balls.z;
  }
  // Counts the splits, rebuilds, tilt reductions and drops (a part changed other than by steps).
  std::uint64_t edition() const { return edition_; }
  // One step on this rank's part: forces, motion of the owned balls, the ghosts' new state from
  // their owners, the global sums (merged over the ranks into `sums`) and the walls' loads (into
  // full.walls). The space and walls are read from `full`.
  void step(ThreadPool& pool, Model& full, const StepKernels& kernels, StepSums& sums, PhaseTimes& times);
  // Whether some ball is outside the periodic cell as it is now, on any rank (a collective call:
  // the cell changes after each step, so this is asked before the next).
  bool outside_cell(const Model& full);
  // What the last step found, over every rank: the largest squared displacement since the list was
  // made, some ball outside a bounded axis of the box.
  double moved2() const { return moved2_; }
  bool outside_box() const { return outside_box_; }
  // A change of the cell's velocity field (a servo's or STRAIN's new rates) on every copy of the
  // part's balls; the work it does, summed over the owned balls and the ranks (a collective call),
  // goes to full's energy.
  void apply_field(Model& full, const FieldChange& change);
  // The tilts of the cell were reduced (reduce_cell_tilt) from `before`: the part's pair images
  // are renumbered alike.
  void reduce_tilt(const Space& before);
  // A new pair list on the parts alone, for the positions now (a collective call, on every rank):
  // a ball in another rank's brick of the split now (owner_at) moves to that rank with the history of
  // its pairs and wall contacts and with its bonds (unless a rank's count would then be a tenth off
  // its share: false);
  // each rank keeps its other balls, receives the others' balls that may be within reach of them
  // (those in the bins around its balls' bins, the bins as wide as the largest reach with `skin`,
  // through the periodic faces too; each rank marks the bins of its balls), searches its pairs as the serial search
  // does and carries their history over. Returns false, changing nothing, where the parts are to be
  // made afresh from the whole model instead (the same answer on every member): a decomposition
  // whose balls have spread (the shell of balls received grew past twice its size at the first
  // such rebuild), members whose speeds would move their shares by a tenth, results not yet
  // gathered, an intact bond longer than the reach (its other ball may lie beyond the bins
  // around), TRUBAL_REBUILD_WHOLE (StepPolicy::local_rule). The walls' contacts of the member's own balls are
  // found afresh too (`search`: the backend whose find_part_pairs searches the part; `pool`: the
  // threads of the walls' search).
  bool rebuild_local(const Model& full, double skin, Backend& search, ThreadPool& pool);
  // The wall contacts of the part's balls found afresh within `reach` of the walls, their history
  // and results carried, the pair list kept (Pipeline::parts_go_on, after parts made from a save).
  void find_walls_again(const Model& full, double reach, ThreadPool& pool);
  // The balls put in space order on the parts (a collective call of the ranks, their parts live),
  // as sort_in_space (model/edit.hpp) puts the whole model's: each rank's keys of its own balls
  // go to every rank, which orders them (by key, then id: about 20 bytes a ball for the moment);
  // the whole model's light arrays (rank 0's hollow model: hollow_whole first), each ball's owner,
  // the split's cuts and bonds follow the new order, and each part is renumbered and put in it,
  // its pairs and wall contacts with it (reorder_balls), its list kept. Returns the order (new
  // index k holds old index order[k]), or nothing where no ball moves (the same on every rank).
  // The rescue copy stays of the order it was taken in (whole_from_copy puts every ball array back).
  std::vector<std::uint32_t> sort_in_space(Model& full);
  // Wraps the parts' balls into the periodic cell as the whole model's wrap would (a collective
  // call, where outside_cell said some ball is out): every copy of a ball moves alike, so each part
  // renumbers its pairs' images as the whole list would be; the energy the wrap adds (a straining
  // cell's velocity change) goes to full's, summed in the whole model's order. The whole model's
  // list is then made from the parts' at the next sync. Returns false, changing nothing, where the
  // ranks are to step through the whole model instead (as rebuild_local).
  bool wrap(Model& full);
  // Brings `full` up to date with every rank's part (a collective call; the parts stay live): rank
  // 0's `full` for the ranks of a run (share() then the others'), the one whole model for threads. Where
  // the parts rebuilt their list, full's list is made from theirs, and the positions it was built
  // at go into `whole_ref` (the pipeline's reference for the whole model).
  // leave_results (a CYCLE's end on kept parts): the contact results the parts' last step wrote
  // (a step taken again there, results_onto_parts) stay on the parts (results_left), gathered only
  // where a command reads them (gather_results, gather_result_array).
  void sync(Model& full, VerletReference* whole_ref = nullptr, bool leave_results = false);
  // The parts hold the contact results of the state `full` holds, which full's table lacks (the
  // same answer on every member): a sync left them, and no step, list nor split changed the parts
  // since.
  bool results_left() const { return live_ && results_left_; }
  // The results the parts' last step wrote were read on the parts and are not wanted in the whole
  // model (an output step's sums, CycleRun::observe): the parts go on as after a lean step.
  void forget_step_results() { results_written_ = false; }
  // Those results into full's table (rank 0's for the ranks; a collective call where
  // results_left), of full's cycle; the parts' arrays of them are freed.
  void gather_results(Model& full);
  // Array k of those results (ContactTable::for_each_result_array's order: `state` bytes, the
  // others reals) into *bytes or *reals on rank 0, of full's table's length; the parts keep theirs
  // (a collective call of the ranks, where results_left).
  void gather_result_array(const Model& full, std::size_t k, std::vector<double>* reals,
                           std::vector<std::uint8_t>* bytes);
  // Brings `full` up to date on every rank (a collective call): sync() makes rank 0's whole model
  // current (the ranks' syncs gather to rank 0 alone: the rescue copies and the output read it
  // there), and this hands it to the others, for what every rank does on the whole model (a
  // wrap or a rebuild through it, START's escapes, a membrane's forces, the CYCLE's end). Threads
  // share one whole model: sync() is all they need. release_parts: the parts are released first
  // (the CYCLE's end: the next CYCLE makes them afresh), so that no rank holds a part and the whole
  // model at once.
  void share(Model& full, VerletReference* whole_ref = nullptr, bool release_parts = false);
  // The whole model's critical step, without the Hertz cap (physics/timestep.hpp), from each rank's
  // own balls on its part: the smallest over the ranks (a collective call).
  double critical_step(const Features& features);
  // And its contact-free step (physics/timestep.hpp contact_free_step), so.
  double free_step(const Features& features, double cap);
  // The applied loads of `full`'s balls changed (a following membrane's, between steps, on every
  // rank alike): the part's copies take them.
  void loads_changed(const Model& full);
  // INIT, APPLY, FIX and FREE where the ranks keep their parts (a collective call): change(balls, k)
  // on each of the part's balls, its own and its ghosts, where `range` holds (read with full's
  // groups); the count of every member's own balls changed. GROUP's: the ids of every member's own
  // balls where it holds, ascending, on every member.
  std::size_t change_balls(const Model& full, const Range& range, const std::function<void(Balls&, std::size_t)>& change);
  std::vector<std::int64_t> ids_where(const Model& full, const Range& range);
  // A ball's history item where the parts are live (a collective call): read(balls, k) on the
  // member that owns the ball of that id, its `count` values to every member (NaN where none does).
  std::vector<double> own_ball_values(std::int64_t id, std::size_t count,
                                      const std::function<std::vector<double>(const Balls&, std::size_t)>& read);
  // The balls of these ids where the parts are live (a collective call): every member's own, their
  // heights and unbalanced forces to every member in the whole model's order (HIST's platens).
  PlatenBalls own_platen_balls(const std::vector<std::int64_t>& ids);
  // MEMBRANE follow on the live parts (a collective call): the loaded balls' centres by their place
  // in the membrane's ids, every member's own to every member, the loads made from them as serial
  // makes them (physics/membrane.hpp follow_loads) and set on the part's balls (its own and its
  // copies); returned for the whole model's arrays.
  MembraneFollow follow_membrane(const Membrane& m);
  // The bonds' counts where the parts are live (a collective call): every member's own bonds (its
  // ball i's) by their fates now, summed over the members, with the bonds no part holds (HIST bonds).
  BondCounts own_bond_counts();
  // The state and fates of the bonds the parts hold into full's table on rank 0 (a collective call
  // of the ranks, as sync() gathers them), nothing else of the model.
  void bonds_to_root(Model& full);
  // The balls' centres the parts hold into full's x, y and z on rank 0, made whole-sized there (a
  // collective call of the ranks; a bonded model's dump draws its bonds from them).
  void centres_to_root(Model& full);
  // DELETE where the parts are live and hold no bond (a collective call): the balls where `range`
  // holds (read by their owners) taken out of every member's part and of the whole model's arrays
  // every rank holds, the rest numbered again in their order (cycle/brick_delete.cpp). Returns how
  // many, every member's.
  std::size_t delete_balls(Model& full, const Range& range);
  // Rank 0's whole model lets go of the state the parts step (hollow_whole: the balls' motion and
  // unbalanced forces, the pair list with its history and results, the wall contacts), keeping what
  // a CYCLE and the light commands read there (the balls' ids, types, fixities, radii, masses and
  // applied loads, the bonds, the walls); the parts alone hold the model's state, until a sync
  // gathers it whole again (every array of it, the lists made afresh from the parts'). Ranks of a
  // run only, where the parts are live; a collective call. The same answer on every rank.
  void hollow_whole(Model& full);
  bool whole_hollow() const { return live_ && whole_hollow_; }
  // A CYCLE's end on kept parts (a collective call): the contact results the parts' last step wrote
  // (a step taken again there, results_onto_parts) stay there (results_left), and rank 0's whole
  // model goes hollow (hollow_whole), nothing gathered.
  void end_on_parts(Model& full);
  // This member's counts over its own pairs, wall contacts and balls, which the caller sums over the
  // members: the pairs and the wall contacts touching in the results the part holds (none where it
  // holds none), the capillary bridges between balls and to walls, the balls that spin, that carry
  // an applied force, that carry an applied moment.
  std::vector<double> own_counts() const;
  // The largest overlap over the pairs and wall contacts this member owns (physics/overlap.hpp), at
  // the part's positions now with full's space and walls: its ratio, ball, other, wall (0 or 1) and
  // count beyond `threshold`, then its place in the whole model's tables' order (wall, the whole
  // model's ball i or ball, ball j or wall, the image) for the caller's choice among the members.
  std::vector<double> own_largest_overlap(const Model& full, double threshold);
  // Love's formula's sums (physics/measure.hpp stress_sums) over the pairs and wall contacts this
  // member owns, from the results the part holds, with full's space and walls: exact, so that
  // their total over the members is the whole model's.
  StressSums own_stress(const Model& full);
  // The contact measures' sums (physics/measure.hpp contact_sums) over the pairs, wall contacts
  // and balls this member owns, from the results the part holds.
  ContactSums own_contact_sums() const { return contact_sums(part_, &owned_pairs_, &owned_walls_, &owned_); }
  // A measurement sphere's sums (physics/measure_sphere.hpp sphere_sums) over the balls, pairs and
  // wall contacts this member owns, its pairs' other balls read where the part holds them, with
  // full's space.
  SphereSums own_sphere_sums(const Model& full, const MeasureSphere& sphere);
  // A periodic servo's stiffness sums (physics/cell.hpp servo_stiffness_sums) over the pairs this
  // member owns, from the results the part holds.
  std::array<ExactSum, 3> own_servo_stiffness() const;
  // Whether nothing in the part's tables touches and no bridge holds (physics/cell.hpp).
  bool part_touches_nothing() const { return touches_nothing(part_); }
  // The part's state streamed to rank 0 in the whole model's order (SAVE where rank 0's whole
  // model is hollow; cycle/brick_stream.cpp), each a collective call of the ranks. place_saved_pairs:
  // the pairs this member owns that SAVE keeps (touching in the results the part holds, where
  // `results`, or with history) placed in the whole order; place_saved_walls: its wall contacts;
  // each returns the count over every member. stream_table: array k of the balls (table 0, in
  // Balls::for_each_array's order), of the placed pairs (1) or wall contacts (2) in
  // io/save.cpp's order (the list's, every declared history part's, the results'), `write(chunk)`
  // on rank 0 for each chunk in turn (a failure there is rank 0's, thrown once the stream ends).
  // free_saved: the places let go.
  std::uint64_t place_saved_pairs(bool results);
  std::uint64_t place_saved_walls();
  void stream_table(int table, std::size_t k, const std::function<void(const std::vector<double>&)>& write);
  void free_saved();
  // PRINT balls and contacts where rank 0's whole model is hollow (a collective call of the ranks):
  // the rows of this member's own balls by id, of its own pairs that touch in the results the part
  // holds (or hold a capillary bridge, where `bridges`) by their balls' ids, merged in that order to
  // rank 0, a batch at a time, where `take(row)` reads each in turn (on rank 0 alone; a failure there is
  // thrown once every row came). A ball's row: id (its bits), type, x y z, rad, vx vy vz, wx wy wz,
  // fx fy fz; a contact's: the smaller id, the larger (their bits), nx ny nz from the smaller's ball
  // to the larger's, overlap, fn, fsx fsy fsz and mrx mry mrz on the larger's, the state, the bridge.
  static constexpr std::size_t kBallRow = 15, kContactRow = 15;
  // An id as a row holds it (its bits).
  static std::int64_t row_id(double v) { return std::bit_cast<std::int64_t>(v); }
  // With `range` (read with full's groups), the balls where it holds, and the pairs with a ball
  // where it holds (its copy read where another member owns it).
  void stream_ball_rows(const std::function<void(const double*)>& take, const Model* full = nullptr,
                        const Range* range = nullptr);
  void stream_contact_rows(bool bridges, const std::function<void(const double*)>& take, const Model* full = nullptr,
                           const Range* range = nullptr);
  // DUMP's rows (io/vtk.hpp) where the parts are live (a collective call of the ranks), merged to
  // rank 0 in the whole model's order as above: every member's own balls' (vtk_ball_rows), its own
  // pairs' that touch in the results the part holds (vtk_line_rows: as many as own_counts' touching).
  // `full`: the cell as it is now.
  void vtk_ball_rows(const std::function<void(const double*)>& take);
  void vtk_line_rows(const Model& full, const std::function<void(const double*)>& take);
  // The parts are dropped (the whole model was changed, or is to be stepped another way). Not
  // where they alone hold the model (whole_hollow: an internal error; sync first).
  void drop() {
    if (live_ && whole_hollow_) throw std::logic_error("internal error: the ranks' parts dropped where they alone hold the model");
    ++edition_;
    live_ = false;
    results_left_ = false;
  }
  // The parts dropped where they alone hold the model, which is then lost on every rank (a step
  // taken again on them failed part way: Pipeline::drop_parts_unsynced).
  void drop_hollow() {
    whole_hollow_ = false;
    drop();
  }
  // The ranks other than 0 freed their whole model's arrays (Pipeline::hollow; said on every rank
  // alike): the next share() hands rank 0's over again, whether or not a step has followed.
  void whole_freed() { shared_ = false; }
  // Dropped, and their memory given back (the next split makes them afresh). The rescue copy stays.
  void release();

  // The rescue copy of this rank's part (Pipeline::take_rescue, where the ranks' parts are live):
  // its balls, pairs, wall contacts and bonds as cycle/snapshot.hpp copies a model, and what a sync
  // needs to gather them (each ball's and pair's place in the whole model). Ranks only.
  void keep_copy();
  bool copy_held() const { return copy_.held; }
  // The bytes of the copy's arrays (0 where none is held).
  std::size_t copy_bytes() const;
  void free_copy();
  // Rank 0's whole model made the state the copies hold (a collective call, every rank holding its
  // copy): every array of the balls, resized to the copy's count, the pair list and its history,
  // the wall contacts and the bonds' state; the contact results dropped and the unbalanced forces
  // zero (Snapshot::restore's answer where a step since wrote them). The other ranks' models are
  // left as they are. The parts are released after (they held the copy's state for the gathers).
  void whole_from_copy(Model& full);
  // The live parts put back to their copies in place, where nothing but steps and wraps changed
  // them since (no split, rebuild or tilt reduction: the same balls, lists and ghosts),
  // so that a step taken again from there needs no split from rank 0 (results_onto_parts).
  // Returns false, changing nothing, where they cannot be (the same answer on every rank: a
  // collective call). The whole model then no longer holds the parts' state (the next sync
  // gathers it).
  bool restore_copy_in_place(const Model& full);

  // A node of the split's recursive bisection: the balls before (coordinate, whole-model index)
  // (at, at_ball) along `axis` go to `left`, the others to `right`; a leaf (left < 0) is rank `owner`'s
  // brick. A ball that has moved belongs to the brick that holds it now (owner_at).
  struct Cut {
    int axis = 0;
    double at = 0;
    std::uint32_t at_ball = 0;
    std::int32_t left = -1, right = -1;
    int owner = 0;
  };
  // The rank whose brick of the last split holds a ball at (x, y, z) with whole-model index k.
  int owner_at(double x, double y, double z, std::uint32_t k) const;

  std::vector<std::pair<std::string, std::string>> info() const;
  std::size_t local_rebuilds() const { return local_rebuilds_; }
  // The decomposition's counts (PRINT counters): the same on every member, but the balls and
  // ghosts, which are this member's, and least/most_balls over the members at the last split.
  struct Counts {
    std::size_t decompositions = 0, list_rebuilds = 0, wraps = 0, migrations = 0;
    std::size_t ghosts = 0, least_balls = 0, most_balls = 0;
    std::size_t bonds_across = 0;   // intact bonds whose balls two members owned at the last split
    std::size_t sorts = 0;          // the sorts into space order on the parts (sort_in_space), moving balls or not
    std::size_t gathers = 0;        // the whole model made current from the parts (sync)
  };
  // The counts as they were (a step taken again on the parts is no decomposition of the run's:
  // results_onto_parts keeps the CYCLE's).
  void set_counts(const Counts& c) {
    splits_ = c.decompositions; local_rebuilds_ = c.list_rebuilds; local_wraps_ = c.wraps; migrations_ = c.migrations;
    ghosts_ = c.ghosts; least_balls_ = c.least_balls; most_balls_ = c.most_balls; bonds_across_ = c.bonds_across;
    sorts_ = c.sorts;
    gathers_ = c.gathers;
  }
  Counts counts() const {
    return {splits_, local_rebuilds_, local_wraps_, migrations_, ghosts_, least_balls_, most_balls_, bonds_across_, sorts_,
            gathers_};
  }
  // The bytes of the part's arrays of balls, pairs and wall contacts.
  std::size_t part_bytes() const;
  // The bytes of the part's contact results (ContactTable::result_bytes).
  std::size_t part_result_bytes() const { return part_.contacts.result_bytes(); }

 private:
  // split()'s work. decompose: the owners and every member's lists (rank_balls_ and the like), from
  // the whole model; cut_part: member `me`'s part and its lists (owned_, send_ and the like), into
  // this one's; finish_part: what every member then sets alike.
  void decompose(const Model& full);
  // A rank of a run other than 0, its part made: each ball's owner and the other ranks' rows of
  // rank_balls_ let go; its own rows (its balls, its bonds) made again from its part after a
  // rebuild or a sort on the parts (own_rows_from_part).
  void let_go_of_others_lists();
  void own_rows_from_part();
  // The rows of rank_balls_ and rank_bonds_ after a rebuild or a sort on the parts: every rank's
  // from owner_ where this member keeps it, else its own from its part.
  void remake_rows();
  void cut_part(const Model& full, const VerletReference& ref, int me);
  void finish_part(const Model& full);
  // The ranks of a run scatter (cycle/brick_scatter.cpp): rank 0 alone reads the whole model,
  // decomposes it and hands the others the lists every member keeps, then cuts each rank's part and
  // sends it; the others have freed their whole model's arrays before (Pipeline::split_parts), so
  // that no rank but 0 ever holds the whole model and a part at once. `fault`: a test's fault, run
  // where split() agrees on failures.
  bool scatters() const { return !team_->shares_whole() && team_->size() > 1; }
  void scatter_parts(const Model& full, const VerletReference& ref, const std::function<void()>& fault,
                     const std::string& doing);
  void share_decomposition();
  // f(vector&) on each array of the part and its lists that cut_part makes, in the order rank 0
  // sends them and a rank receives them.
  template <class F> void each_sent_array(F&& f);
  // (cycle/brick_stream.cpp) Each member's values (value(q) for its q-th entry, at its place at[q]
  // in the whole order of `total` entries, ascending) to rank 0 in the whole order, a chunk at a
  // time; and the places of entries by their balls (the whole model's, ascending), every ball's
  // entries on its owner, in the whole order (by ball, then as each member lists them): the count.
  template <class Value>
  void stream_in_order(const std::vector<std::uint64_t>& at, std::uint64_t total, Value&& value,
                       const std::function<void(const std::vector<double>&)>& write);
  std::uint64_t place_by_ball(const std::vector<std::uint32_t>& ball, std::vector<std::uint64_t>& at);
  // Rows of `width` values, `count` on each member (row(q, out) writes its q-th into out, in its
  // order of `before`), merged to rank 0 in that order, take(row) there on each.
  void merge_rows_to_root(std::size_t count, std::size_t width, const std::function<void(std::size_t, double*)>& row,
                          const std::function<bool(const double*, const double*)>& before,
                          const std::function<void(const double*)>& take);
  std::vector<std::uint32_t> saved_pairs_;          // (place_saved_pairs) the part's pairs SAVE keeps
  std::vector<std::uint64_t> saved_pair_at_, saved_wall_at_;   // their places, and the wall contacts'
  std::uint64_t saved_pairs_total_ = 0, saved_walls_total_ = 0;
  // sync()'s first work after rebuild_local: full's list from every rank's (a collective call).
  void install_local_list(Model& full, VerletReference* whole_ref);
  // Its part for the walls' contacts.
  void install_local_walls(Model& full);
  // Rank 0's part of it, of the ranks: every rank's records (`all`, `counts` each rank's count),
  // each rank's in the list's order, merged into full's table and each rank's places in it
  // (rank_pairs_); false, changing nothing, where some rank's are not in order.
  bool merge_pair_runs(Model& full, std::vector<std::uint8_t>& all, const std::vector<double>& counts);
  // sync()'s part for a bonded scene: the state and fate of every member's bonds into full's.
  void gather_bonds(Model& full, std::vector<double>& out, std::vector<double>& in);
  // The parts' contact results into full's table (sync, gather_results). free_each: each part's
  // array freed as it is gathered; else all once every one is.
  void gather_result_arrays(Model& full, std::vector<double>& out, std::vector<double>& in, bool free_each = true);
  // A test's fault in gather_results, gather_result_array, place_saved_pairs and
  // stream_contact_rows (StepPolicy::fail_results).
  void results_fault();
  // Every member's `mine` concatenated into `all`: on every thread; on rank 0 alone of the ranks.
  template <class T> void gather_whole(const std::vector<T>& mine, std::vector<T>& all);
  // Runs `work` so that a member's failure is every member's (ranks: comm::together; threads: the
  // team's abort, through Pipeline::each_part).
  void together(const std::function<void()>& work, const std::string& doing);
  // The shares every member's speed since the last split gives (a collective call; the same on
  // every member; empty where too little was measured), and those of the next split, made from them.
  std::vector<double> proposed_shares();
  void update_shares();

  // rebuild_local's stages, in the order it runs them; what each leaves for the next is in the
  // Rebuild it is handed (the comments at their definitions say which).
  struct Rebuild;
  bool may_rebuild_local(const Model& full);
  bool bonds_within(const Space& space, double reach);
  void fit_shell_bins(Rebuild& r, const Space& space) const;
  void find_moves(Rebuild& r) const;
  bool balanced_after_moves(Rebuild& r) const;
  void mark_bins(Rebuild& r) const;
  void find_shells(Rebuild& r) const;
  void find_leaving(Rebuild& r) const;
  void announce_counts(Rebuild& r) const;
  bool shells_within_bounds(Rebuild& r);
  void pack_messages(Rebuild& r) const;
  void list_entries(Rebuild& r) const;
  void unpack_arrivals(Rebuild& r) const;
  void search_part(Rebuild& r, const Space& space, Backend& search) const;
  void carry_history(Rebuild& r) const;
  void make_next_balls(Rebuild& r) const;
  void commit_rebuild(Rebuild& r);
  void index_part();
  void find_part_walls(Rebuild& r, const Model& full, ThreadPool& pool);
  void install_file_walls(WallContacts& walls);
  // A test's fault: this rank's next split fails as out of memory (StepPolicy::fail_split).
  void split_fault();
  // The part's balls made already (`mine`, their places in the whole model, ascending): the part
  // holds them alone, no pair, bond, wall contact or ghost, its lists to be searched
  // (split_from_records, split_from_file).
  void own_balls_alone(const std::vector<std::uint32_t>& mine);


  // (keep_copy)
  struct PartCopy {
    Snapshot part;
    std::vector<std::uint32_t> global_ball, owned, owned_pairs, owned_walls;
    std::vector<std::vector<std::uint32_t>> rank_balls, rank_bonds;   // (rank 0's; the others' own row)
    std::vector<std::uint8_t> ghost;
    VerletReference ref;         // (a wrap since moved the balls' reference positions with them)
    std::size_t full_balls = 0;
    bool bonded = false, walls_any = false, held = false;
    std::uint64_t edition = 0;   // the part's edition_ when taken
    double moved2 = 0;           // the last step's findings then
    bool outside_box = false;
  };

  StepPolicy* policy_;
  Team* team_ = &rank_team();
  PartCopy copy_;
  Model part_;
  StepScratch scratch_;
  ParallelStep step_;
  VerletReference ref_;                     // the reference positions of the part's balls
  StepKernels kernels_;                     // the cycle's, with the part's pair laws
  bool live_ = false;
  bool current_ = true;                     // `full` holds the parts' state (ranks: rank 0's)
  bool whole_hollow_ = false;               // (whole_hollow)
  bool shared_ = true;                      // and every rank's `full` does (share)
  bool walls_any_ = false;                  // the whole model had walls or wall contacts at the split
  // The parts' last step wrote the pairs' results, not yet gathered (the same on every rank, which
  // a part's own results_kept() is not: an empty part's table counts as kept).
  bool results_written_ = false;
  bool results_left_ = false;               // (results_left)
  const Model* model_ = nullptr;
  std::uint64_t list_version_ = 0, wall_version_ = 0;
  std::size_t full_balls_ = 0;
  std::vector<int> owner_;                  // per ball of the whole model (rank 0's alone of a run: let_go_of_others_lists)
  std::vector<std::size_t> rank_counts_;    // per member: the balls it owns (every member's)
  std::vector<Cut> cuts_;                   // the last split's bisection (node 0 the root)
  std::vector<std::uint32_t> global_ball_;  // part ball -> whole model's ball
  std::vector<std::uint32_t> owned_, owned_pairs_, owned_walls_;   // part indices this rank reports
  // Per rank: the whole model's balls it owns, pairs whose ball i it owns, its balls' wall contacts
  // (of the ranks of a run, the pairs and wall contacts on rank 0 alone, which places what sync gathers).
  std::vector<std::vector<std::uint32_t>> rank_balls_, rank_pairs_, rank_walls_;
  // Per rank: the whole model's rows of the intact bonds (at the split) whose ball i it owns, by
  // (id_i, id_j); whether there were any (the same on every member).
  std::vector<std::vector<std::uint32_t>> rank_bonds_;
  // The split's intact bonds by (id_i, id_j): their rows in the whole model, their balls i there.
  std::vector<std::uint32_t> split_bond_rows_, split_bond_ball_i_;
  bool bonded_ = false;
  std::size_t bonds_across_ = 0;
  BondCounts split_off_;   // the whole table's bonds no part holds at the split (broken, or a ball gone)
  HistoryLaws split_laws_;                  // the whole model's pairs' history parts at the split
  // Per rank: the part's balls sent to it each step (its ghosts), and the ghosts it sends.
  std::vector<std::vector<std::uint32_t>> send_, recv_;
  std::vector<std::vector<double>> send_buf_, recv_buf_;
  std::vector<double> sums_out_, sums_in_;
  double moved2_ = 0;                       // over every rank, after the last step
  bool outside_box_ = false;
  std::size_t ghosts_ = 0, most_balls_ = 0, least_balls_ = 0, most_ghosts_ = 0;
  std::size_t splits_ = 0;
  std::size_t local_rebuilds_ = 0;           // lists rebuilt on the parts (rebuild_local)
  std::size_t local_wraps_ = 0;              // wraps on the parts (wrap)
  std::size_t migrations_ = 0;               // balls that changed owner at a rebuild on the parts
  std::size_t sorts_ = 0;                    // (Counts::sorts)
  std::size_t gathers_ = 0;                  // (Counts::gathers)
  bool list_local_ = false;                  // the parts' list is newer than full's
  // Counts every change of the part's balls and lists but a step's or a wrap's (a split, a
  // rebuild on the parts, a tilt reduction, a drop): restore_copy_in_place's test.
  std::uint64_t edition_ = 0;
  // Set by restore_copy_in_place: the whole model's list is the parts' list the step taken again
  // comes back to (its wraps renumber the pairs' images as the first time), so the next sync
  // need not make it again, unless the part's edition changed since kept_edition_.
  bool whole_list_kept_ = false;
  std::uint64_t kept_edition_ = 0;
  // split_from_file's pairs and wall contacts (in the whole model's numbers), which the first
  // rebuild_local takes in; whether their results are the model's.
  bool from_file_ = false, from_file_results_ = false;
  ContactTable file_pairs_;
  WallContacts file_walls_;
  double max_radius_ = 0;                    // the whole model's largest ball (at the split)
  double shell_base_ = 0;                    // the largest shell received at the first local rebuild
  // Each member's share of the balls at the next split (the same on every member), and this
  // member's own stepping since the last split: seconds in its forces and motion, ball-steps.
  std::vector<double> shares_;
  double work_seconds_ = 0, work_ball_steps_ = 0;
};

}  // namespace trubal
