#include "physics/pair_laws.hpp"

#include <algorithm>
#include <cmath>

namespace trubal {
namespace {

double series(double a, double b) { return a + b > 0 ? a * b / (a + b) : 0; }

// Restitution of a linear spring-dashpot whose dashpot may not pull (Schwager & Poeschel,
// Granular Matter 9:465, 2007): the contact ends when the force reaches zero, at phase
// theta = atan2(2 xi s, 2 xi^2 - 1), s = sqrt(1 - xi^2); e = exp(-xi theta / s), continued
// analytically past critical damping.
double clamped_restitution(double xi) {
  if (xi < 1) {
    const double s = std::sqrt(1 - xi * xi);
    return std::exp(-xi * std::atan2(2 * xi * s, 2 * xi * xi - 1) / s);
  }
  if (xi == 1) return std::exp(-2.0);
  const double q = std::sqrt(xi * xi - 1);
  return std::exp(-xi / q * std::atanh(2 * xi * q / (2 * xi * xi - 1)));
}

}  // namespace

double restitution_xi(double e, bool hertz) {
  if (!(e < 1)) return 0;
  const double log_e = std::log(e);
  if (hertz) return -log_e / std::sqrt(M_PI * M_PI + log_e * log_e);
  double lo = 0, hi = 1e3;   // clamped_restitution falls monotonically from 1
  for (int k = 0; k < 200 && hi - lo > 1e-15 * hi; ++k) {
    const double mid = 0.5 * (lo + hi);
    (clamped_restitution(mid) > e ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

// Mixes two materials (doc/physics.md "Mixed materials"); equal materials give their own values.
PairLaw mix(const Material& a, const Material& b) {
  PairLaw law;
  law.kn = 2 * series(a.kn, b.kn);
  law.ks = 2 * series(a.ks, b.ks);
  law.friction = std::min(a.friction, b.friction);
  law.cohesion = std::min(a.cohesion, b.cohesion);
  law.rolling = std::min(a.rolling_friction, b.rolling_friction);
  if (a.hertz() && b.hertz()) {
    // 1/E* = (1 - nu_a)/(2 G_a) + (1 - nu_b)/(2 G_b);  1/G* = (2 - nu_a)/G_a + (2 - nu_b)/G_b.
    law.hertz_n = 4.0 / 3.0 * series(2 * a.shear_modulus / (1 - a.poisson), 2 * b.shear_modulus / (1 - b.poisson));
    law.hertz_s = 8 * series(a.shear_modulus / (2 - a.poisson), b.shear_modulus / (2 - b.poisson));
  }
  if (a.has_restitution || b.has_restitution) {
    const double e = std::min(a.has_restitution ? a.restitution : 1.0, b.has_restitution ? b.restitution : 1.0);
    law.rest_xi = restitution_xi(e, law.hertz_n > 0);
  }
  return law;
}

}  // namespace

PairLaws make_pair_laws(const Model& model) {
  PairLaws k;
  // Compact type indices, in type-number order.
  std::vector<int> types;
  for (const auto& [type, material] : model.materials) types.push_back(type);
  k.type_count = static_cast<int>(types.size());
  k.ball_type.resize(model.balls.size());
  for (std::size_t b = 0; b < model.balls.size(); ++b)
    k.ball_type[b] = static_cast<std::uint16_t>(std::lower_bound(types.begin(), types.end(), model.balls.type[b]) - types.begin());
  k.wall_type.resize(model.walls.size());
  for (std::size_t w = 0; w < model.walls.size(); ++w)
    k.wall_type[w] = static_cast<std::uint16_t>(std::lower_bound(types.begin(), types.end(), model.walls[w].type) - types.begin());
  for (int ta : types)
    for (int tb : types) k.table.push_back(mix(model.materials.at(ta), model.materials.at(tb)));
  for (int ta : types)
    for (int tb : types) k.bridges.push_back(mix_bridge(model.materials.at(ta), model.materials.at(tb)));
  if (std::none_of(k.bridges.begin(), k.bridges.end(), [](const BridgeLaw& b) { return b.on(); })) k.bridges.clear();
  for (int t : types) {
    const Material& m = model.materials.at(t);
    k.alone_kn.push_back(m.hertz() ? 0 : m.kn);
    k.alone_ks.push_back(m.hertz() ? 0 : m.ks);
    k.alone_xi.push_back(k.table[k.alone_xi.size() * (types.size() + 1)].rest_xi);
  }
  if (k.type_count == 1) {
    k.ball_pair_law = 0;
  } else if (!k.ball_type.empty() &&
             std::all_of(k.ball_type.begin(), k.ball_type.end(), [&](std::uint16_t t) { return t == k.ball_type[0]; })) {
    k.ball_pair_law = k.ball_type[0] * (k.type_count + 1);
  }
  return k;
}

}  // namespace trubal
