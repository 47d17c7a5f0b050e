// The one API through which commands reach the engine: it owns the model, the backend and the
// history, and keeps them consistent (a change to the balls invalidates the pipeline's lists).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gen/pack.hpp"
#include "gen/size_distribution.hpp"
#include "cycle/run.hpp"
#include "cycle/step_policy.hpp"
#include "io/history.hpp"
#include "io/vtk.hpp"
#include "model/bond_table.hpp"
#include "model/centre_index.hpp"
#include "model/edit.hpp"
#include "model/held_balls.hpp"
#include "model/model.hpp"
#include "model/range.hpp"
#include "physics/measure.hpp"
#include "physics/overlap.hpp"
#include "physics/scene.hpp"

namespace trubal {

// (Declared only: the commands reach the pipeline through Session; the few that read it include
// cycle/pipeline.hpp themselves, so the step's headers are not compiled into every command.)
class Pipeline;

class Session {
 public:
  Session();
  ~Session();

  // The model, its contact results made first where the last CYCLE left them to be made when read
  // (make_results, cycle/run.hpp: one step taken again).
  const Model& model() const {
    make_results_to_read(model_, *pipeline_);
    return model_;
  }
  // The model for what reads of the contact results no more than which pairs touch
  // (touching_pairs): under mpirun, where they are made on the ranks' parts (results_onto_parts) and the
  // others serve rank 0's command, without them (rank 0 never holding them all); else model().
  const Model& model_but_results() const;
  // The model for what reads the bonds' table and the balls' ids alone (PRINT bonds): under mpirun,
  // where rank 0 serves a command and the parts alone hold the model, rank 0's hollow model with
  // the bonds' state gathered into its table (Pipeline::request_bonds); else model().
  const Model& model_for_bonds() const;
  // The pairs of balls that touch (physics/measure.hpp contact_count): from the parts' results
  // where model_but_results leaves them there (one array of bytes).
  std::size_t touching_pairs() const;
  // One of model_but_results().contacts' result arrays (`of`): itself where the table holds the
  // results, else fetched from the ranks' parts into `into`, which is returned (one array at a
  // time, so that a reader holds those it reads, not all).
  const std::vector<double>& results_of(const std::vector<double>& of, std::vector<double>& into) const;
  const std::vector<std::uint8_t>& results_of(const std::vector<std::uint8_t>& of, std::vector<std::uint8_t>& into) const;
  // The model as it is, its contact results and the balls' unbalanced forces perhaps not made
  // (ContactTable::results_kept): for what a CYCLE's report reads (cycle, time, counts).
  const Model& state() const { return model_; }
  // The model with each ball's mass and inertia from its type's density as they are now (CYCLE
  // sets them at its start): for measurements taken before the first CYCLE or after a PROP,
  // such as gravity's potential energy. Changes nothing else.
  const Model& model_with_masses();
  // For commands that change the balls: the backend's lists are invalidated, and the energy terms
  // of the last step (Model::energy_at_step) are no longer the state's.
  Model& edit();
  void set_title(const std::string& title) {
    model_.title = title;
    unsaved_ = true;
  }
  // SET sort: how often the run puts the balls in space order (Model::order; no change to the balls
  // now).
  void set_sort_every(std::int64_t every) {
    model_.order.every = every;
    unsaved_ = true;
  }
  // STRAIN and SERVO: the cell's and walls' settings (the space's strain rates and servo, a wall's
  // servo), with the balls unchanged; the next step is estimated afresh. Where the ranks keep their
  // parts, every rank calls it (Command::on_ranks) and the parts stay, as edit_walls: the results a
  // CYCLE deferred made on them, not gathered (but where a servo drives the cell: gathered to rank 0).
  Model& edit_cell();
  // WALL's motion and SERVO wall: a wall's motion or servo, the balls unchanged. Where the ranks
  // keep their parts, every rank calls it (Command::ranks_for, on_ranks): the contact results a
  // CYCLE deferred are made on the parts first, of the walls as they were, and stay there; the
  // parts stay, and the next step searches their lists afresh, as serial's after an edit. Else as
  // edit().
  Model& edit_walls();
  // INIT, APPLY, FIX and FREE: change(balls, k) on each ball where `range` holds; the count. Where
  // the ranks keep their parts every rank calls it (Command::ranks_for: parts_where_kept): each
  // changes its part's balls, its own and its ghosts, as edit_walls the walls (the results made on
  // the parts first, the parts kept, the next step searching afresh; rank 0's whole model, where not
  // hollow, changed alike), and the count is summed over the ranks. Else on edit()'s model.
  // `fixities`: it changes Balls::fixed, which rank 0's hollow whole model keeps (streamed to it from
  // the parts after).
  std::size_t change_balls(const Range& range, const std::function<void(Balls&, std::size_t)>& change,
                           bool fixities = false);
  // New strain rates of the periodic cell, and the change of the velocity field they make on the
  // balls, wherever the balls are (the ranks' kept parts; rank 0's whole model made current).
  void set_cell_rates(const std::array<double, 6>& rates);
  // SAMPLE: the specimen's walls and reference (no change to the balls or the step).
  Sample& edit_sample() {
    unsaved_ = true;
    return model_.sample;
  }
  // For settings that do not touch the balls (damping, gravity, frac); the next step is
  // estimated afresh, and PRINT energy takes the state as it is until the next step. The contact
  // results a CYCLE deferred stay so: the step taken again to make them reads the settings it was
  // taken with (Pipeline::Deferred), and a CYCLE that follows has no use for them.
  Settings& settings() {
    model_.critical_dt = 0;
    model_.energy_at_step.valid = false;   // gravity's potential, say, is no longer the last step's
    unsaved_ = true;
    return model_.settings;
  }

  // Under mpirun, after a CYCLE: each rank holds its own part of the model, and the ranks other than
  // 0 no more of the whole than its balls' ids, types and radii (rank 0 holds the whole model as
  // well, current). The next CYCLE goes on from the parts; a command that needs the whole model on
  // every rank has it handed over first (whole_everywhere: a collective call, made by the
  // interpreter for each command as Command::on_ranks says).
  bool parts_kept() const;
  void whole_everywhere();
  // Under mpirun, a command that changes the model alone (its balls, materials, walls, groups,
  // bonds: OnRanks::ModelOnZero) runs on rank 0 alone, on its whole model. model_on_zero, made
  // first on every rank: where the ranks keep their parts, rank 0's model takes their state and the
  // parts end (a collective call); then the others hold only the balls' ids, types and radii of the
  // model, and the rest of rank 0's state after it (light_everywhere: a collective call where such
  // a command ran since, made before any command of another kind) until a command or a CYCLE needs
  // the whole model (whole_everywhere, or the CYCLE's split: rank 0 sends each rank its part).
  void model_on_zero();
  void light_everywhere();
  // A command that only reads the model (OnRanks::RankZero) under mpirun: rank 0 runs `work` alone
  // while the others serve what it asks of them (the contact results made on
  // the parts, where the command reads them: Pipeline::serve_root), until it ends; one process
  // runs it. Made on every rank.
  void run_on_root(const std::function<void()>& work);

  // Each rank's memory figures (PRINT info, PRINT counters), gathered by a collective call under
  // mpirun (gather_rank_figures, before a command that rank 0 alone runs); this process's alone on
  // one rank.
  struct RankFigures {
    double peak_mib = 0;           // peak resident memory so far
    double results_mib = 0;        // the contact results held (its part's included)
    double whole_arrays_mib = 0, part_arrays_mib = 0;   // the arrays held in the last distributed step
    double model_arrays_mib = 0;   // the arrays of the model this rank holds now (its part's included)
    double rescue_mib = 0;         // the rescue copy's arrays this rank holds (Pipeline::rescue_bytes)
  };
  void gather_rank_figures();
  std::vector<RankFigures> rank_figures() const;

  // The step pipeline: its backend (pair finding) and threads.
  const Pipeline& pipeline() const { return *pipeline_; }
  // How the steps are shared where the default is a timed choice, and the faults a test injects
  // (cycle/step_policy.hpp): every pipeline of the session reads this one, BACKEND's too.
  StepPolicy& policy() { return policy_; }
  // BACKEND: threads <= 0 the backend's default; max_memory 0 its default (throws
  // std::invalid_argument for a bad name or option).
  void set_backend(const std::string& name, int threads, std::uint64_t max_memory = 0);

  // START: a new model (the backend choice and the interpreter's variables stay).
  // periodic: the axes whose faces are periodic (mixed periodicity); the others are bounded.
  void start_box(const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                 const std::array<Outside, 3>& outside = {Outside::Stop, Outside::Stop, Outside::Stop},
                 const std::array<bool, 3>& periodic = {false, false, false});
  void start_periodic(const std::array<double, 3>& length, const std::array<int, 3>& boxes);
  void require_started() const;

  std::size_t add_ball(std::int64_t id, int type, double x, double y, double z, double rad);
  // BALL: the ball added (add_ball), or where the ranks hold BALL lines (hold_balls), held: every
  // rank runs it, checks its part of BALL's rules and keeps the ball where its centre's hash says
  // (model/held_balls.hpp). Returns the ball's id.
  std::int64_t add_ball_line(std::int64_t id, int type, double x, double y, double z, double rad);
  // One ball held (hold_balls), its rules checked before (add_ball_line; LATTICE checks its own):
  // the next free id where id <= 0; returns the id.
  std::int64_t hold_ball(std::int64_t id, int type, double x, double y, double z, double rad);
  // Under mpirun in a batch deck (the interpreter's word before each command: Interpreter::execute),
  // with BACKEND mpi: BALL lines are held on the ranks rather than built into rank 0's model. The
  // same on every rank.
  void set_hold_balls(bool hold) { hold_balls_ = hold && comm_size_ > 1; }
  bool hold_balls() const { return hold_balls_ && distributed(); }
  // Whether BALL, to be held, first needs a collective call (hold_start: the parts released, the
  // others given rank 0's light state); the same on every rank.
  bool hold_needs_start() const;
  // That call: before the first held BALL line (each rank then takes the model as it is).
  void hold_start();
  // The balls held, on all ranks (every rank's count); placed in the model by place_held, a
  // collective call: every rank sends its balls to rank 0, which adds them in the lines' order, a
  // chunk of lines at a time. Every command that reads the balls has them placed first
  // (Interpreter::run_agreed, Command::held).
  std::uint64_t held_balls() const { return held_.total; }
  void place_held();
  // GEN under hold_balls: whether the model holds no ball, none is held and no bond (rank 0's
  // word, broadcast: a collective call). Where it does, GEN (rank 0 alone running it) keeps the
  // balls it makes aside, and hand_out_generated (a collective call) has every rank hold them as
  // BALL lines, rank 0 broadcasting them a chunk at a time: no rank builds the whole model.
  bool generates_held();
  void hand_out_generated();
  // DELETE under hold_balls: whether balls are held and the model holds no other ball and no bond
  // (rank 0's word, broadcast: a collective call). Where so, DELETE (every rank running it) deletes
  // those of each rank's held balls the range holds (each read as the ball it will be), the lines
  // renumbered and the next free id found again as serial's DELETE leaves them: delete_balls, a
  // collective call, until end_held_command.
  bool deletes_held();
  // The command that generates_held or deletes_held was asked for has run.
  void end_held_command() { generating_held_ = deleting_held_ = false; }
  // For a CYCLE: the held balls made the ranks' parts straight away where the model holds no other
  // ball (nor a bond) and none lies outside a periodic cell (Pipeline::parts_from_records: rank 0 gathers their ids,
  // types, radii and centres alone, checks them, sorts them into space order and decomposes them,
  // and each rank sends its balls to their owners); else place_held. A collective call.
  void place_held_as_parts();
  // Rank 0 takes each held ball in the lines' order (`take`: id, type, x, y, z, radius) while every
  // rank sends its own, 256 Ki lines a gather (a collective call). A failure of take is returned,
  // not thrown: the others' sends went on, and the caller has the ranks agree on it.
  std::exception_ptr gather_held(const std::function<void(std::int64_t, int, double, double, double, double)>& take);
  // GEN: returns how many were placed (fewer than n when there is no room).
  std::size_t generate(std::size_t n, double rlo, double rhi, int type, std::uint64_t seed, const Range& range);
  // GEN with a size distribution: n balls (count > 0) or a target porosity; the balls' types
  // shared by mass fraction (type, fraction; fractions summing to 1), largest ball first.
  struct GenSpec {
    SizeDistribution sizes;
    std::size_t count = 0;
    double porosity = -1;
    std::vector<std::pair<int, double>> types{{1, 1.0}};
    std::uint64_t seed = 0;
    Range range;
  };
  PackResult generate(const GenSpec& spec);
  // The sizes the last GEN asked for, and the ids of the balls it made (PRINT psd).
  const std::optional<SizeDistribution>& last_sizes() const { return last_sizes_; }
  const std::vector<std::int64_t>& last_generated() const { return last_generated_; }
  // LATTICE: which layers to build (layer 0 is even: the nx x ny one).
  enum class Layers { All, Even, Odd };
  std::size_t lattice_fcc(double d, int nx, int ny, int nz, const std::array<double, 3>& origin, int type,
                          const Range& range, Layers layers = Layers::All);
  std::size_t delete_balls(const Range& range);
  // BOND (model/bond_table.hpp): bonds the pairs of balls of the range within the spec's gap, or
  // deletes the bonds that hold a ball of the range. Return how many.
  std::size_t make_bonds(const Range& range, const BondSpec& spec);
  std::size_t delete_bonds(const Range& range);
  // RENUMBER (model/edit.hpp renumber_balls): the balls get ids 1..N in space order or their present
  // order; groups, the membrane, the histories' platens and GEN's last balls follow them. The balls
  // themselves do not change: the last step's energies and step estimate stay the state's.
  Renumbering renumber(RenumberOrder order);
  // PROP: type's material. Where the ranks keep their parts every rank calls it (parts_where_kept):
  // each sets it, and each part takes the materials and its balls' masses from them (as edit_walls:
  // the results made on the parts first, the parts kept); else on edit()'s model. A law with history
  // new to the scene gets its part of every pair's history, zero (ContactTable::history_laws).
  void set_material(int type, const Material& material);
  // GROUP: the ids where `range` holds now; where the ranks keep their parts (every rank calling
  // it) read on their own balls, every rank given them all.
  std::size_t define_group(const std::string& name, const Range& range);

  // Selected balls (ascending index), and a check that the range selects some (warning text).
  std::vector<std::size_t> select(const Range& range) const { return trubal::select(model_, range); }

  // CYCLE / SOLVE. The interrupt flag is the process's Ctrl-C flag.
  // defer_results: the last step's contact results are made when next read (CycleControl).
  // keep_parts: under mpirun, each rank keeps its part after the run (parts_kept; CYCLE's way).
  CycleResult cycle(std::int64_t n, const std::function<void(std::int64_t, std::int64_t)>& progress = {},
                    bool defer_results = false, bool keep_parts = false);
  struct SolveResult { CycleResult run; double ratio = 0; bool converged = false; };
  SolveResult solve(double ratio, std::int64_t limit,
                    const std::function<void(std::int64_t, std::int64_t)>& progress = {});
  // CYCLE ... until: at most `limit` cycles, checking `measure` every `every` cycles, until it reaches
  // `target` (a positive target at or above it, a negative one at or below, 0 from the side it
  // starts on; at once where it is there already); or until it has not
  // moved from where it started over ten checks (stalled), or, for a measure `driven` one way (an
  // axial strain, the time), has gone farther from the target at each of ten checks (receding).
  // `measure` runs on rank 0 alone, given its model (its light state where the ranks keep their
  // parts: the stress comes from average_stress_in), the others serving it; every rank takes its
  // value. Under mpirun the CYCLEs of k keep the ranks' parts, as CYCLE does.
  struct UntilResult {
    CycleResult run;
    double start = 0, value = 0;
    bool reached = false, stalled = false, receding = false;
  };
  UntilResult cycle_until(std::int64_t limit, const std::function<double(const Model&)>& measure, double target,
                          bool driven, std::int64_t every,
                          const std::function<void(std::int64_t, std::int64_t)>& progress = {});

  History& history() { return *history_; }
  const History& history() const { return *history_; }

  // DUMP vtk: writes a dump now; with every > 0 also every `every` cycles from now on.
  // START and RESTART stop periodic dumps.
  void dump_vtk(const std::string& base, std::int64_t every);
  void dump_off() { dumps_.reset(); }
  const VtkSeries* dumps() const { return dumps_.get(); }

  // What all CYCLE and SOLVE runs of the session took, for the summary at exit.
  struct RunTotals {
    std::int64_t cycles = 0;
    double ball_cycles = 0;
    double seconds = 0;          // wall time in the cycling loop
    PhaseTimes times;
  };
  const RunTotals& totals() const { return totals_; }

  // SAVE / RESTART (io/save.hpp does the file format). SAVE keeps the histories; RESTART resumes
  // them, appending to their files, and returns what it had to do to those files (notes).
  void save(const std::string& path) const;
  std::vector<std::string> restart(const std::string& path);
  // Whether the model changed (START, an edit, a setting, a CYCLE) since the last SAVE or RESTART:
  // the shell says so before it lets the session end.
  bool unsaved() const { return unsaved_; }

  std::uint64_t seed = 12345;          // SET seed: default seed of GEN
  bool gen_interrupted = false;        // the last GEN was stopped by Ctrl-C
  bool gen_missed_range = false;       // the last GEN n stopped since no place it drew was in the range
  double overlap_warned = 0;           // the largest overlap ratio a run last warned of (0: none outstanding)
  double volume = 0;                   // SET volume: volume for stress in free space (0: the box)
  // Volume used for the average stress: SET volume, else the periodic cell or START box.
  double stress_volume() const;
  // The contact results a CYCLE deferred made in rank 0's model, every rank taking part (a
  // collective call): before a command that every rank runs reads the model on rank 0 alone
  // (comm::on_root), where the ranks' parts hold the copy they are made from.
  // Rank 0's whole model is made current too, gathered from the kept parts where a CYCLE left it
  // hollow (Pipeline::whole_hollow: results_before_setting).
  void results_on_root() { results_before_setting(); }
  // HIST's platen balls where `range` holds now: their ids, and their heights and forces in `rows`
  // (rank 0's; a collective call). Read on the parts where the ranks keep them, rank 0 gathering
  // no whole model for it.
  std::vector<std::int64_t> platen_choice(const Range& range, PlatenBalls& rows);
  // What PRINT info and counters tell of the state without the whole model on rank 0: the pairs
  // and wall contacts touching, the capillary bridges between balls and to walls, and whether some
  // ball spins or carries a load (where the model's arrays do not say: `flags` empty where they do). Under
  // mpirun, rank 0 running a command the others serve, summed over the kept parts where rank 0's
  // whole model is hollow; else counted on model_but_results().
  struct StateCounts {
    std::size_t touching = 0, wall_touching = 0, bridges = 0, wall_bridges = 0;
    std::optional<BallFlags> flags;
  };
  StateCounts state_counts() const;
  // The average stress in `volume` (physics/measure.hpp average_stress): under mpirun, rank 0
  // running a command the others serve, from the kept parts' exact sums where rank 0's whole model
  // is hollow (as state_counts: the whole model is not gathered); else from model().
  Sym6 average_stress_in(double volume) const;
  // The contact measures' sums (physics/measure.hpp contact_sums: fabric, coordination, sliding,
  // unbalanced force) of the whole space, as average_stress_in: from the parts where rank 0's
  // whole model is hollow.
  ContactSums whole_contact_sums() const;
  // A measurement sphere's measurement (physics/measure_sphere.hpp), as average_stress_in: from
  // the parts where rank 0's whole model is hollow. Throws std::runtime_error as measure_sphere.
  SphereMeasurement measure_in(const MeasureSphere& sphere) const;
  // Ball array `of` of the model (one of its arrays of reals): itself, or streamed from the kept
  // parts into `into` where rank 0's whole model is hollow (as state_counts).
  const std::vector<double>& ball_array(const std::vector<double>& of, std::vector<double>& into) const;
  // Under mpirun, rank 0 running a command the others serve, where rank 0's whole model is hollow:
  // the rows of PRINT balls (every ball, by id) and contacts (every pair touching, or holding a
  // bridge where `bridges`, by ids) streamed from the kept parts (BrickStep::stream_ball_rows,
  // stream_contact_rows); rows_from_parts says where. The results made on the parts first.
  bool rows_from_parts() const;
  void ball_rows(const std::function<void(const double*)>& take, const Range& range = {}) const;
  void contact_rows(bool bridges, const std::function<void(const double*)>& take, const Range& range = {}) const;
  // The largest overlap (physics/overlap.hpp) on rank 0: from the kept parts where rank 0's whole
  // model is hollow (a collective call, every rank taking part); else rank 0's whole model's.
  LargestOverlap largest_overlap_now();

 private:
  void start(const Space& space);   // a fresh model in this space; histories and dumps end
  // What every change of the balls marks (edit(), hold_ball): a change, unsaved, the last step's
  // energy terms no longer the state's, the lists invalidated, the step estimated afresh.
  void mark_edited();
  // The same but the lists (edit_cell, edit_walls: the parts, where kept, stay).
  void mark_changed();
  // edit_walls' and change_balls' work on the kept parts before the change (every rank): the results
  // made there, the next step searching afresh.
  void edit_on_parts();
  // A dump from the ranks' kept parts (their rows merged to rank 0, which writes): every rank calls
  // it, at a CYCLE's output step or for DUMP, the results on the parts.
  void dump_from_parts(VtkSeries& dumps, const Model& model);
  // Whether rank 0's model has no bond, agreed by every rank (a collective call under mpirun).
  bool bonds_agreed_empty() const;
  // The contact results a CYCLE deferred, made before a setting changes (the step taken again
  // reads the settings). Where the ranks keep their parts, rank 0's alone, agreed by every rank
  // (each runs the setting's command: Command::on_ranks).
  void results_before_setting();
  // Under mpirun, rank 0 running a command the others serve, the contact results on their parts
  // (Pipeline::results_on_parts): what model_but_results leaves there.
  bool results_from_parts() const;
  // results_of's work, for either element type.
  template <class T> const std::vector<T>& fetch_results(const std::vector<T>& of, std::vector<T>& into) const;
  // mutable: model() makes deferred results (a cache of what the state determines).
  mutable Model model_;
  std::vector<RankFigures> rank_figures_;   // gathered by gather_rank_figures (several ranks)
  StepPolicy policy_;   // (before pipeline_, which reads it to the end)
  std::unique_ptr<Pipeline> pipeline_;
  std::unique_ptr<History> history_;
  std::unique_ptr<VtkSeries> dumps_;
  RunTotals totals_;
  std::optional<SizeDistribution> last_sizes_;
  std::vector<std::int64_t> last_generated_;
  bool generating_held_ = false;   // generates_held's word, for the GEN it runs before
  bool deleting_held_ = false;     // deletes_held's, for the DELETE
  std::size_t delete_held(const Range& range);
  // The balls GEN made for hand_out_generated (rank 0's), x y z r and type, in their order.
  std::vector<std::array<double, 5>> generated_;
  // The balls GEN made, x y z r, their types and their order: added to the model, or held.
  void keep_generated(const std::vector<std::array<double, 4>>& balls, const std::vector<int>& types,
                      const std::vector<std::size_t>& order);
  // BALL's check that no two balls share a centre, built afresh after any other change of the
  // balls (changes_ counts them: edit, cycle, start, restart).
  CentreIndex centres_;
  // Cycles in chunks of `chunk` until `limit`, an interruption or instability, or `stop()` (asked
  // after each chunk on every rank; every rank takes rank 0's answer): SOLVE's and CYCLE ...
  // until's loop. `on_parts`: each chunk a CYCLE's (its last step's results deferred, the ranks
  // keeping their parts).
  CycleResult cycle_in_chunks(std::int64_t limit, std::int64_t chunk,
                              const std::function<void(std::int64_t, std::int64_t)>& progress,
                              const std::function<bool()>& stop, bool on_parts = false);
  // BALL lines held on the ranks (hold_balls): this rank's, and the counts every rank keeps.
  HeldBalls held_;
  bool hold_balls_ = false;
  int comm_size_ = 1;
  bool distributed() const;
  // BALL's check that a centre lies in the START box, where it is bounded.
  void check_in_box(double x, double y, double z) const;
  std::uint64_t changes_ = 0, centres_changes_ = ~std::uint64_t{0};
  mutable bool unsaved_ = false;   // (SAVE is const: it changes nothing in the model)
  // model_on_zero ran since the last light_everywhere (every rank alike).
  bool light_pending_ = false;
};

}  // namespace trubal
