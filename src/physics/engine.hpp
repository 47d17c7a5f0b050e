// Cycling: the time step, the specialised kernels for a scene, the instability guard.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "backends/backend.hpp"
#include "model/model.hpp"

namespace trubal {

// What a scene uses; each flag off removes work from the kernels (chosen once per CYCLE).
struct Features {
  bool rotation = true;     // some ball has a free spin component and shear forces exist
  bool friction = true;     // some material has ks > 0 (shear forces at all)
  bool hertz = false;
  bool stiffness_damping = false;   // Rayleigh beta or restitution dashpots
  DampKind mass_damping = DampKind::None;
  bool gravity = false;
  bool applied = false;
  bool periodic = false;
  std::string describe() const;     // for PRINT info
};

Features scene_features(const Model& model);

struct CycleControl {
  const std::atomic<bool>* interrupt = nullptr;   // set by Ctrl-C: stop at the end of the step
  // Called after every completed step (history, dumps); keep it cheap.
  std::function<void(const Model&)> after_step;
  // Whether after_step will read the contacts' results (normal, overlap, forces, state) after the
  // step that ends at this cycle; steps nobody reads skip writing them. Unset: every step.
  std::function<bool(std::int64_t cycle)> reads_contacts;
  // Called now and then for progress reports.
  std::function<void(std::int64_t done, std::int64_t total)> progress;
};

struct CycleResult {
  std::int64_t done = 0;
  bool interrupted = false;
  bool unstable = false;
  std::string message;              // for an unstable run: cycle, ball, suggested FRAC
  double seconds = 0;               // wall time of the loop
  PhaseTimes times;                 // where it went
};

// Checks that every ball's type has density and stiffness; throws std::runtime_error naming the type.
void check_ready(const Model& model);
// Derives mass and moment of inertia from the type densities.
void update_mass(Model& model);
// Critical time step of the current state (before FRAC), see PHYSICS.md "Time step".
double critical_timestep(const Model& model);
// The critical step the next cycle uses (its step is FRAC times this), from the one held now and the
// estimate of the state just computed (both capped by the Rayleigh step of the Hertz balls, `cap`).
// Linear law: the estimate, every cycle. Hertz: the tangent stiffness, and so the estimate, changes
// every step of a contact, and a step that follows it costs central differences their time symmetry
// (first-order impacts). So the held step is kept through a contact episode and replaced by the
// estimate only (1) between episodes, when no contact is stiffer than the cap; (2) when stability
// needs it: FRAC times the held step above max(0.9, FRAC) times the estimate; (3) when the estimate
// has grown to twice the held step. The step then changes a bounded number of times per contact,
// whatever FRAC, and the rebound is second order in the step.
double next_critical_step(double held, double estimate, double frac, double cap, bool hertz);
// Runs n steps (or until interrupted or unstable). On instability the model is left at the last
// good state, which can be printed and saved.
CycleResult run_cycles(Model& model, Backend& backend, std::int64_t n, const CycleControl& control);

}  // namespace trubal
