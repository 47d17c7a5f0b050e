#include "physics/scene.hpp"

#include "physics/bridge.hpp"

#include <cmath>
#include <algorithm>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "model/periodic_cell.hpp"

namespace trubal {

// The types of the balls and of the walls (a wall's material mixes with the balls').
static std::set<int> used_types(const Model& model) {
  std::set<int> types(model.balls.type.begin(), model.balls.type.end());
  for (const Wall& w : model.walls) types.insert(w.type);
  return types;
}

std::string Features::describe() const {
  std::string s = hertz ? "hertz-mindlin" : "linear";
  if (friction) s += " shear";
  if (rotation) s += " rotation";
  if (stiffness_damping) s += " dashpots";
  if (mass_damping == DampKind::Rayleigh) s += " mass-damping";
  if (mass_damping == DampKind::Local) s += " local-damping";
  if (gravity) s += " gravity";
  if (applied) s += " applied-loads";
  if (periodic) s += " periodic";
  if (bridges) s += " capillary-bridges";
  if (bonds) s += " parallel-bonds";
  return s;
}

Features scene_features(const Model& model, std::optional<BallFlags> flags) {
  Features f;
  const Balls& b = model.balls;
  const Damping& damping = model.settings.damping;
  bool restitution = false, rolling = false;
  f.friction = f.hertz = false;
  for (int type : used_types(model)) {
    const auto it = model.materials.find(type);
    if (it == model.materials.end()) continue;
    const Material& m = it->second;
    f.hertz = f.hertz || m.hertz();
    f.friction = f.friction || m.ks > 0 || m.hertz();
    restitution = restitution || m.has_restitution;
    rolling = rolling || m.rolling_friction > 0;
  }
  f.stiffness_damping = restitution || (damping.kind == DampKind::Rayleigh && damping.beta > 0);
  if (damping.kind == DampKind::Rayleigh && damping.alpha > 0) f.mass_damping = DampKind::Rayleigh;
  else if (damping.kind == DampKind::Local && damping.local > 0) f.mass_damping = DampKind::Local;
  const auto& g = model.settings.gravity;
  f.gravity = g[0] != 0 || g[1] != 0 || g[2] != 0;
  bool free_spin = false, spinning = false, moments = false;
  f.applied = false;
  for (std::size_t i = 0; i < b.size(); ++i) {
    free_spin = free_spin || (b.fixed[i] & kSpin) != kSpin;
    if (flags) continue;
    spinning = spinning || b.wx[i] != 0 || b.wy[i] != 0 || b.wz[i] != 0;
    moments = moments || b.amx[i] != 0 || b.amy[i] != 0 || b.amz[i] != 0;
    f.applied = f.applied || moments || b.ax[i] != 0 || b.ay[i] != 0 || b.az[i] != 0;
  }
  if (flags) {
    spinning = flags->spinning;
    moments = flags->moments;
    f.applied = flags->applied || flags->moments;
  }
  // A bond carries moments: its balls turn whatever the contacts' shear.
  f.bonds = std::any_of(model.bonds.fate.begin(), model.bonds.fate.end(), [](std::uint8_t v) { return v == 0; });
  f.rotation = ((f.friction || f.bonds) && free_spin) || spinning || moments;
  f.rolling = rolling && f.friction && f.rotation;
  f.periodic = model.space.periodic;
  f.bridges = bridge_reach(model) > 0;
  return f;
}

HistoryLaws laws_with_history(const Model& model) { return HistoryLaws{has_rolling(model), has_bridges(model)}; }

bool has_rolling(const Model& model) {
  for (const auto& [type, m] : model.materials)
    if (m.rolling_friction > 0) return true;
  return false;
}

void check_ready(const Model& model) {
  check_periodic_cell(model);
  bool hertz = false, linear = false;
  for (int type : used_types(model)) {
    const auto it = model.materials.find(type);
    if (it == model.materials.end())
      throw std::runtime_error(fmt::format("type {0} has no properties (PROP type {0} kn ... ks ... dens ...)", type));
    const Material& m = it->second;
    const bool wall_only = std::find(model.balls.type.begin(), model.balls.type.end(), type) == model.balls.type.end();
    if (!(m.density > 0) && !wall_only)
      throw std::runtime_error(fmt::format("type {0} has no density (PROP type {0} dens ...)", type));
    if (m.hertz()) {
      if (!(m.poisson >= 0 && m.poisson < 0.5))
        throw std::runtime_error(fmt::format("type {0} needs a Poisson ratio in [0, 0.5) (PROP type {0} poisson ...)", type));
      hertz = true;
    } else if (!(m.kn > 0)) {
      throw std::runtime_error(fmt::format(
          "type {0} has no stiffness (PROP type {0} kn ... ks ..., or shear ... poisson ...)", type));
    } else {
      linear = true;
    }
    if (m.has_restitution && !(m.restitution > 0 && m.restitution <= 1))
      throw std::runtime_error(fmt::format("type {0}: restitution must be in (0, 1] (PROP type {0} rest ...)", type));
  }
  if (hertz && linear)
    throw std::runtime_error("the balls mix Hertz-Mindlin and linear types; give every type the same law");
}

BallMass ball_mass(const Model& model, int type, double r) {
  const auto it = model.materials.find(type);
  const double density = it == model.materials.end() ? 0 : it->second.density;
  BallMass m;
  m.mass = density * 4.0 / 3.0 * M_PI * r * r * r;
  m.inertia = 0.4 * m.mass * r * r;
  return m;
}

void update_mass(Model& model) {
  Balls& b = model.balls;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const BallMass m = ball_mass(model, b.type[i], b.rad[i]);
    b.mass[i] = m.mass;
    b.inertia[i] = m.inertia;
  }
}

std::string ball_mass_problem(std::int64_t id, double mass, double inertia, double rad) {
  if (mass > 0 && std::isfinite(1 / mass) && inertia > 0) return "";
  return fmt::format("ball {} has mass {:.3g} (radius {:.3g}): too small for a step to move it; give it a larger "
                     "radius or density", id, mass, rad);
}

}  // namespace trubal
