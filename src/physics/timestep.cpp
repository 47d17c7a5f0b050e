#include "physics/timestep.hpp"

#include <initializer_list>
#include <limits>

#include "model/bond_table.hpp"
#include "model/edit.hpp"
#include "model/periodic_cell.hpp"
#include "physics/bond.hpp"
#include "physics/contact_law.hpp"
#include "physics/pair_laws.hpp"
#include "physics/scene.hpp"
#include "physics/walls.hpp"

namespace trubal {
namespace {

// The held critical step (see next_critical_step): shrunk only when the step would
// exceed this fraction of the critical estimate (or FRAC itself, when FRAC is larger), and grown
// within a contact episode only when the estimate has risen this many times above it (a linear
// scene: at most, see held_growth).
constexpr double kHeldStability = 0.9;
constexpr double kHeldGrowth = 2.0;

}  // namespace

// pi R sqrt(rho/G) / (0.1631 nu + 0.8766) for the smallest Hertz ball.
double hertz_step_cap(const Model& model) {
  double cap = std::numeric_limits<double>::infinity();
  const Balls& b = model.balls;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const auto it = model.materials.find(b.type[i]);
    if (it == model.materials.end() || !it->second.hertz()) continue;
    const Material& m = it->second;
    cap = std::min(cap, M_PI * b.rad[i] * std::sqrt(m.density / m.shear_modulus) / (0.1631 * m.poisson + 0.8766));
  }
  return cap;
}

double held_growth(double frac, bool hertz) {
  return hertz ? kHeldGrowth : std::min(kHeldGrowth, std::max(kHeldStability, frac) / frac);
}

double next_critical_step(double held, double estimate, double frac, double free_step, bool hertz) {
  if (!(held > 0)) return estimate;
  // Between contact episodes (no ball stiffer than a lone ball, or than a lone Hertz ball's cap) the
  // step is free.
  if (!(estimate < free_step)) return estimate;
  // Stability: the step frac * held must stay below kHeldStability (or frac) times the estimate.
  if (frac * held > std::max(kHeldStability, frac) * estimate) return estimate;
  // A softer state (contacts unloaded, a sample dilating): take the longer step, a bounded number
  // of jumps.
  if (estimate > held_growth(frac, hertz) * held) return estimate;
  return held;
}

bool any_ball_free(const Model& model, bool rotation, const std::uint8_t* skip) {
  const Balls& b = model.balls;
  for (std::size_t i = 0; i < b.size(); ++i)
    if (!(skip && skip[i]) && !ball_held(b.fixed[i], rotation)) return true;
  return false;
}

double critical_timestep(const Model& model) {
  const Features features = scene_features(model);
  const bool any_free = any_ball_free(model, features.rotation, nullptr);
  return std::min(balls_critical_step(model, features, any_free, nullptr), hertz_step_cap(model));
}

double balls_critical_step(const Model& model, const Features& features, bool any_free, const std::uint8_t* skip) {
  const PairLaws laws = make_pair_laws(model);
  const Damping& damping = model.settings.damping;
  const double beta = damping.kind == DampKind::Rayleigh ? damping.beta : 0;
  const Balls& b = model.balls;
  const ContactTable& c = model.contacts;
  const std::size_t n = b.size();
  // Per-ball sums over the touching pairs, added in list order: ascending partner, as the gather.
  struct Sums { double kmax = 0, ks = 0, cn = 0; };
  std::vector<Sums> sums(n);
  // A contact's stiffness and dashpot, added to the sums of its balls where it touches.
  auto add = [&](const PairLaw& law, const ContactInput& in, std::initializer_list<std::size_t> balls) {
    const ContactResult r = features.hertz ? contact_force<ContactFeatures{.hertz = true, .dashpot = true}>(law, in, 0, 0)
                                           : contact_force<ContactFeatures{.dashpot = true}>(law, in, 0, 0);
    if (r.state == 0) return;
    for (std::size_t ball : balls) {
      sums[ball].kmax += std::max(r.kn, r.ks);
      sums[ball].ks += r.ks;
      // (the kernels' order: the rolling spring's share after the shear spring's)
      if (features.rolling) {
        const double share = balls.size() == 1 ? 1.0 : (ball == *balls.begin() ? in.rj : in.ri) / (in.ri + in.rj);
        sums[ball].ks += rolling_ks(r.ks, share);
      }
      sums[ball].cn += r.cn;
    }
  };
  for (std::size_t p = 0; p < c.size(); ++p) {
    const std::size_t i = c.i[p], j = c.j[p];
    if (i >= n || j >= n) continue;   // a stale list: count what is still valid
    const PairLaw& law = laws.law(i, j);
    ContactInput in{};
    in.dx = b.x[j] - b.x[i]; in.dy = b.y[j] - b.y[i]; in.dz = b.z[j] - b.z[i];
    if (model.space.periodic && p < c.image_x.size()) {
      double ox, oy, oz;
      image_offset(cell_frame(model.space), c.image_x[p], c.image_y[p], c.image_z[p], ox, oy, oz);
      in.dx = image_delta(b.x[j], b.x[i], ox);
      in.dy = image_delta(b.y[j], b.y[i], oy);
      in.dz = image_delta(b.z[j], b.z[i], oz);
    }
    in.ri = b.rad[i]; in.rj = b.rad[j];
    if (law.rest_xi > 0) in.mstar = pair_mstar(b.mass[i], b.mass[j], velocity_held(b.fixed[i]), velocity_held(b.fixed[j]));
    add(law, in, {i, j});
  }
  // Wall contacts, after the ball's pairs (the kernels' order).
  const WallContacts& wc = model.wall_contacts;
  for (std::size_t p = 0; p < wc.size(); ++p) {
    const std::size_t i = wc.ball[p], w = wc.wall[p];
    if (i >= n || w >= model.walls.size()) continue;
    const WallLane lane = wall_lane(model.walls[w], {b.x[i], b.y[i], b.z[i]}, b.rad[i]);
    ContactInput in{};
    in.dx = lane.dx; in.dy = lane.dy; in.dz = lane.dz;
    in.ri = in.rj = lane.r;
    in.mstar = b.mass[i];
    add(laws.wall_law(i, w), in, {i});
  }
  // The intact bonds, after the wall contacts, by their balls' ids (the step's order of the sums:
  // cycle/bond_pass.hpp).
  const Bonds& bonds = model.bonds;
  for (std::size_t q : bond_rows_by_id(bonds)) {
    if (bonds.fate[q] != 0) continue;
    const std::int64_t i = find_ball(model, bonds.id_i[q]), j = find_ball(model, bonds.id_j[q]);
    if (i < 0 || j < 0) continue;
    const BondStiffness k = bond_stiffness(bond_law(bonds, q), b.rad[i], b.rad[j]);
    for (const std::int64_t ball : {i, j}) {
      sums[static_cast<std::size_t>(ball)].kmax += k.kmax;
      sums[static_cast<std::size_t>(ball)].ks += k.ks;
    }
  }
  const bool rotation = features.rotation;
  // Held balls set no step of their own; where every ball is held (the balls may still move at their
  // fixed velocities), the step is that of the balls as if free.
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    if ((skip && skip[i]) || (any_free && ball_held(b.fixed[i], rotation))) continue;
    double sum_kmax = sums[i].kmax, sum_ks = sums[i].ks, sum_cn = sums[i].cn;
    if (sum_kmax == 0) alone_sums(laws, i, b.mass[i], sum_kmax, sum_ks, &sum_cn);
    const double omega2 = ball_omega2(b.mass[i], sum_kmax, sum_ks, rotation);
    if (!(omega2 > 0)) continue;
    const double omega = std::sqrt(omega2);
    step = std::min(step, damped_critical_step(omega, 0.5 * beta * omega + sum_cn / (b.mass[i] * omega)));
  }
  return step;
}

double contact_free_step(const Model& model, const Features& features, double cap) {
  return contact_free_step(model, features, cap, any_ball_free(model, features.rotation, nullptr), nullptr);
}

double contact_free_step(const Model& model, const Features& features, double cap, bool any_free,
                         const std::uint8_t* skip) {
  const PairLaws laws = make_pair_laws(model);
  const Damping& damping = model.settings.damping;
  const double beta = damping.kind == DampKind::Rayleigh ? damping.beta : 0;
  const Balls& b = model.balls;
  const bool rotation = features.rotation;
  // The per-ball step of balls_critical_step for a ball without contacts, the same arithmetic: a
  // state with no ball stiffer than a lone one estimates this step to the bit.
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < b.size(); ++i) {
    if ((skip && skip[i]) || (any_free && ball_held(b.fixed[i], rotation))) continue;
    double sum_kmax = 0, sum_ks = 0, sum_cn = 0;
    alone_sums(laws, i, b.mass[i], sum_kmax, sum_ks, &sum_cn);
    const double omega2 = ball_omega2(b.mass[i], sum_kmax, sum_ks, rotation);
    if (!(omega2 > 0)) continue;
    const double omega = std::sqrt(omega2);
    step = std::min(step, damped_critical_step(omega, 0.5 * beta * omega + sum_cn / (b.mass[i] * omega)));
  }
  return std::min(step, cap);
}

}  // namespace trubal
