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
#include <vector>

#include "cycle/pair_list.hpp"
#include "model/model.hpp"

namespace trubal {

struct Snapshot {
  Balls balls;
  // The contact table's state: its pair list, the shear history.
  PairCandidates pairs;
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
    pairs.i = c.i; pairs.j = c.j; pairs.image_x = c.image_x; pairs.image_y = c.image_y; pairs.image_z = c.image_z;
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
  // the model's table, and install_pairs moves them to the copy's list by the pair, as it moves
  // them at a rebuild; a pair the list has lost since comes back with zero results, which are its
  // results only if it did not touch (its state tells). Else they are zero, with results_cycle -1.
  bool restore(Model& m) const {
    ContactTable& c = m.contacts;
    const bool same_step = c.results_cycle == results_cycle && m.balls.id == balls.id;
    install_pairs(c, pairs);
    c.fsx = fsx; c.fsy = fsy; c.fsz = fsz;
    const bool current = same_step && c.state == state;
    if (!current) {
      c.for_each_result_array([&](auto& v) { v.assign(v.size(), {}); });
      c.results_cycle = -1;
    }
    m.balls = balls; m.walls = walls; m.wall_contacts = wall_contacts; m.space = space;
    m.energy = energy; m.energy_at_step = energy_at_step;
    m.membrane = membrane; m.groups = groups;
    m.cycle = cycle; m.time = time; m.dt = dt; m.critical_dt = critical_dt;
    return current;
  }
};

}  // namespace trubal
