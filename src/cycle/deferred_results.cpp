// The contact results a CYCLE deferred, made when read (cycle/run.hpp: make_results,
// make_results_to_read).
#include <exception>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "cycle/pair_list.hpp"
#include "cycle/pipeline.hpp"
#include "cycle/run.hpp"
#include "support/comm.hpp"
#include "support/peak_memory.hpp"

namespace trubal {
namespace {

// The step taken again with the settings it was first taken with (a DAMP, FRAC, TSTEP or GRAV
// since changed them without making the results: Session::settings), and what such a setting
// changed of the state kept after it: the step estimated afresh at the next CYCLE, the energy
// terms no longer the last step's. Made once the model's state is that step's again (made());
// the settings are the model's again however the step ends.
class StepAgain {
 public:
  // critical_dt, at_step: the model's before anything was put back (where the caller put it back first).
  StepAgain(Model& model, const Pipeline::Deferred& left)
      : StepAgain(model, left, model.critical_dt, model.energy_at_step) {}
  StepAgain(Model& model, const Pipeline::Deferred& left, double critical_dt, const EnergyAtStep& at_step)
      : model_(model), now_(model.settings), critical_dt_(critical_dt), at_step_(at_step) {
    model.settings = left.settings;
  }
  StepAgain(const StepAgain&) = delete;
  StepAgain& operator=(const StepAgain&) = delete;
  void made() {
    made_ = true;
    model_.critical_dt = critical_dt_;
    model_.energy_at_step = at_step_;
  }
  ~StepAgain() {
    model_.settings = now_;
    if (!made_ && !(critical_dt_ > 0)) model_.critical_dt = 0;   // (put back to the copy: estimated afresh still)
  }

 private:
  Model& model_;
  const Settings now_;
  const double critical_dt_;
  const EnergyAtStep at_step_;
  bool made_ = false;
};

}  // namespace

void make_results(Model& model, Pipeline& pipeline, bool keep_rescue) {
  if (pipeline.results_deferred(model)) {
    const Pipeline::Deferred left = pipeline.deferred();
    pipeline.clear_deferred();
    StepAgain again(model, left);
    // The list as that step had it: the same search, or none (the SAVE that follows writes it).
    pipeline.restore_rescue(model);
    pipeline.rewind_step();
    CycleControl control;
    control.replay = !keep_rescue;
    if (control.replay) pipeline.release_rescue();
    const CycleResult r = run_cycles(model, pipeline, 1, control);   // its one step writes the results
    pipeline.count_results_made();
    if (r.unstable || r.left_box || !Pipeline::Deferred::of(model).same(left))
      throw std::logic_error(fmt::format(
          "internal error: cycle {} taken again to make its contact results did not give the same state", left.cycle));
    again.made();
    return;
  }
  model.contacts.keep_results();
}

namespace {

// Whether the deferred results were made already (by make_results_alone, which leaves the step
// deferred on every rank alike).
bool made_already(const Model& model) {
  return model.contacts.results_kept() && model.contacts.results_cycle == model.cycle;
}

// Rank 0 alone, under mpirun: the step a CYCLE deferred taken again through its whole model, from
// its rescue copy, by a serial pipeline of its own, so that nothing the ranks share changes: the
// ranks' parts (kept or not), the pipeline's list state and reference, the step left deferred on
// every rank (the next CYCLE reuses the copy, as every rank decides alike). The pair list every
// rank holds is put back after it, under its own versions (the search may keep other candidates
// beside the same touching pairs). On failure rank 0's model is put back to the list it held and
// marked stale (Pipeline::mark_whole_stale): the next collective call gathers it again.
// The pair list rank 0 holds, which the ranks share, and its versions (make_results_alone puts
// them back after its step).
struct HeldList {
  PairCandidates pairs;
  std::uint64_t pairs_version = 0, walls_version = 0;
  double critical_dt = 0;   // (and these, for StepAgain)
  EnergyAtStep at_step;
  static HeldList of(const Model& model) {
    return {pair_list_of(model.contacts), model.contacts.list_version, model.wall_contacts.list_version,
            model.critical_dt, model.energy_at_step};
  }
  void put_back(Model& model) const {
    if (!holds_pairs(model.contacts, pairs)) install_pairs(model.contacts, pairs);
    model.contacts.list_version = pairs_version;
    model.wall_contacts.list_version = walls_version;
  }
};

// held: the list as it was before rescue_to_root put rank 0's model back (where the copy is the
// parts'); else the list now.
void make_results_alone(Model& model, Pipeline& pipeline, const HeldList* before = nullptr) {
  if (made_already(model)) return;
  const Pipeline::Deferred left = pipeline.deferred();
  const HeldList held = before ? *before : HeldList::of(model);
  auto put_back_list = [&] { held.put_back(model); };
  StepAgain again(model, left, held.critical_dt, held.at_step);
  try {
    if (pipeline.policy().fail_remake == 0) {   // (a test's fault: TRUBAL_TEST_FAIL_AT "0 remake")
      pipeline.policy().fail_remake = -1;
      throw std::bad_alloc();
    }
    // (Where the copy is the parts', rescue_to_root put rank 0's model back to it already.)
    if (!pipeline.part_rescue()) pipeline.rescue().restore(model);
    const std::unique_ptr<Pipeline> serial = make_pipeline("serial", 1, 0, &pipeline.policy());
    CycleControl control;
    control.replay = true;   // (no copy of its own: it gave these bits once already)
    const CycleResult r = run_cycles(model, *serial, 1, control);   // its one step writes the results
    if (r.unstable || r.left_box || !Pipeline::Deferred::of(model).same(left))
      throw std::logic_error(fmt::format(
          "internal error: cycle {} taken again to make its contact results did not give the same state", left.cycle));
    again.made();
    put_back_list();
    pipeline.count_results_made();
  } catch (const std::bad_alloc&) {
    put_back_list();
    model.contacts.drop_results();
    pipeline.mark_whole_stale();
    throw std::runtime_error("rank 0 ran out of memory making the contact results (taking the CYCLE's last step "
                             "again); the model is as the CYCLE left it");
  } catch (...) {
    put_back_list();
    model.contacts.drop_results();
    pipeline.mark_whole_stale();
    throw;
  }
  return_free_memory();   // (the serial pipeline's list and index, freed)
}

}  // namespace

void results_onto_parts(Model& model, Pipeline& pipeline) {
  if (!pipeline.results_to_make_on_parts(model)) return;
  const Pipeline::Deferred left = pipeline.deferred();
  pipeline.clear_deferred();
  StepAgain again(model, left);
  // The copy of the step before put back: on the parts where each rank keeps its own and nothing
  // but that step changed them since, the copy then let go (the step writes over it, as serial's
  // make_results lets its copy go), so that a rank never holds its part, its copy and the results
  // at once; else the parts' state to rank 0 (current already but for a failed reading's), the
  // parts released, and rank 0's whole model put back, the others' light state (the step is then
  // split among the ranks afresh), the copy kept until the step is taken.
  // Rank 0's whole model hollow (a CYCLE's end left the state on the parts alone): nothing holds
  // the CYCLE's end but the parts the step is taken on.
  const bool hollow = pipeline.whole_hollow(model);   // (the same answer on every rank)
  Snapshot state_after;   // (the light state of the CYCLE's end, which a failure in place comes back to)
  state_after.take_light(model);
  const bool in_place = pipeline.restore_rescue_on_parts(model);
  if (in_place) {
    pipeline.release_rescue();
  } else {
    pipeline.release_parts(model);
    pipeline.restore_rescue_on_root(model);
  }
  bool stepping = false;
  try {
    comm::together([&] {   // (a test's fault: TRUBAL_TEST_FAIL_AT "R remake")
      if (pipeline.policy().fail_remake != comm::rank()) return;
      pipeline.policy().fail_remake = -1;
      throw std::bad_alloc();
    }, "making the contact results");
    // One step on the parts, its results left there (in place; else split from rank 0's model as a
    // CYCLE's first is, the others holding no balls).
    CycleControl control;
    control.replay = true;
    control.keep_parts = control.leave_results = true;
    const BrickStep::Counts counts = pipeline.counters().parts;   // (the CYCLE's, which PRINT counters tells)
    stepping = true;
    const CycleResult r = run_cycles(model, pipeline, 1, control);
    pipeline.set_part_counts(counts);
    // (Checked on every rank: each holds the same light state.)
    comm::together([&] {
      if (r.unstable || r.left_box || !Pipeline::Deferred::of(model).same(left))
        throw std::logic_error(fmt::format(
            "internal error: cycle {} taken again to make its contact results did not give the same state", left.cycle));
    }, "making the contact results");
    again.made();
    pipeline.release_rescue();
    pipeline.count_results_made();
  } catch (...) {
    // (Every rank: the failures in the step are agreed.) In place, rank 0's whole model hollow:
    // before the step began, the parts hold the copy's state, the step before, and the model's
    // light state is the copy's: kept so, its results not made; part way through the step they
    // hold no state whole, and the model is lost with them.
    if (in_place && hollow && !stepping) throw;
    if (in_place && hollow) {
      std::string what = "the step failed";
      try {
        throw;
      } catch (const std::exception& e) {
        what = e.what();
      } catch (...) {
      }
      pipeline.drop_parts_unsynced(model);
      model = Model{};
      throw std::runtime_error(fmt::format("{}; the model, which the ranks' parts alone held, was lost with the step "
                                           "taken again: RESTART from a save", what));
    }
    // In place: the parts part way through the step are dropped, and rank 0's whole model, which
    // the step did not touch, is the CYCLE's end again, without its results. Else the step before,
    // as the copy holds it.
    if (in_place) {
      state_after.restore_light(model);
      pipeline.drop_parts_unsynced(model);
    } else {
      pipeline.restore_rescue_on_root(model);
    }
    throw;
  }
}

void make_results_to_read(Model& model, Pipeline& pipeline) {
  if (!pipeline.distributed() || comm::size() < 2) return make_results(model, pipeline);
  // The ranks keep their parts: rank 0 alone reads its whole model (Command::on_ranks), the others
  // hold none (Session::whole_everywhere hands it over first).
  if (pipeline.parts_live(model)) {
    if (!comm::root())
      throw std::logic_error("internal error: the whole model was read on a rank that holds its part alone");
    // Where the others serve rank 0's command (Pipeline::serve_root): made on the parts, the step
    // taken again there, and gathered, and rank 0's whole model gathered from the parts where a
    // CYCLE left it hollow; else taken again here.
    if (pipeline.serving()) {
      if (pipeline.results_on_parts(model) || pipeline.results_deferred(model)) pipeline.request_part_results(model);
      pipeline.request_whole(model);
      model.contacts.keep_results();   // (made; else zero, as below)
      return;
    }
    if (pipeline.whole_hollow(model))
      throw std::logic_error("internal error: the whole model was read on rank 0 alone, where the ranks' parts alone hold it");
    if (pipeline.results_deferred(model)) {
      // (The parts' copies are put back together: a command that rank 0 alone runs reads the
      // results on every rank first, Session::results_on_root.)
      if (pipeline.part_rescue())
        throw std::logic_error("internal error: the contact results a CYCLE deferred were read on rank 0 alone, "
                               "where the ranks' parts hold the copy they are made from");
      make_results_alone(model, pipeline);
    } else if (pipeline.results_on_parts(model)) {
      throw std::logic_error("internal error: the contact results on the ranks' parts were read on rank 0 alone");
    } else {
      model.contacts.keep_results();
    }
    return;
  }
  // Every rank holds the whole model and reads it at the same points: rank 0 makes the results,
  // the others leave theirs unmade (ContactTable::results_kept false: the measurements read nothing
  // there; rank 0 alone prints and writes what they feed), so that their memory stays at the model's.
  if (!pipeline.results_deferred(model)) {   // (the same answer on every rank)
    if (comm::root()) model.contacts.keep_results();
    return;
  }
  try {
    // (Where the copy is the ranks' parts': put back on rank 0 first, a collective call.)
    HeldList held;
    if (pipeline.part_rescue() && comm::root()) held = HeldList::of(model);
    pipeline.rescue_to_root(model);
    comm::together([&] {
      if (comm::root()) make_results_alone(model, pipeline, pipeline.part_rescue() ? &held : nullptr);
    }, "making the contact results");
  } catch (...) {
    // Rank 0's model may be part way through the step taken again: every rank goes back to rank
    // 0's rescue copy, the step before (a collective call), and the failure is every rank's.
    pipeline.clear_deferred();
    pipeline.restore_rescue(model);
    pipeline.invalidate();
    throw;
  }
  pipeline.clear_deferred();
  // The next step searches afresh (the same pairs touch either way): the ranks then search on
  // their parts once split (Pipeline::prepare's PartsToSearch), not split the whole model's list
  // while they still hold it.
  pipeline.invalidate();
}

}  // namespace trubal
