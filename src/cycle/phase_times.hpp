// Where cycling time goes, in seconds: added up by the pipeline (detect, forces, motion) and the
// loop (step, output). Not part of the model.
#pragma once

namespace trubal {

struct PhaseTimes {
  double detect = 0;     // pair lists and contact detection
  double forces = 0;     // contact forces and their sums per ball
  double motion = 0;     // law of motion
  double step = 0;       // the whole step
  double output = 0;     // histories and dumps between steps
  void add(const PhaseTimes& o) {
    detect += o.detect; forces += o.forces; motion += o.motion; step += o.step; output += o.output;
  }
};

}  // namespace trubal
