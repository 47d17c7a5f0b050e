// Everything a failed step must be able to go back to: the rescue copy run_cycles takes every few
// hundred steps. The pipeline keeps it between CYCLEs, so that each CYCLE does not fault in fresh
// pages for it.
//
// Of the contact table it copies the state alone (the pair list, the shear history and whether
// each pair touched), not the results of the last force pass (normal, overlap, forces, stiffness,
// work: 16 of the 22 values of a pair), which would make the copy as large as the model. The
// results come back otherwise: the copies on a multiple of 500 steps are taken a step before, and
// run_cycles takes that step again, which writes them (cycle/run.cpp); for the copy of a CYCLE's
// start they still stand in the model's table (restore).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include "model/model.hpp"

namespace trubal {

struct Snapshot {
  Balls balls;
  // The contact table's state.
  std::vector<std::uint32_t> pair_i, pair_j;
  std::vector<std::int8_t> image_x, image_y, image_z;
  std::vector<double> fsx, fsy, fsz;
  std::vector<std::uint8_t> state;   // whether each pair touched (restore: a pair the list lost since)
  std::int64_t results_cycle = -1;
  std::vector<Wall> walls;
  WallContacts wall_contacts;
  Energy energy;
  EnergyAtStep energy_at_step;
  Space space;
  Membrane membrane;                                          // a following membrane's area
  std::map<std::string, std::vector<std::int64_t>> groups;   // destroyed balls leave their groups
  std::int64_t cycle = 0;
  double time = 0, dt = 0, critical_dt = 0;

  void take(const Model& m) {
    balls = m.balls;
    const ContactTable& c = m.contacts;
    pair_i = c.i; pair_j = c.j; image_x = c.image_x; image_y = c.image_y; image_z = c.image_z;
    fsx = c.fsx; fsy = c.fsy; fsz = c.fsz;
    state = c.state;
    results_cycle = c.results_cycle;
    walls = m.walls; wall_contacts = m.wall_contacts; space = m.space;
    energy = m.energy; energy_at_step = m.energy_at_step;
    membrane = m.membrane; groups = m.groups;
    cycle = m.cycle; time = m.time; dt = m.dt; critical_dt = m.critical_dt;
  }

  // Puts the copy back. Returns whether the table's results are those of the copy's state: true
  // where no step since wrote results and the balls are the same. The results then still stand in
  // the model's table, moved with their pairs where a rebuild changed the list (install_pairs),
  // and are taken from there; a pair the list has lost since had zero results if it did not touch.
  // Else they are zero, with results_cycle -1.
  bool restore(Model& m) const {
    ContactTable& c = m.contacts;
    const std::size_t n = pair_i.size(), now = c.size();
    bool current = c.results_cycle == results_cycle && m.balls.id == balls.id && state.size() == n;
    c.for_each_pair_array([&](const auto& v) { current = current && v.size() == now; });
    // Where each of the copy's pairs is in the model's list (both sorted by i, j, image), or none.
    constexpr std::size_t kLost = ~std::size_t{0};
    std::vector<std::size_t> from;
    if (current) {
      from.assign(n, kLost);
      auto key = [](const std::vector<std::uint32_t>& i, const std::vector<std::uint32_t>& j,
                    const std::vector<std::int8_t>& x, const std::vector<std::int8_t>& y,
                    const std::vector<std::int8_t>& z, std::size_t p) { return std::tuple(i[p], j[p], x[p], y[p], z[p]); };
      std::size_t p = 0;
      for (std::size_t q = 0; q < n && current; ++q) {
        const auto want = key(pair_i, pair_j, image_x, image_y, image_z, q);
        while (p < now && key(c.i, c.j, c.image_x, c.image_y, c.image_z, p) < want) ++p;
        if (p < now && key(c.i, c.j, c.image_x, c.image_y, c.image_z, p) == want) from[q] = p;
        else current = state[q] == 0;
      }
    }
    c.i = pair_i; c.j = pair_j; c.image_x = image_x; c.image_y = image_y; c.image_z = image_z;
    c.fsx = fsx; c.fsy = fsy; c.fsz = fsz;
    c.for_each_result_array([&](auto& v) {
      std::decay_t<decltype(v)> kept(n, {});
      if (current)
        for (std::size_t q = 0; q < n; ++q)
          if (from[q] != kLost) kept[q] = v[from[q]];
      v.swap(kept);
    });
    if (!current) c.results_cycle = -1;
    c.list_version = 0;   // a list nobody indexed: the pipeline searches afresh
    m.balls = balls; m.walls = walls; m.wall_contacts = wall_contacts; m.space = space;
    m.energy = energy; m.energy_at_step = energy_at_step;
    m.membrane = membrane; m.groups = groups;
    m.cycle = cycle; m.time = time; m.dt = dt; m.critical_dt = critical_dt;
    return current;
  }
};

}  // namespace trubal
