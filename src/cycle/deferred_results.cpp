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
  // Under mpirun no run defers its results (Session::cycle): its last step made them on the ranks'
  // parts, gathered to rank 0, which alone prints and writes them. Where the parts are kept, the
  // others hold no whole model to read (Session::whole_everywhere hands it over first).
  if (pipeline.results_deferred(model) || (pipeline.parts_live(model) && !comm::root()))
    throw std::logic_error("internal error: the whole model was read on a rank that does not hold it");
  if (comm::root()) model.contacts.keep_results();
}

}  // namespace trubal
