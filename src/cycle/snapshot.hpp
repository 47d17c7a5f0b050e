// Everything a failed step must be able to go back to: the rescue copy run_cycles takes every few
// hundred steps. The pipeline keeps it between CYCLEs, so that each CYCLE does not fault in fresh
// pages for it.
//
// Of the contact table it copies the state alone (the pair list and the shear history), not the
// results of the last force pass (normal, overlap, forces, stiffness, work, state: 17 of the 22
// values of a pair), which would make the copy as large as the model. run_cycles makes them
// afresh instead: it replays the steps from the copy up to the one before the failing step, the
// last of them writing the results (cycle/run.cpp).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "model/model.hpp"

namespace trubal {

struct Snapshot {
  Balls balls;
  // The contact table's state.
  std::vector<std::uint32_t> pair_i, pair_j;
  std::vector<std::int8_t> image_x, image_y, image_z;
  std::vector<double> fsx, fsy, fsz;
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
    results_cycle = c.results_cycle;
    walls = m.walls; wall_contacts = m.wall_contacts; space = m.space;
    energy = m.energy; energy_at_step = m.energy_at_step;
    membrane = m.membrane; groups = m.groups;
    cycle = m.cycle; time = m.time; dt = m.dt; critical_dt = m.critical_dt;
  }

  // Puts the copy back. Returns whether the table's results are those of the copy's state: true
  // where the model still holds the same pair list with the results of the same force pass (no
  // step since wrote results or changed the list); else they are zero, with results_cycle -1.
  bool restore(Model& m) const {
    ContactTable& c = m.contacts;
    const std::size_t n = pair_i.size();
    bool current = c.results_cycle == results_cycle && c.i == pair_i && c.j == pair_j && c.image_x == image_x &&
                   c.image_y == image_y && c.image_z == image_z;
    c.for_each_pair_array([&](const auto& v) { current = current && v.size() == n; });
    c.i = pair_i; c.j = pair_j; c.image_x = image_x; c.image_y = image_y; c.image_z = image_z;
    c.fsx = fsx; c.fsy = fsy; c.fsz = fsz;
    if (!current) {
      c.for_each_result_array([&](auto& v) { v.assign(n, {}); });
      c.results_cycle = -1;
    }
    c.list_version = 0;   // a list nobody indexed: the pipeline searches afresh
    m.balls = balls; m.walls = walls; m.wall_contacts = wall_contacts; m.space = space;
    m.energy = energy; m.energy_at_step = energy_at_step;
    m.membrane = membrane; m.groups = groups;
    m.cycle = cycle; m.time = time; m.dt = dt; m.critical_dt = critical_dt;
    return current;
  }
};

}  // namespace trubal
