// What a scene models, read off the model once per CYCLE: the features that choose the kernels,
// the readiness checks, the masses.
#pragma once

#include <optional>

#include <string>

#include "model/model.hpp"

namespace trubal {

// What a scene uses; each flag off removes work from the kernels (chosen once per CYCLE).
struct Features {
  bool rotation = true;     // some ball has a free spin component and shear forces exist
  bool friction = true;     // some material has ks > 0 (shear forces at all)
  bool hertz = false;
  bool rolling = false;     // some material has rolling resistance (rr_fric), with shear and spins
  bool bridges = false;     // some pair of types has capillary bridges (PROP bridge): cycle/bridge_pass.hpp
  bool bonds = false;       // some parallel bond holds (BOND): cycle/bond_pass.hpp
  bool stiffness_damping = false;   // Rayleigh beta or restitution dashpots
  DampKind mass_damping = DampKind::None;
  bool gravity = false;
  bool applied = false;
  bool periodic = false;
  std::string describe() const;     // for PRINT info
};

// What scene_features reads of each ball's motion and loads: whether some ball spins, carries an
// applied force or moment, carries an applied moment.
struct BallFlags {
  bool spinning = false, applied = false, moments = false;
};
// flags: where the caller knows them and the model does not hold the balls' angular velocities and
// applied loads (a distributed run's rank 0 whose kept parts alone hold them).
Features scene_features(const Model& model, std::optional<BallFlags> flags = std::nullopt);
// Whether some material has rolling resistance (PROP rr_fric): output then shows the rolling moments.
bool has_rolling(const Model& model);
// The laws with history of their own that the model's materials have (rolling resistance,
// capillary bridges): the parts a contact table keeps (ContactTable::history_laws).
HistoryLaws laws_with_history(const Model& model);

// Checks that every ball's type has density and stiffness; throws std::runtime_error naming the type.
void check_ready(const Model& model);
// Derives mass and moment of inertia from the type densities.
void update_mass(Model& model);
// A ball's mass and moment of inertia from its type's density (update_mass's, for one ball).
struct BallMass {
  double mass = 0, inertia = 0;
};
BallMass ball_mass(const Model& model, int type, double rad);
// What is wrong with a ball's mass for a step ("" where nothing is): CYCLE's check.
std::string ball_mass_problem(std::int64_t id, double mass, double inertia, double rad);
}  // namespace trubal
