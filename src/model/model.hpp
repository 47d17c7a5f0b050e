// The state of a simulation as plain data: balls, materials, contacts with their history, space and
// settings. No per-step scratch and no timings (the cycle keeps those); src/physics/ and src/cycle/
// act on it.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include "model/bonds.hpp"

namespace trubal {

// Velocity components that FIX/FREE address, as bits of Balls::fixed.
enum Dof : std::uint8_t {
  kXVel = 1, kYVel = 2, kZVel = 4, kXSpin = 8, kYSpin = 16, kZSpin = 32,
  kVel = kXVel | kYVel | kZVel, kSpin = kXSpin | kYSpin | kZSpin,
};

// Contact properties of one ball type (PROP). Unset values are 0.
struct Material {
  double kn = 0, ks = 0;          // linear springs, force per length
  double friction = 0;            // Coulomb coefficient mu (PROP fric gives an angle)
  double cohesion = 0;            // force added to the Coulomb limit
  double density = 0;
  double shear_modulus = 0;       // > 0 selects Hertz-Mindlin (with poisson)
  double poisson = 0;
  double restitution = 0;         // used when has_restitution (contact dashpot)
  double rolling_friction = 0;    // rolling resistance coefficient mu_r (PROP rr_fric; 0: none)
  // Capillary bridges (PROP bridge V tension gamma angle deg; physics/bridge.hpp): the liquid volume
  // of one bridge (0: dry), the liquid's surface tension and its contact angle in radians.
  double bridge_volume = 0, surface_tension = 0, contact_angle = 0;
  bool has_restitution = false;
  std::uint8_t unused[7] = {};    // the padding SAVE writes with the struct, made explicit so its bytes are 0
  bool hertz() const { return shear_modulus > 0; }
};

// Balls as structure of arrays, stored in the model's canonical order: the order each ball's
// contact forces are summed in (partners by index) and the order SAVE writes. The order is a
// function of the model's state alone: balls are added at the end, and the run puts them in space
// order at cycles fixed by the model's own counter (Model::order, cycle/run.cpp). Ids are the
// user's names for the balls and never change with the order; `by_id` finds a ball by id.
// The bytes a vector holds (its capacity): the memory figures PRINT info reports.
template <class V> std::size_t capacity_bytes(const V& v) { return v.capacity() * sizeof(typename V::value_type); }

struct Balls {
  std::vector<std::int64_t> id;
  std::vector<int> type;
  std::vector<std::uint8_t> fixed;              // Dof bits
  std::vector<double> rad, mass, inertia;       // mass/inertia derived from type density
  std::vector<double> x, y, z;                  // position at t
  std::vector<double> vx, vy, vz;               // velocity at t - dt/2
  std::vector<double> wx, wy, wz;               // angular velocity at t - dt/2
  std::vector<double> fx, fy, fz;               // unbalanced force of the last step
  std::vector<double> mx, my, mz;               // unbalanced moment of the last step
  std::vector<double> ax, ay, az;               // applied force (APPLY, MEMBRANE)
  std::vector<double> amx, amy, amz;            // applied moment
  // The balls' indices by ascending id: not a per-ball array of the state (SAVE does not write it).
  // Kept by what adds, removes and reorders balls (model/edit.hpp); index_ids() makes it afresh.
  std::vector<std::uint32_t> by_id;

  std::size_t size() const { return id.size(); }
  // Makes by_id afresh from the ids.
  void index_ids();
  // Whether by_id lists every index once, by strictly ascending id (the ids unique).
  bool ids_indexed() const;
  double max_radius() const {
    double r = 0;
    for (double v : rad) r = v > r ? v : r;
    return r;
  }

  // Calls f(vector&) for every per-ball array, so resizing and reordering cannot miss one.
  template <class F> void for_each_array(F&& f) {
    f(id); f(type); f(fixed);
    for (auto* v : {&rad, &mass, &inertia, &x, &y, &z, &vx, &vy, &vz, &wx, &wy, &wz, &fx, &fy, &fz,
                    &mx, &my, &mz, &ax, &ay, &az, &amx, &amy, &amz})
      f(*v);
  }
  template <class F> void for_each_array(F&& f) const {
    const_cast<Balls*>(this)->for_each_array([&](auto& v) { f(static_cast<const decltype(v)&>(v)); });
  }
};

// What a contact keeps from one step to the next, its history, is declared once: each part of a
// contact law that keeps state lists its arrays in ContactTable::for_each_history (and, where a
// ball meets a wall, WallContacts::for_each_history), with what a value does when i and j trade
// places. Every place that moves contact state goes through those lists: the pair list's
// carry-over (cycle/pair_list.cpp, cycle/wall_list.cpp), the rescue snapshot (cycle/snapshot.hpp),
// SAVE and RESTART, RENUMBER (model/edit.cpp), and the step shared among threads and ranks
// (cycle/parallel_step.cpp; what migrates with a ball: Travels, cycle/brick_step_parts.hpp).
// A contact table keeps the parts of the laws its scene has (ContactTable::history_laws): the
// lists visit only those, and a part not kept is zero for every pair.
enum class OnSwap : std::uint8_t {
  Keep,     // a value of the pair as a whole (a count, a flag, a length)
  Negate,   // a vector on j from i (the shear force on j): on i it is minus this
};
struct HistoryPart {
  const char* name;   // as SAVE names it (a save is read by these names, so a new part reads old saves)
  OnSwap swap;
};

// The contact laws that keep history of their own beside the shear spring (a contact table keeps
// their arrays only where such a law is in the scene: ContactTable::history_laws).
struct HistoryLaws {
  bool rolling = false;   // rolling resistance (PROP rr_fric): mrx mry mrz
  bool bridge = false;    // capillary bridges (PROP bridge): bridge
  bool operator==(const HistoryLaws&) const = default;
};

// Pairs of balls that may touch, i < j as ball indices, sorted by (i, j). Only pairs with positive
// overlap are contacts; the rest carry zero history. The history survives rebuilds because it is
// carried over by the pair of ball ids.
struct ContactTable {
  std::vector<std::uint32_t> i, j;
  std::vector<std::int8_t> image_x, image_y, image_z;   // periodic image of j as seen from i
  std::vector<double> fsx, fsy, fsz;                    // shear force on j (history)
  std::vector<double> mrx, mry, mrz;                    // rolling moment on j (history; on i: minus this)
  std::vector<double> bridge;                           // 1: a capillary bridge holds the pair (history)
  // Results of the last force computation, per pair:
  std::vector<double> nx, ny, nz;                       // unit normal from i to j
  std::vector<double> overlap, fn;                      // overlap U, normal force (spring + dashpot)
  std::vector<double> fx, fy, fz;                       // total force on j (on i: minus this)
  std::vector<double> tx, ty, tz;                       // n x (shear force): moment on b is -R_b t
  std::vector<double> kn_eff, ks_eff;                   // stiffness now, for the time step
  std::vector<double> cn_eff;                           // restitution dashpot coefficient now
  std::vector<double> work_friction, work_damping;      // energy dissipated this step
  std::vector<std::uint8_t> state;                      // 0 apart, 1 touching, 2 sliding
  // Which laws' history the table keeps beside the shear spring's (for_each_history): the arrays of
  // the others are empty (zero for every pair).
  HistoryLaws history_laws;
  // The cycle whose step's force pass the results above are of (cycle/run.hpp says which steps
  // write them); -1: none yet. The result arrays are either all of the list's length or all empty
  // (not kept: results_cycle is then -1); a CYCLE's last step may leave them empty, to be made again
  // when read (make_results, cycle/run.hpp).
  std::int64_t results_cycle = -1;
  // Unique to each pair list installed (cycle/pair_list.hpp): what the pipeline's index of the
  // list is checked against. Not saved; 0: a list nobody indexed.
  std::uint64_t list_version = 0;

  std::size_t size() const { return i.size(); }
  // Whether the result arrays are of the list's length (else they are empty: not kept).
  bool results_kept() const { return state.size() == i.size() && nx.size() == i.size(); }
  // Whether pair p touched in the results' force pass (false where the results are not kept: a
  // distributed run's ranks other than 0 may leave them unmade, cycle/run.hpp make_results_to_read).
  bool touching(std::size_t p) const { return p < state.size() && state[p] != 0; }
  // The result arrays of the list's length, zero where they were not kept.
  void keep_results() {
    if (results_kept()) return;
    for_each_result_array([&](auto& v) { v.assign(i.size(), {}); });
    results_cycle = -1;
  }
  // The place of `array` in for_each_result_array's order, where it is one of the result arrays;
  // else -1.
  int result_index(const void* array) const {
    int at = 0, found = -1;
    const_cast<ContactTable*>(this)->for_each_result_array([&](const auto& v) {
      if (&v == array) found = at;
      ++at;
    });
    return found;
  }
  // The bytes the result arrays hold (their capacity).
  std::size_t result_bytes() const {
    std::size_t bytes = 0;
    const_cast<ContactTable*>(this)->for_each_result_array(
        [&](const auto& v) { bytes += capacity_bytes(v); });
    return bytes;
  }
  // Frees the result arrays (their memory goes back).
  void drop_results() {
    for_each_result_array([](auto& v) { std::decay_t<decltype(v)>().swap(v); });
    results_cycle = -1;
  }
  // The history, each array with its name and what its value does when i and j trade places: the
  // parts in use (history_laws), in one fixed order.
  template <class F> void for_each_history(F&& f) {
    for_each_declared_history([&](auto& v, const HistoryPart& part, bool used) {
      if (used) f(v, part);
    });
  }
  // Every part a law declares, with whether the table keeps it (in use): the shear spring's always,
  // the rolling spring's and the capillary bridge's where history_laws says. A part not in use holds
  // zero for every pair and its array is empty.
  template <class F> void for_each_declared_history(F&& f) {
    f(fsx, HistoryPart{"fsx", OnSwap::Negate}, true);   // the shear spring
    f(fsy, HistoryPart{"fsy", OnSwap::Negate}, true);
    f(fsz, HistoryPart{"fsz", OnSwap::Negate}, true);
    f(mrx, HistoryPart{"mrx", OnSwap::Negate}, history_laws.rolling);   // the rolling spring
    f(mry, HistoryPart{"mry", OnSwap::Negate}, history_laws.rolling);
    f(mrz, HistoryPart{"mrz", OnSwap::Negate}, history_laws.rolling);
    f(bridge, HistoryPart{"bridge", OnSwap::Keep}, history_laws.bridge);   // the capillary bridge (cycle/bridge_pass.hpp)
  }
  template <class F> void for_each_declared_history(F&& f) const {
    const_cast<ContactTable*>(this)->for_each_declared_history(
        [&](auto& v, const HistoryPart& part, bool used) { f(static_cast<const decltype(v)&>(v), part, used); });
  }
  template <class F> void for_each_history(F&& f) const {
    const_cast<ContactTable*>(this)->for_each_history(
        [&](auto& v, const HistoryPart& part) { f(static_cast<const decltype(v)&>(v), part); });
  }
  // How many doubles of history a pair carries (the parts in use).
  std::size_t history_count() const {
    std::size_t n = 0;
    for_each_history([&](const auto&, const HistoryPart&) { ++n; });
    return n;
  }
  // Where each part's arrays start in for_each_history's order (the cross pairs' copy of the
  // history, cycle/parallel_step.cpp, holds them in that order); a part not in use has none.
  static constexpr std::size_t shear_history_at() { return 0; }
  static constexpr std::size_t rolling_history_at() { return 3; }
  std::size_t bridge_history_at() const { return history_laws.rolling ? 6 : 3; }
  // Takes the parts `laws` names into use beside those in use (zero for every pair: a law added
  // since the pairs were found has stored nothing yet). A part once in use stays so (a law taken
  // away and given back later finds its history as it left it), until drop_zero_history.
  void use_history(HistoryLaws laws) {
    HistoryLaws next = history_laws;
    next.rolling = next.rolling || laws.rolling;
    next.bridge = next.bridge || laws.bridge;
    set_history_laws(next);
  }
  // Makes exactly `laws`'s parts in use: those added zero for every pair, those dropped freed.
  void set_history_laws(HistoryLaws laws) {
    const HistoryLaws before = history_laws;
    history_laws = laws;
    const auto fit = [&](std::vector<double>& v, bool was, bool now) {
      if (now && !was) v.assign(i.size(), 0.0);
      if (!now) std::vector<double>().swap(v);
    };
    for (auto* v : {&mrx, &mry, &mrz}) fit(*v, before.rolling, laws.rolling);
    fit(bridge, before.bridge, laws.bridge);
  }
  // Leaves in use only the parts `keep` names and those holding a value other than zero (dropping
  // a part that is zero for every pair changes nothing a step reads).
  void drop_zero_history(HistoryLaws keep) {
    const auto zero = [](const std::vector<double>& v) {
      for (double x : v)
        if (x != 0 || std::signbit(x)) return false;
      return true;
    };
    HistoryLaws next = history_laws;
    next.rolling = next.rolling && (keep.rolling || !(zero(mrx) && zero(mry) && zero(mrz)));
    next.bridge = next.bridge && (keep.bridge || !zero(bridge));
    set_history_laws(next);
  }
  // The bytes the history arrays hold (their capacity).
  std::size_t history_bytes() const {
    std::size_t bytes = 0;
    for_each_declared_history([&](const auto& v, const HistoryPart&, bool) { bytes += v.capacity() * sizeof(double); });
    return bytes;
  }
  // Whether pair p carries any history.
  bool has_history(std::size_t p) const {
    bool any = false;
    for_each_history([&](const auto& v, const HistoryPart&) { any = any || (p < v.size() && v[p] != 0); });
    return any;
  }
  // The pair list's arrays (the pairs and their images).
  template <class F> void for_each_list_array(F&& f) { f(i); f(j); f(image_x); f(image_y); f(image_z); }
  template <class F> void for_each_pair_array(F&& f) {
    for_each_list_array(f);
    f(state);
    for_each_history([&](auto& v, const HistoryPart&) { f(v); });
    for (auto* v : {&nx, &ny, &nz, &overlap, &fn, &fx, &fy, &fz, &tx, &ty, &tz, &kn_eff, &ks_eff, &cn_eff,
                    &work_friction, &work_damping})
      f(*v);
  }
  template <class F> void for_each_pair_array(F&& f) const {
    const_cast<ContactTable*>(this)->for_each_pair_array([&](auto& v) { f(static_cast<const decltype(v)&>(v)); });
  }
  // The arrays of the last force pass's results (all of for_each_pair_array's but the pair list
  // and the shear history).
  template <class F> void for_each_result_array(F&& f) {
    f(state);
    for (auto* v : {&nx, &ny, &nz, &overlap, &fn, &fx, &fy, &fz, &tx, &ty, &tz, &kn_eff, &ks_eff, &cn_eff,
                    &work_friction, &work_damping})
      f(*v);
  }
};

// The order of a pair list (a ContactTable's or PairCandidates'): by i, then j, then image (the
// same two balls may touch across several periodic faces in a small cell). PairKey is a pair's
// place in it, for lists kept in other forms (the records the ranks send: BrickStep::merge_pair_runs).
struct PairKey {
  std::uint32_t i = 0, j = 0;
  std::int8_t x = 0, y = 0, z = 0;
  friend bool operator<(const PairKey& a, const PairKey& b) {
    return std::tie(a.i, a.j, a.x, a.y, a.z) < std::tie(b.i, b.j, b.x, b.y, b.z);
  }
};
template <class A> PairKey pair_key(const A& a, std::size_t p) {
  return {static_cast<std::uint32_t>(a.i[p]), static_cast<std::uint32_t>(a.j[p]), static_cast<std::int8_t>(a.image_x[p]),
          static_cast<std::int8_t>(a.image_y[p]), static_cast<std::int8_t>(a.image_z[p])};
}
// Pair p of `a` before pair q of `b`.
template <class A, class B> bool pair_before(const A& a, std::size_t p, const B& b, std::size_t q) {
  return pair_key(a, p) < pair_key(b, q);
}

// What the servo reads of a force pass, summed by the contact loops: sum of F (x) l (symmetric part,
// xx yy zz xy xz yz) and of k_n l_a^2 over the touching pairs, l the branch vector i -> j.
struct ContactMoments {
  std::array<double, 6> force{};
  std::array<double, 3> stiffness{};
};

// What happens to a ball whose centre leaves a free region (START box) across one axis's faces.
enum class Outside : std::uint8_t { Stop, Destroy };

// Where the balls live: a free region (START box) or a periodic cell (START x y z).
struct Space {
  bool periodic = false;                            // some axis is periodic (the image arithmetic is on)
  // Per axis, with `periodic`: whether balls meet images across that axis's faces. START x y z: all;
  // START box ... x periodic ...: those named (mixed periodicity); the others are bounded like a
  // box's, with its `outside` conditions, and hold no images (model/periodic_cell.hpp).
  std::array<bool, 3> periodic_axis{true, true, true};
  bool wraps(int a) const { return periodic && periodic_axis[a]; }
  bool mixed() const { return periodic && !(periodic_axis[0] && periodic_axis[1] && periodic_axis[2]); }
  std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};   // region, or periodic cell [lo, hi)
  // A sheared periodic cell (STRAIN with shear rates) is the parallelepiped lo + H s, s in [0, 1)^3,
  // with edge vectors a = (Lx, 0, 0), b = (xy, Ly, 0), c = (xz, yz, Lz), L = hi - lo: these tilts.
  std::array<double, 3> tilt{0, 0, 0};              // xy xz yz
  std::array<int, 3> boxes{0, 0, 0};                // contact-detection boxes asked for (0: auto)
  // Per bounded axis: CYCLE stops when a centre leaves (the default), or the ball is deleted.
  std::array<Outside, 3> outside{Outside::Stop, Outside::Stop, Outside::Stop};
  std::int64_t destroyed = 0;                       // balls deleted for leaving, since START
  // Periodic cell control (compression positive): xx yy zz xy xz yz.
  std::array<double, 6> strain_rate{};
  std::array<double, 6> strain{};                   // accumulated
  // The cell's volume where `strain` was last 0 (START, STRAIN reset): the volumetric strain is
  // 1 - V / this. 0 where unknown (a save older than format 6): then exp of the accumulated
  // strains stands in for the ratio.
  double reference_volume = 0;
  double volume() const { const auto L = length(); return L[0] * L[1] * L[2]; }
  std::array<bool, 3> servo_on{false, false, false};
  std::array<double, 3> servo_target{};
  double servo_gain = 0, servo_max_rate = 0;
  // The moments of the last force pass while the servo ran: the next step's servo acts on them. They
  // are state, like the velocities at t - dt/2, so that a run cut into CYCLEs, switched to another
  // backend or saved and restarted takes the same steps as one CYCLE (saved). Not valid before the
  // servo's first step: it then reads the contact table.
  ContactMoments servo_measured;
  bool servo_measured_valid = false;
  // The servo's integral term per axis (a strain rate): what it has learnt the loading needs beyond
  // the proportional part (physics/cell.hpp). State, saved.
  std::array<double, 3> servo_integral{};
  // Energy the cell control moved in and out, counted without sign (not saved): the instability
  // guard's scale, as a servo stopping a fast cell takes much out in one step.
  double gross_work = 0;
  std::array<double, 3> length() const { return {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}; }
};

// WALL: a rigid surface balls touch with the contact law of their types (doc/physics.md "Walls").
// A plane is one-sided: balls live on the side its normal points to. A polygon (planar, its
// vertices in order) and a cylinder (finite, balls inside or outside) touch from either side
// and at their edges. Geometry and motion are state (saved); the loads are those of the last
// force pass.
enum class WallKind : std::uint8_t { Plane, Polygon, Cylinder };

struct Wall {
  std::int64_t id = 0;
  int type = 1;                                 // material (PROP type), mixed with the ball's
  WallKind kind = WallKind::Plane;
  std::array<double, 3> point{};                // plane: a point on it; cylinder: its axis starts here
  std::array<double, 3> normal{0, 0, 1};        // plane: unit normal toward the balls; polygon: of its
                                                // plane (right hand of the vertex order); cylinder: unit axis
  std::vector<std::array<double, 3>> vertices;  // polygon
  double radius = 0, length = 0;                // cylinder: radius, length along the axis from point
  bool inside = true;                           // cylinder: balls inside (a container) or outside
  // Motion, constant within a step: a translation, a spin about an axis through spin_point, and
  // (cylinder) a rate of change of the radius. spin_point moves with the wall.
  std::array<double, 3> velocity{}, spin{}, spin_point{};
  double radius_rate = 0;
  // SERVO wall: the velocity along `normal` (cylinder: the radius rate) drives the wall's stress
  // (compression positive) toward the target; proportional-integral as the cell's servo.
  bool servo_on = false;
  double servo_target = 0, servo_gain = 0, servo_max_speed = 0, servo_integral = 0;
  double servo_area = 0;                        // given area (0: the wall's own, physics/walls.hpp)
  // The area from other walls (0: none): a plane's or polygon's is pi r^2 of cylinder area_walls[0]
  // (a platen in a cylinder); a cylinder's is 2 pi r times the distance along its axis between walls
  // area_walls[0] and [1] (the platens), so the stress is over the loaded height.
  std::array<std::int64_t, 2> area_walls{0, 0};
  // Loads of the last force pass that formed them: every CYCLE's last step, the steps an observer
  // reads, every step while a wall servo runs (cycle/run.cpp, StepPlan::wall_loads; a CYCLE that a
  // ball leaving the box stops leaves those of an earlier step); and the work the wall has done on
  // the balls since START (every step).
  std::array<double, 3> force{}, moment{};      // on the wall; moment about spin_point
  double normal_force = 0;                      // sum of the contacts' normal forces (compression > 0)
  double stiffness = 0;                         // sum of the touching contacts' k_n
  std::int64_t contacts = 0;                    // touching
  double work = 0;
  // Where its surface moves: sum over the touching balls of m |v_wall(c) - v|^2 / 2, their kinetic
  // energy in the wall's frame (v at t - dt/2). The instability guard counts it as energy in play
  // (cycle/run.cpp); not saved (every step the guard checks makes it again).
  double relative_kinetic = 0;
};

// Ball-wall contacts that may touch, sorted by (ball, wall): candidates within the pair-list skin.
// Only those with positive overlap carry force; the shear history is carried over by (ball id,
// wall id), like a ball pair's.
struct WallContacts {
  std::vector<std::uint32_t> ball, wall;        // ball index, index into Model::walls
  std::vector<std::int64_t> ball_id, wall_id;   // what the history is keyed by
  std::vector<double> fsx, fsy, fsz;            // shear force on the wall (history)
  std::vector<double> mrx, mry, mrz;            // rolling moment on the wall (history; on the ball: minus this)
  std::vector<double> bridge;                   // 1: a capillary bridge holds the ball to the wall (history)
  // Results of the last force pass that wrote details (ContactTable::results_cycle says which):
  std::vector<double> nx, ny, nz;               // unit normal, ball -> wall
  std::vector<double> overlap, fn, fx, fy, fz;  // fx..: force on the wall (on the ball: minus this)
  std::vector<double> kn_eff, ks_eff;           // stiffness now
  std::vector<std::uint8_t> state;              // 0 apart, 1 touching, 2 sliding
  // Unique to each list installed (as ContactTable::list_version); not saved.
  std::uint64_t list_version = 0;
  std::size_t size() const { return ball.size(); }
  // The history, each array with its name (a wall contact's ball never trades places with its wall).
  template <class F> void for_each_history(F&& f) {
    f(fsx, HistoryPart{"fsx", OnSwap::Negate});   // the shear spring
    f(fsy, HistoryPart{"fsy", OnSwap::Negate});
    f(fsz, HistoryPart{"fsz", OnSwap::Negate});
    f(mrx, HistoryPart{"mrx", OnSwap::Negate});   // the rolling spring
    f(mry, HistoryPart{"mry", OnSwap::Negate});
    f(mrz, HistoryPart{"mrz", OnSwap::Negate});
    f(bridge, HistoryPart{"bridge", OnSwap::Keep});   // the capillary bridge
  }
  // As ContactTable's (a wall contact keeps every part: the list is short).
  template <class F> void for_each_declared_history(F&& f) {
    for_each_history([&](auto& v, const HistoryPart& part) { f(v, part, true); });
  }
  // The list's arrays (which ball meets which wall).
  template <class F> void for_each_list_array(F&& f) { f(ball); f(wall); f(ball_id); f(wall_id); }
  // The results of the last force pass (every array but the list's and the history).
  template <class F> void for_each_result_array(F&& f) {
    f(state);
    for (auto* v : {&nx, &ny, &nz, &overlap, &fn, &fx, &fy, &fz, &kn_eff, &ks_eff}) f(*v);
  }
  template <class F> void for_each_array(F&& f) {
    for_each_list_array(f);
    f(state);
    for_each_history([&](auto& v, const HistoryPart&) { f(v); });
    for (auto* v : {&nx, &ny, &nz, &overlap, &fn, &fx, &fy, &fz, &kn_eff, &ks_eff}) f(*v);
  }
};

enum class DampKind { None, Rayleigh, Local };

struct Damping {
  DampKind kind = DampKind::None;
  std::uint32_t unused = 0;        // the padding SAVE writes with the struct, made explicit so its bytes are 0
  double alpha = 0, beta = 0;      // Rayleigh: mass and stiffness coefficients
  double lambda = 0, freq = 0;     // as given (DAMP lambda f), for PRINT damp; 0 when given as coefficients
  double local = 0;                // local damping coefficient
};

struct Settings {
  double frac = 0.8;               // dt = frac * critical step
  double fixed_dt = 0;             // TSTEP: > 0 fixes the step
  std::array<double, 3> gravity{0, 0, 0};
  Damping damping;
};

// Energy terms accumulated since START (or the last reset), for the balance.
struct Energy {
  double friction_work = 0;        // dissipated by sliding
  double damping_work = 0;         // dissipated by all damping
  double boundary_work = 0;        // done by fixed velocities and applied forces (gravity: potential)
  double rolling_work = 0;         // dissipated by the rolling springs' limit (PROP rr_fric)
  double capillary_work = 0;       // done on the balls by the capillary bridges (PROP bridge)
  double bond_break_work = 0;      // the strain energy the parallel bonds held when they broke (BOND)
};

// The energy terms at the time t of the last step's force pass (cycle/run.cpp): the positions were
// then x(t) (now x(t) + v dt), the velocities v(t - dt/2) and v(t + dt/2) (now the latter). kinetic
// m v(t - dt/2).v(t + dt/2)/2, the springs' energy and gravity's potential at x(t); the ahead parts
// are what the step's works (Energy) hold beyond t, so the works up to t are the totals less them.
// valid: the balls are as that step left them (an edit of the balls makes it false).
struct EnergyAtStep {
  bool valid = false;
  double kinetic_translation = 0, kinetic_rotation = 0, strain = 0, potential = 0;
  double damping_ahead = 0, boundary_ahead = 0, capillary_ahead = 0;
};

// MEMBRANE: its pressure and the cross-section area its forces are consistent with (the union of
// the loaded layers' square cells), so that HIST ratio can form F1 / (A sigma2). 0: no membrane.
// With `follow`, the forces are recomputed from the positions every follow_every cycles
// (physics/membrane.hpp), from what was fixed when MEMBRANE was given: the loaded balls, the open
// cell faces of each, its layer, and each loaded layer's first extent; the area then follows the
// widest loaded layer's extent.
struct Membrane {
  double pressure = 0;
  double area = 0;
  std::int64_t follow_every = 0;           // 0: the forces stay as computed
  double cell = 0;                         // d, the side of a ball's square cell
  std::vector<std::int64_t> ids;           // loaded balls
  std::vector<std::int8_t> face_x, face_y; // per loaded ball: open faces, -1 .. 1 (force direction)
  std::vector<std::int32_t> layer;         // per loaded ball: its loaded layer, 0 = lowest
  std::vector<double> extent_x, extent_y;  // per loaded layer: the x and y extent of its centres then
  std::vector<double> layer_cells;         // per loaded layer: its cells, times d^2 its area
};

// SAMPLE: a specimen held by walls, as in a triaxial or an oedometer test between platens. Its
// measures (physics/sample.hpp) are referred to the sample as it stood when declared or reset.
struct Sample {
  std::array<std::int64_t, 2> platens{0, 0};   // the walls across the axial direction; 0: no sample
  // The lateral walls: a cylinder (sides[0], the rest 0), or two pairs of facing planes or polygons
  // (sides[0] and [1] across one direction, [2] and [3] across the other).
  std::array<std::int64_t, 4> sides{0, 0, 0, 0};
  double height0 = 0, area0 = 0;               // the platens' distance and the cross-section then
  bool declared() const { return platens[0] != 0; }
};

struct Model {
  Space space;
  std::map<int, Material> materials;      // by type number
  Balls balls;
  ContactTable contacts;
  std::vector<Wall> walls;                // by ascending id
  WallContacts wall_contacts;
  Bonds bonds;                            // parallel bonds (model/bonds.hpp)
  Settings settings;
  Energy energy;
  EnergyAtStep energy_at_step;
  Membrane membrane;
  Sample sample;
  std::map<std::string, std::vector<std::int64_t>> groups;   // GROUP name -> ball ids
  std::int64_t cycle = 0;
  // The balls' order in memory (SET sort; cycle/run.cpp): at the start of a step whose cycle number
  // is a multiple of `every`, and of the first step after balls were added (`pending`), the balls
  // are put in space order, so that neighbours in space are neighbours in memory (every 0: never;
  // they stay in the order they were added). Both saved.
  struct Order {
    std::int64_t every = 1000;            // LAMMPS's atom_modify sort default
    bool pending = false;
  } order;
  double time = 0;
  double dt = 0;                          // step of the last cycle (0 before the first)
  double critical_dt = 0;                 // critical step from the last force pass (0: estimate afresh)
  std::string title;
  bool started = false;                   // START given
};

}  // namespace trubal
