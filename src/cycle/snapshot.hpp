// Everything a failed step must be able to go back to: the rescue copy run_cycles takes every few
// hundred steps. The pipeline keeps it between CYCLEs, so that each CYCLE does not fault in fresh
// pages for it.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "model/model.hpp"

namespace trubal {

struct Snapshot {
  Balls balls;
  ContactTable contacts;
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
    balls = m.balls; contacts = m.contacts; walls = m.walls; wall_contacts = m.wall_contacts; space = m.space;
    energy = m.energy; energy_at_step = m.energy_at_step;
    membrane = m.membrane; groups = m.groups;
    cycle = m.cycle; time = m.time; dt = m.dt; critical_dt = m.critical_dt;
  }
  void restore(Model& m) const {
    m.balls = balls; m.contacts = contacts; m.walls = walls; m.wall_contacts = wall_contacts; m.space = space;
    m.energy = energy; m.energy_at_step = energy_at_step;
    m.membrane = membrane; m.groups = groups;
    m.cycle = cycle; m.time = time; m.dt = dt; m.critical_dt = critical_dt;
  }
};

}  // namespace trubal
