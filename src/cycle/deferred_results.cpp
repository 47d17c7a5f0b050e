// The contact results a CYCLE deferred, made when read (cycle/run.hpp: make_results,
// make_results_to_read).
#include <exception>
#include <memory>
#include <new>
#include <stdexcept>

#include <fmt/format.h>

#include "cycle/pair_list.hpp"
#include "cycle/pipeline.hpp"
#include "cycle/run.hpp"
#include "support/comm.hpp"
#include "support/peak_memory.hpp"

namespace trubal {

void make_results(Model& model, Pipeline& pipeline, bool keep_rescue) {
  if (pipeline.results_deferred(model)) {
    const Pipeline::Deferred left = pipeline.deferred();
    pipeline.clear_deferred();
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
void make_results_alone(Model& model, Pipeline& pipeline) {
  if (made_already(model)) return;
  const Pipeline::Deferred left = pipeline.deferred();
  const PairCandidates held = pair_list_of(model.contacts);
  const std::uint64_t pairs_version = model.contacts.list_version, walls_version = model.wall_contacts.list_version;
  auto put_back_list = [&] {
    if (!holds_pairs(model.contacts, held)) install_pairs(model.contacts, held);
    model.contacts.list_version = pairs_version;
    model.wall_contacts.list_version = walls_version;
  };
  try {
    if (pipeline.policy().fail_remake == 0) {   // (a test's fault: TRUBAL_TEST_FAIL_AT "0 remake")
      pipeline.policy().fail_remake = -1;
      throw std::bad_alloc();
    }
    pipeline.rescue().restore(model);
    const std::unique_ptr<Pipeline> serial = make_pipeline("serial", 1, 0, &pipeline.policy());
    CycleControl control;
    control.replay = true;   // (no copy of its own: it gave these bits once already)
    const CycleResult r = run_cycles(model, *serial, 1, control);   // its one step writes the results
    if (r.unstable || r.left_box || !Pipeline::Deferred::of(model).same(left))
      throw std::logic_error(fmt::format(
          "internal error: cycle {} taken again to make its contact results did not give the same state", left.cycle));
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
  // The parts' state to rank 0 (current already but for a failed reading's), the parts released,
  // and the copy of the step before put back: rank 0's whole, the others' light state.
  pipeline.release_parts(model);
  pipeline.restore_rescue_on_root(model);
  try {
    comm::together([&] {   // (a test's fault: TRUBAL_TEST_FAIL_AT "R remake")
      if (pipeline.policy().fail_remake != comm::rank()) return;
      pipeline.policy().fail_remake = -1;
      throw std::bad_alloc();
    }, "making the contact results");
    // One step from rank 0's copy, split among the ranks as a CYCLE's first is (the others hold
    // no balls), its results left on the parts and deferred again, the copy kept.
    CycleControl control;
    control.replay = true;
    control.defer_results = control.keep_parts = control.leave_results = true;
    const BrickStep::Counts counts = pipeline.counters().parts;   // (the CYCLE's, which PRINT counters tells)
    const CycleResult r = run_cycles(model, pipeline, 1, control);
    pipeline.set_part_counts(counts);
    // (Checked on rank 0, whose model is the one read: the others' light energies may differ from
    // it in the last bits, which the next hand-over of rank 0's light state mends.)
    comm::on_root([&] {
      if (r.unstable || r.left_box || !Pipeline::Deferred::of(model).same(left))
        throw std::logic_error(fmt::format(
            "internal error: cycle {} taken again to make its contact results did not give the same state", left.cycle));
    }, "making the contact results");
    pipeline.count_results_made();
  } catch (...) {
    // (Every rank: the failures in the step are agreed.) The step before, as the copy holds it.
    pipeline.restore_rescue_on_root(model);
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
    // taken again there, and gathered; else taken again here.
    if (pipeline.serving() && (pipeline.results_on_parts(model) || pipeline.results_deferred(model)))
      return pipeline.request_part_results(model);
    if (pipeline.results_deferred(model)) make_results_alone(model, pipeline);
    else model.contacts.keep_results();
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
    comm::together([&] { if (comm::root()) make_results_alone(model, pipeline); }, "making the contact results");
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
