// Everything a failed step must be able to go back to: the rescue copy run_cycles takes every few
// hundred steps. The pipeline keeps it between CYCLEs, so that each CYCLE does not fault in fresh
// pages for it.
//
// Of the contact table it copies the state alone (the pair list, the history and whether
// each pair touched), not the results of the last force pass (normal, overlap, forces, stiffness,
// work: 16 of the 22 values of a pair), which would make the copy as large as the model. The
// results come back otherwise: the copies on a multiple of 500 steps are taken a step before, and
// run_cycles takes that step again, which writes them (cycle/run.cpp); for the copy of a CYCLE's
// start they still stand in the model's table (restore).
//
// An array that is all zeros is kept as an empty one, with its length (Zeros): the rolling moments
// of a scene without rolling resistance, the applied loads where nothing is applied, the spins of
// a scene without rotation. A million balls' copy is then some 200 bytes a ball smaller.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "cycle/pair_list.hpp"
#include "model/model.hpp"

namespace trubal {

struct Snapshot {
  Balls balls;   // all but the unbalanced forces and moments (results: restore), zero arrays empty
  std::vector<std::size_t> ball_lengths;   // of each of balls' arrays (for_each_array's order)
  // The contact table's state: its pair list, the history (ContactTable::for_each_history's arrays,
  // in its order).
  PairCandidates pairs;
  std::vector<std::vector<double>> history;   // an all-zero part empty
  HistoryLaws history_laws;                    // the parts in use
  std::vector<std::size_t> history_lengths;
  std::vector<std::uint8_t> state;   // whether each pair touched (restore: a pair the list lost since)
  std::int64_t results_cycle = -1;
  std::vector<Wall> walls;
  WallContacts wall_contacts;
  Energy energy;
  EnergyAtStep energy_at_step;
  Space space;
  Membrane membrane;                                          // a following membrane's area
  std::map<std::string, std::vector<std::int64_t>> groups;   // destroyed balls leave their groups
  Bonds bonds;                                                // their forces, and which broke
  std::int64_t cycle = 0;
  Model::Order order;
  double time = 0, dt = 0, critical_dt = 0;

  void take(const Model& m) {
    copy_balls(balls, m.balls);
    const ContactTable& c = m.contacts;
    pairs = pair_list_of(c);
    history_laws = c.history_laws;
    history.resize(c.history_count());
    history_lengths.assign(history.size(), 0);
    std::size_t h = 0;
    c.for_each_history([&](const auto& v, const HistoryPart&) {
      history_lengths[h] = v.size();
      copy_unless_zero(history[h++], v);
    });
    state = c.state;
    wall_contacts = m.wall_contacts;
    take_rest(m);
  }

  // All but the balls, the pairs and the wall contacts (a distributed run's ranks other than 0:
  // rank 0 hands those over where the copy is put back, Pipeline::restore_rescue). Their memory goes.
  void take_light(const Model& m) {
    take_light_arrays();
    take_rest(m);
  }
  void take_light_arrays() {
    auto free = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
    balls = Balls{};
    pairs = PairCandidates{};
    free(history); free(history_lengths); free(state); free(ball_lengths);
    wall_contacts = WallContacts{};
  }
  // Frees the balls, the pairs and the wall contacts, and marks the copy as of no cycle: make_results
  // puts the copy back to take a step again and needs it no more (a million balls' copy is about
  // 300 MB, which the results made then take instead).
  void release() {
    take_light_arrays();
    cycle = kNone;
  }
  static constexpr std::int64_t kNone = -2;   // (cycle + 1 is no model's cycle)

  // The bytes of its arrays of balls, pairs and wall contacts (their capacity).
  std::size_t bytes() const {
    std::size_t n = 0;
    auto add = [&](const auto& v) { n += capacity_bytes(v); };
    balls.for_each_array(add);
    for (const auto* v : {&pairs.i, &pairs.j}) add(*v);
    for (const auto* v : {&pairs.image_x, &pairs.image_y, &pairs.image_z}) add(*v);
    for (const auto& v : history) add(v);
    add(state);
    const_cast<WallContacts&>(wall_contacts).for_each_array(add);   // (no const visitor; it only reads)
    return n;
  }

  // What take_light kept, back into the model.
  void restore_light(Model& m) const {
    m.walls = walls; m.space = space;
    m.energy = energy; m.energy_at_step = energy_at_step;
    m.membrane = membrane; m.groups = groups; m.bonds = bonds;
    m.cycle = cycle; m.order = order; m.time = time; m.dt = dt; m.critical_dt = critical_dt;
  }

  // Puts the copy back. Returns whether the table's results are those of the copy's state: true
  // where they were of its cycle when it was taken, no step since wrote results and the balls are
  // the same. The results then still stand in
  // the model's table, and install_pairs moves them to the copy's list by the pair, as it moves
  // them at a rebuild; a pair the list has lost since comes back with zero results, which are its
  // results only if it did not touch (its state tells) and no bridge held it apart (its normal
  // does: bridge_lost). Else they are zero, with results_cycle -1.
  bool restore(Model& m) const {
    ContactTable& c = m.contacts;
    const bool same_step = c.results_cycle == results_cycle && m.balls.id == balls.id;
    if (!holds_pairs(c, pairs)) install_pairs(c, pairs);   // the same list keeps its index
    c.set_history_laws(history_laws);
    std::size_t h = 0;
    c.for_each_history([&](auto& v, const HistoryPart&) {
      paste(v, history[h], history_lengths[h]);
      ++h;
    });
    const bool current = same_step && results_cycle == cycle && c.state == state && !bridge_lost(c);
    if (!current) {
      c.for_each_result_array([&](auto& v) { v.assign(v.size(), {}); });
      c.results_cycle = -1;
    }
    paste_balls(m.balls);
    m.balls.index_ids();   // (the copy's order: a sort since has moved them)
    // The unbalanced forces are results too: the model's stand where the results do.
    for (auto* v : unbalanced(m.balls))
      if (!current || v->size() != m.balls.size()) v->assign(m.balls.size(), 0.0);
    m.wall_contacts = wall_contacts;
    restore_light(m);
    return current;
  }

 private:
  // Whether a pair that a bridge held apart in the results' force pass has no normal there: the
  // bridge pass gave every such pair one (cycle/bridge_pass.cpp), so the list lost it since.
  static bool bridge_lost(const ContactTable& c) {
    if (c.bridge.size() != c.size() || !c.results_kept()) return false;
    for (std::size_t p = 0; p < c.size(); ++p)
      if (c.bridge[p] != 0 && c.state[p] == 0 && c.nx[p] == 0 && c.ny[p] == 0 && c.nz[p] == 0) return true;
    return false;
  }
  // Everything but the balls, the pairs and the wall contacts (restore_light puts it back).
  void take_rest(const Model& m) {
    results_cycle = m.contacts.results_cycle;
    walls = m.walls; space = m.space;
    energy = m.energy; energy_at_step = m.energy_at_step;
    membrane = m.membrane; groups = m.groups; bonds = m.bonds;
    cycle = m.cycle; order = m.order; time = m.time; dt = m.dt; critical_dt = m.critical_dt;
  }
  static std::array<std::vector<double>*, 6> unbalanced(Balls& b) { return {&b.fx, &b.fy, &b.fz, &b.mx, &b.my, &b.mz}; }
  // A copy of `from` in `to`, or `to` emptied where `from` is all zeros (its capacity kept, so
  // that a copy every few hundred steps does not fault in fresh pages).
  template <class V> static void copy_unless_zero(V& to, const V& from) {
    using T = typename V::value_type;
    if (std::all_of(from.begin(), from.end(), [](const T& x) { return x == T{}; })) {
      to.clear();
      return;
    }
    to = from;
  }
  // The copy back: the values, or zeros of the length where the copy is empty.
  template <class V> static void paste(V& to, const V& from, std::size_t length) {
    if (from.empty()) to.assign(length, typename V::value_type{});
    else to = from;
  }
  // f(to's array, from's array, k) for every per-ball array but the unbalanced forces and moments
  // (48 bytes a ball the copy need not hold), k its place in Balls::for_each_array's order.
  template <class F> static void each_kept_array(Balls& to, const Balls& from, F&& f) {
    std::vector<const void*> source;
    from.for_each_array([&](const auto& v) { source.push_back(&v); });
    const auto skip = unbalanced(to);
    std::size_t k = 0;
    to.for_each_array([&](auto& v) {
      using V = std::decay_t<decltype(v)>;
      const V& s = *static_cast<const V*>(source[k]);
      const std::size_t at = k++;
      if constexpr (std::is_same_v<V, std::vector<double>>)
        if (std::find(skip.begin(), skip.end(), &v) != skip.end()) return;
      f(v, s, at);
    });
  }
  // The model's balls into the copy, each all-zero array empty (the ids always whole: restore
  // compares them).
  void copy_balls(Balls& to, const Balls& from) {
    std::size_t arrays = 0;
    from.for_each_array([&](const auto&) { ++arrays; });
    ball_lengths.assign(arrays, 0);
    each_kept_array(to, from, [&](auto& v, const auto& s, std::size_t k) {
      ball_lengths[k] = s.size();
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, std::vector<std::int64_t>>) v = s;
      else copy_unless_zero(v, s);
    });
  }
  // The copy's balls into the model's (the unbalanced forces left to restore).
  void paste_balls(Balls& to) const {
    each_kept_array(to, balls, [&](auto& v, const auto& s, std::size_t k) { paste(v, s, ball_lengths[k]); });
  }
};

}  // namespace trubal
