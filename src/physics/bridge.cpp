#include "physics/bridge.hpp"

#include <algorithm>

namespace trubal {

BridgeLaw mix_bridge(const Material& a, const Material& b) {
  BridgeLaw law;
  if (!(a.bridge_volume > 0 && b.bridge_volume > 0)) return law;
  law.volume = 0.5 * (a.bridge_volume + b.bridge_volume);
  const double tension = 0.5 * (a.surface_tension + b.surface_tension);
  const double angle = 0.5 * (a.contact_angle + b.contact_angle);
  law.pull = 2 * std::numbers::pi * tension * std::cos(angle);
  law.rupture = (1 + 0.5 * angle) * std::cbrt(law.volume);
  return law;
}

double bridge_reach(const Model& model) {
  double reach = 0;
  for (const auto& [ta, a] : model.materials)
    for (const auto& [tb, b] : model.materials) {
      const BridgeLaw law = mix_bridge(a, b);
      if (law.on()) reach = std::max(reach, law.rupture);
    }
  return reach;
}

bool has_bridges(const Model& model) {
  return std::any_of(model.materials.begin(), model.materials.end(),
                     [](const auto& m) { return m.second.bridge_volume > 0; });
}

namespace {
BridgeLaw types_bridge(const Model& model, int ta, int tb) {
  const auto a = model.materials.find(ta), b = model.materials.find(tb);
  if (a == model.materials.end() || b == model.materials.end()) return {};
  return mix_bridge(a->second, b->second);
}
}  // namespace

BridgeLaw pair_bridge(const Model& model, std::size_t i, std::size_t j) {
  return types_bridge(model, model.balls.type[i], model.balls.type[j]);
}

BridgeLaw wall_bridge(const Model& model, std::size_t ball, std::size_t wall) {
  return types_bridge(model, model.balls.type[ball], model.walls[wall].type);
}

std::size_t count_bridges(const ContactTable& c) {
  return static_cast<std::size_t>(std::count_if(c.bridge.begin(), c.bridge.end(), [](double v) { return v != 0; }));
}

std::size_t count_bridges(const WallContacts& w) {
  return static_cast<std::size_t>(std::count_if(w.bridge.begin(), w.bridge.end(), [](double v) { return v != 0; }));
}

}  // namespace trubal
