// The contact results a CYCLE deferred, made when read (cycle/run.hpp: make_results,
// make_results_to_read).
#include <exception>
#include <stdexcept>

#include <fmt/format.h>

#include "cycle/pair_list.hpp"
#include "cycle/pipeline.hpp"
#include "cycle/run.hpp"
#include "support/comm.hpp"

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

void make_results_to_read(Model& model, Pipeline& pipeline) {
  if (!pipeline.distributed() || comm::size() < 2) return make_results(model, pipeline);
  if (!pipeline.results_deferred(model)) {   // (the same answer on every rank)
    if (comm::root()) model.contacts.keep_results();
    return;
  }
  std::exception_ptr failure;
  try {
    comm::together([&] {
      if (!comm::root()) return;
      // The list every rank holds (rank 0's, handed over at the CYCLE's end): the step taken again
      // searches on its own and may keep other candidates beside the same touching pairs.
      const PairCandidates held = pair_list_of(model.contacts);
      {
        comm::Alone alone;
        Pipeline::Alone serial(pipeline);
        make_results(model, pipeline, true);
      }
      if (!holds_pairs(model.contacts, held)) install_pairs(model.contacts, held);
    }, "making the contact results");
  } catch (...) {
    failure = std::current_exception();
  }
  pipeline.clear_deferred();
  pipeline.invalidate();
  if (!failure) return;
  // Rank 0 may have put its model back to the step before, or be part way through it: every rank
  // goes back to rank 0's rescue copy (a collective call), then the failure is every rank's.
  pipeline.restore_rescue(model);
  pipeline.invalidate();
  std::rethrow_exception(failure);
}

}  // namespace trubal
