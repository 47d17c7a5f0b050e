// What must hold of a model read from a file (io/model_checks.hpp).
#include "io/model_checks.hpp"

#include "model/bond_table.hpp"

#include <cmath>
#include <string>

#include <fmt/format.h>

#include "model/wall_shape.hpp"
#include "physics/sample.hpp"
#include "physics/walls.hpp"

namespace trubal {
namespace {

// A bool inside a struct read whole: its byte must be 0 or 1 (read as bytes, which is allowed).
bool valid_bool(const bool& b) { return *reinterpret_cast<const unsigned char*>(&b) <= 1; }

}  // namespace

std::string ball_problem(const Balls& b, std::size_t k, std::size_t at) {
  auto finite = [](double v) { return std::isfinite(v); };
  if (!(b.id[k] > 0)) return fmt::format("ball ids are not positive (ball {} at position {})", b.id[k], at);
  if (!(b.rad[k] > 0) || !finite(b.rad[k])) return fmt::format("ball {} has radius {}", b.id[k], b.rad[k]);
  for (double v : {b.x[k], b.y[k], b.z[k], b.vx[k], b.vy[k], b.vz[k], b.wx[k], b.wy[k], b.wz[k]})
    if (!finite(v)) return fmt::format("ball {} has a position or velocity that is not a number", b.id[k]);
  if (b.fixed[k] > kVel + kSpin) return fmt::format("ball {} has fixities {}", b.id[k], int(b.fixed[k]));
  return "";
}

std::string pair_problem(const ContactTable& c, std::size_t p, std::size_t at) {
  if (!(c.i[p] < c.j[p])) return fmt::format("contact {} is not i < j", at);
  if (p > 0 && (c.i[p] < c.i[p - 1] || (c.i[p] == c.i[p - 1] && c.j[p] < c.j[p - 1])))
    return fmt::format("the contacts are not sorted (at {})", at);
  if (c.state[p] > 2) return fmt::format("contact {} has state {}", at, int(c.state[p]));
  return "";
}

std::string wall_contact_problem(const WallContacts& wc, std::size_t p, std::size_t at, const Model& m) {
  const Balls& b = m.balls;
  if (wc.ball[p] >= b.size() || wc.wall[p] >= m.walls.size() || b.id[wc.ball[p]] != wc.ball_id[p] ||
      m.walls[wc.wall[p]].id != wc.wall_id[p] || wc.state[p] > 2)
    return fmt::format("wall contact {} does not match the balls and walls", at);
  return "";
}

std::string ids_problem(const Balls& b) {
  if (b.ids_indexed()) return "";
  for (std::size_t r = 1; r < b.by_id.size() && b.by_id.size() == b.size(); ++r)
    if (b.by_id[r] < b.size() && b.by_id[r - 1] < b.size() && b.id[b.by_id[r]] == b.id[b.by_id[r - 1]])
      return fmt::format("ball id {} is given to two balls (at positions {} and {})", b.id[b.by_id[r]], b.by_id[r - 1],
                         b.by_id[r]);
  return "the index of the ball ids is not made";
}

std::string light_problem(const Model& m) {
  auto finite = [](double v) { return std::isfinite(v); };
  const Space& s = m.space;
  for (int a = 0; a < 3; ++a) {
    if (m.started && !(s.hi[a] > s.lo[a] && finite(s.lo[a]) && finite(s.hi[a])))
      return fmt::format("the space's {} bounds are [{}, {}]", "xyz"[a], s.lo[a], s.hi[a]);
    if (static_cast<unsigned>(s.outside[a]) > 1) return "a box condition is neither stop nor destroy";
  }
  for (double v : s.tilt) if (!finite(v)) return "the cell's tilts are not numbers";
  for (double v : s.strain_rate) if (!finite(v)) return "the strain rates are not numbers";
  for (const auto& [type, mat] : m.materials)
    if (!valid_bool(mat.has_restitution) || !finite(mat.kn) || !finite(mat.ks) || !finite(mat.density) ||
        !(mat.rolling_friction >= 0) || !finite(mat.rolling_friction) || !(mat.bridge_volume >= 0) ||
        !finite(mat.bridge_volume) || !(mat.surface_tension >= 0) || !finite(mat.surface_tension) ||
        !(mat.contact_angle >= 0) || !(mat.contact_angle < std::numbers::pi / 2))
      return fmt::format("type {} has properties that are not numbers", type);
  const Settings& st = m.settings;
  if (!(st.frac > 0) || !finite(st.frac)) return fmt::format("FRAC is {}", st.frac);
  if (!(st.fixed_dt >= 0) || !finite(st.fixed_dt)) return fmt::format("TSTEP is {}", st.fixed_dt);
  if (static_cast<unsigned>(st.damping.kind) > 2) return "the damping kind is unknown";
  if (!(m.cycle >= 0) || !(m.dt >= 0) || !finite(m.dt) || !finite(m.time) || !(m.critical_dt >= 0))
    return "the cycle count, time or step are not valid";
  const Membrane& mb = m.membrane;
  const std::size_t loaded = mb.ids.size();
  if (mb.face_x.size() != loaded || mb.face_y.size() != loaded || mb.layer.size() != loaded ||
      mb.extent_x.size() != mb.extent_y.size() || mb.extent_x.size() != mb.layer_cells.size())
    return "the membrane's records do not match";
  for (std::int32_t L : mb.layer)
    if (L < 0 || static_cast<std::size_t>(L) >= mb.extent_x.size()) return "the membrane's layers do not match";
  if (mb.follow_every < 0) return "the membrane's follow period is negative";
  for (std::size_t k = 0; k < m.walls.size(); ++k) {
    Wall w = m.walls[k];
    if (k > 0 && !(w.id > m.walls[k - 1].id)) return "the wall ids are not ascending";
    if (static_cast<unsigned>(w.kind) > 2) return fmt::format("wall {} has an unknown kind", w.id);
    const std::string problem = complete_wall(w);
    if (!problem.empty()) return fmt::format("wall {}: {}", w.id, problem);
    for (double v : {w.velocity[0], w.velocity[1], w.velocity[2], w.spin[0], w.spin[1], w.spin[2], w.radius_rate,
                     w.servo_target, w.servo_integral, w.work})
      if (!finite(v)) return fmt::format("wall {} has a motion or load that is not a number", w.id);
  }
  for (const Wall& w : m.walls)
    for (std::int64_t id : w.area_walls)
      if (id != 0 && !find_wall(m, id)) return fmt::format("wall {}'s servo area names no wall", w.id);
  if (m.sample.declared()) {
    const std::string problem = check_sample(m, m.sample);
    if (!problem.empty()) return "the sample: " + problem;
    if (!(m.sample.height0 > 0) || !(m.sample.area0 > 0) || !finite(m.sample.height0) || !finite(m.sample.area0))
      return "the sample's reference is not a size";
  } else if (m.sample.platens[1] != 0 || m.sample.sides != std::array<std::int64_t, 4>{}) {
    return "the sample's walls do not match";
  }
  return "";
}

// What must hold of a model for it to run: what a checksum cannot vouch for (a file written by
// hand or by another program). "" when it holds, else what does not.
std::string invalid_model(const Model& m) {
  const Balls& b = m.balls;
  if (std::string p = ids_problem(b); !p.empty()) return p;
  for (std::size_t k = 0; k < b.size(); ++k)
    if (std::string p = ball_problem(b, k, k); !p.empty()) return p;
  const ContactTable& c = m.contacts;
  for (std::size_t p = 0; p < c.size(); ++p)
    if (std::string q = pair_problem(c, p, p); !q.empty()) return q;
  if (std::string p = light_problem(m); !p.empty()) return p;
  const WallContacts& wc = m.wall_contacts;
  bool sizes = true;
  const_cast<WallContacts&>(wc).for_each_array([&](auto& v) { sizes = sizes && v.size() == wc.size(); });
  if (!sizes) return "the wall contacts' records do not match";
  for (std::size_t p = 0; p < wc.size(); ++p)
    if (std::string q = wall_contact_problem(wc, p, p, m); !q.empty()) return q;
  if (const std::string bonds = bond_table_problem(m); !bonds.empty()) return bonds;
  return "";
}

}  // namespace trubal
