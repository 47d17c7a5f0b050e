// The loop over steps: CYCLE's n steps through the one pipeline (cycle/pipeline.hpp), the time
// step, the instability guard and its rescue copy, observers between steps.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "cycle/phase_times.hpp"
#include "model/model.hpp"

namespace trubal {

class Pipeline;

struct CycleControl {
  const std::atomic<bool>* interrupt = nullptr;   // set by Ctrl-C: stop at the end of the step
  // Called after every completed step (history, dumps); keep it cheap.
  std::function<void(const Model&)> after_step;
  // Whether after_step will read the contacts' results (normal, overlap, forces, state) after the
  // step that ends at this cycle; steps nobody reads skip writing them. Unset: every step.
  std::function<bool(std::int64_t cycle)> reads_contacts;
  // A distributed run's output steps: after_step runs on rank 0 alone (the others' whole model is
  // not current there), then this on every rank, to hand on what it recorded (History::share_rows).
  std::function<void()> share_output;
  // A distributed run that keeps its parts (keep_parts): where set, its output steps call this on
  // every rank at once (a collective call) in place of after_step and share_output, from the
  // sums made on the parts (Pipeline::stress_on_parts, contact_sums_on_parts): no rank gathers the
  // whole model for them. Where the parts are not live at the step, after_step as above.
  std::function<void(const Model&)> after_step_on_parts;
  // With after_step_on_parts: whether an observer reads the whole model after the step that ends at
  // this cycle (a dump): that step goes by after_step, the whole model gathered to rank 0.
  std::function<bool(std::int64_t cycle)> reads_whole;
  // Called now and then for progress reports.
  std::function<void(std::int64_t done, std::int64_t total)> progress;
  // The last step's results (and the 500th steps' before the rescue copies) are not written: the
  // result arrays are freed, and make_results takes the last step again from the rescue copy when
  // they are read (CYCLE's way: their memory is two fifths of the model's). Under mpirun they are
  // made on the ranks' parts, or by rank 0 alone (make_results_to_read). One stopped early and
  // one whose last step an observer reads write them as usual.
  bool defer_results = false;
  // The step a CYCLE deferred, taken again from the rescue copy put back and released (make_results):
  // it takes no copy of its own, as it gave these bits once already; a failure is an internal error.
  bool replay = false;
  // A distributed run on several ranks: each rank keeps its part at the end (Pipeline::end_cycle),
  // and a run that starts with the parts live goes on from them (Session::parts_kept).
  bool keep_parts = false;
  // With keep_parts, on several ranks: the last step (unless stopped or observed) writes its
  // results on the parts, which keep them; rank 0's table has none (results_onto_parts: the step
  // taken again there).
  bool leave_results = false;
};

inline constexpr double kBalanceWarning = 0.01;   // of the energy that moved: CycleResult::energy_warning

struct CycleResult {
  std::int64_t done = 0;
  bool interrupted = false;
  bool unstable = false;
  bool left_box = false;            // a ball left a START box across a `stop` face (message says which)
  std::size_t destroyed = 0;        // balls deleted for leaving across a `destroy` face
  std::string message;              // for an unstable run: cycle, ball, suggested FRAC
  // The energy balance at each step's force pass (doc/physics.md "Energy"): its largest distance
  // from the first step's, and the largest energy in play (kinetic, strain and the magnitudes of
  // the potential's change and of the works since the first step): the energy that moved.
  double balance_error = 0, energy_scale = 0;
  // Set where balance_error passed kBalanceWarning of energy_scale: what to tell the user once the
  // CYCLE is over, with the FRAC (or TSTEP) that would have held it.
  std::string energy_warning;
  double seconds = 0;               // wall time of the loop
  PhaseTimes times;                 // where it went
};

// Runs n steps (or until interrupted or unstable) on the pipeline. On instability the model is left
// at the last good state, which can be printed and saved: where the CYCLE started, or its last
// multiple of 500 steps (taken again from the rescue copy, which is of a step before).
//
// What a step leaves current (the contract every reader relies on): positions at t + dt,
// velocities and spins at t + dt/2, the shear history and the servo's moments of the force pass at
// t, and model.cycle, time, dt, critical_dt, energy advanced. The per-contact results (normal,
// overlap, forces, stiffness, work, state) and the balls' unbalanced forces and moments are those
// of the force pass of the step that ended at cycle ContactTable::results_cycle: every CYCLE's
// last step writes them (or defers them: CycleControl::defer_results), and so do the steps whose cycle an observer reads (reads_contacts), the
// step a Ctrl-C ends and the one before every 500th (the rescue copy's); other steps skip the writes
// and compute the same numbers. The walls' loads (Wall::force, moment, normal_force, stiffness,
// contacts) are formed on those steps too, on every CYCLE's last step whether or not its results
// are deferred, and on every step while a wall servo runs; each wall's work on every step. The
// energy terms at t (Model::energy_at_step) are formed on the steps that form the walls' loads (but
// not for a wall servo alone), on each CYCLE's first step and on the guard's checks, every
// EnergyGuard::kCheckEvery cycles of the model's count; the other steps mark them not valid. The
// works (Model::energy) count every step.
CycleResult run_cycles(Model& model, Pipeline& pipeline, std::int64_t n, const CycleControl& control);

// Makes the model's contact results current where they can be: a CYCLE that deferred its last
// step's (CycleControl::defer_results) has it taken again from the rescue copy, to the same bits
// (throws std::logic_error where it does not come back to them); else the result arrays are made
// of the list's length, zero where they were not kept (results_cycle -1). Every reader of the
// results (the Session's model()) calls it first.
// keep_rescue: the copy is kept (a distributed run's rank 0: every rank goes back to it where this
// fails); else it is freed before the results take their memory.
void make_results(Model& model, Pipeline& pipeline, bool keep_rescue = false);

// make_results for what a command reads (the Session's model()). Under mpirun, where the ranks keep
// their parts and serve rank 0's command (Pipeline::serve_root), the results are made on the parts
// and gathered (Pipeline::request_part_results); else rank 0 alone takes the deferred step again,
// through its whole model with a serial pipeline of its own, for what it alone prints and writes:
// where the ranks keep their parts, rank 0 alone reads (Command::on_ranks);
// where every rank holds the whole model, every rank calls this at the same points and the others
// leave their results unmade (ContactTable::results_kept false: the measurements read nothing
// there), so that their memory stays at the model's. Should rank 0 fail (out of memory), its
// model is gathered from the parts again at the next collective call where they are kept; else
// every rank goes back to the rescue copy, the step before, and the command fails everywhere with
// rank 0's message.
void make_results_to_read(Model& model, Pipeline& pipeline);

// Under mpirun, where the ranks keep their parts and a CYCLE deferred its last step's results
// (a collective call; the same answer on every rank): the step taken again on the parts, from
// their copies of the step before put back in place (Pipeline::restore_rescue_on_parts), else from
// rank 0's whole model put back to them (restore_rescue_on_root); its results are left there
// (Pipeline::results_on_parts) for what reads them, and the copy goes, as serial's make_results
// lets it go (the results are made). Where it fails, the model is the CYCLE's end, without
// the results (their copy went: in place), or the step before (the copy put back), and it throws.
void results_onto_parts(Model& model, Pipeline& pipeline);

}  // namespace trubal
