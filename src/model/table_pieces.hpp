// Where a distributed RESTART's parts come from: the bulk of a save (its balls', pairs' and wall
// contacts' arrays), which rank 0 reads a piece at a time and hands each rank its own of
// (io/save.hpp SavedTables reads them, cycle/brick_step.hpp BrickStep::split_from_file hands them
// out). Each table's arrays are numbered in one order both sides walk (each_piece_array).
#pragma once

#include <cstddef>
#include <cstdint>

#include "model/model.hpp"

namespace trubal {

enum class PieceTable { Balls, Pairs, Walls };

// f(array, k, used) on each array of a table in its pieces' order, k its number: the balls'
// arrays (Balls::for_each_array); a pair table's list, every declared history part (`used`:
// whether the table keeps it) and results; a wall contact table's arrays (for_each_array).
template <class F> void each_piece_array(Balls& b, F&& f) {
  std::size_t k = 0;
  b.for_each_array([&](auto& v) { f(v, k++, true); });
}
template <class F> void each_piece_array(ContactTable& t, F&& f) {
  std::size_t k = 0;
  t.for_each_list_array([&](auto& v) { f(v, k++, true); });
  t.for_each_declared_history([&](auto& v, const HistoryPart&, bool used) { f(v, k++, used); });
  t.for_each_result_array([&](auto& v) { f(v, k++, true); });
}
template <class F> void each_piece_array(WallContacts& w, F&& f) {
  std::size_t k = 0;
  w.for_each_array([&](auto& v) { f(v, k++, true); });
}

class TablePieces {
 public:
  virtual ~TablePieces() = default;
  // The rows of a table (balls, pairs, wall contacts).
  virtual std::uint64_t rows(PieceTable table) const = 0;
  // Elements [from, from + n) of array k of the table, `size` bytes each, into `out`: zeros where
  // the save holds no such array (a history part it did not know). Throws std::runtime_error
  // where the file cannot be read.
  virtual void read(PieceTable table, std::size_t k, std::uint64_t from, std::uint64_t n, void* out, std::size_t size) = 0;
};

}  // namespace trubal
