// make_kernels: the loops of one CYCLE, picked from the kernel tables (kernels_*.cpp, the templates
// in kernel_contacts.hpp, kernel_walls.hpp and kernel_motion.hpp) for the features the scene uses.
#include "cycle/kernels.hpp"

#include "cycle/kernel_tables.hpp"

namespace trubal {

StepKernels make_kernels(const Model& model) { return make_kernels(model, scene_features(model)); }

StepKernels make_kernels(const Model& model, const Features& features) {
  StepKernels k;
  k.features = features;
  const Features& f = k.features;
  const Damping& damping = model.settings.damping;
  if (damping.kind == DampKind::Rayleigh) { k.alpha = damping.alpha; k.beta = damping.beta; }
  if (damping.kind == DampKind::Local) k.local = damping.local;
  if (f.gravity) k.gravity = model.settings.gravity;

  k.laws = make_pair_laws(model);

  if (model.settings.fixed_dt > 0) k.estimate = StepEstimate::None;
  else k.estimate = f.stiffness_damping ? StepEstimate::Damped : StepEstimate::Undamped;

  ContactFeatures contact{f.rotation, f.friction, f.hertz, f.stiffness_damping, false, f.rolling};
  k.contacts_lean = loops::contact_loop_lean(contact.index());
  k.cross = loops::cross_loop_at(contact.index());
  k.walls_lean = loops::wall_loop_at(contact.index());
  contact.details = true;
  k.contacts_full = loops::contact_loop_full(contact.index());
  k.walls_full = loops::wall_loop_at(contact.index());
  k.walls = k.walls_full;
  k.contacts = k.contacts_full;
  MotionFeatures motion{f.rotation, f.gravity || f.applied, f.mass_damping, k.estimate, false};
  k.motion_lean = loops::motion_loop_lean(motion.index());
  motion.write_forces = true;
  k.motion_full = loops::motion_loop_full(motion.index());
  k.motion = k.motion_full;
  return k;
}


}  // namespace trubal
