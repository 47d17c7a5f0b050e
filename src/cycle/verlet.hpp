// When a kept pair list is stale: the rule the serial and threaded backends share, so both rebuild
// at the same steps and keep the same pairs. The list holds every pair closer than the skin at
// the last rebuild; two balls each moving half the skin (or the periodic cell changing by more than
// it) can just close the gap, so then it is rebuilt.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "model/model.hpp"

namespace trubal {

class VerletReference {
 public:
  // Positions at the last rebuild, for wrap_into_cell to move with the balls. The rule is checked
  // only while the list it was recorded for is the table's (the pipeline's job).
  std::vector<double> x, y, z;

  // The squared displacement a ball may have made since the last rebuild, or a negative number when
  // the list must be rebuilt whatever the balls did (never built, balls added or resized, the cell
  // changed by the skin).
  double displacement_limit2(const Model& model) const;
  // Largest squared displacement of balls [begin, end) since the last rebuild (NaN counts as large).
  double max_displacement2(const Balls& balls, std::size_t begin, std::size_t end) const;
  // The skin for a rebuild now: a fifth of the mean radius (the periodic search may cut it).
  static double skin_for(const Balls& balls);
  // Remembers the state the new list was built from.
  void record(const Model& model, double skin);
  // A rebuild made on a distributed run's parts (BrickStep::rebuild_local), whose positions stay
  // there until a sync gathers them into x, y, z: the cell and the skin of the new list.
  void record_cell(const Model& model, double skin);
  void invalidate() { valid_ = false; }
  // The radii are not kept for the test (a distributed run's ranks whose parts are about to be
  // made from the whole model: any change of a radius is an edit, which drops the parts and
  // invalidates this), saving 8 bytes a ball of the whole model on every rank. The next record
  // keeps them again.
  void forget_radii() {
    std::vector<double>().swap(rad_);
    radii_kept_ = false;
  }
  // The balls were put in the order `order` (new index k holds old index order[k]) without a new
  // list (a distributed run's sort on its parts: Pipeline::sort_on_parts): the positions and radii
  // held follow them.
  void reorder(const std::vector<std::uint32_t>& order);
  // Of `n` balls, those `rows` names kept, in that order, the others gone (DELETE on the parts):
  // the positions and radii held for n balls follow them.
  void keep_rows(const std::vector<std::uint32_t>& rows, std::size_t n);
  // The balls the reference was recorded for (x, y, z hold their positions, but on a distributed
  // run's rank that held the balls' ids, types and radii alone: then they are empty).
  std::size_t balls() const { return count_; }
  double skin() const { return skin_; }
  std::size_t rebuilds() const { return rebuilds_; }

 private:
  std::vector<double> rad_;
  std::array<double, 3> cell_{0, 0, 0};   // periodic cell edges at the last rebuild
  std::array<double, 3> tilt_{0, 0, 0};   // and its tilts
  double skin_ = 0;
  std::size_t count_ = 0;
  bool valid_ = false;
  bool radii_kept_ = true;                // (forget_radii)
  std::size_t rebuilds_ = 0;
};

// The pair-list skin to use in the periodic cell: the given one, cut down so that a ball's reach
// (its diameter plus the skin) stays below half of every width (one image per pair).
double periodic_skin(const Model& model, double skin);


}  // namespace trubal
