// HIST: quantities recorded every n cycles, kept in memory (PRINT history, PLOT) and written as CSV
// rows as they come (flushed, so a crash loses nothing already recorded).
#pragma once

#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "model/model.hpp"
#include "model/range.hpp"

namespace trubal {

struct HistoryTable {
  std::vector<std::string> items;          // as asked: stress, energy, ...
  std::vector<std::string> columns;        // cycle, time, then the items' columns
  std::int64_t every = 1;
  std::string file;                        // empty: memory only
  Range platen_range;                      // as given (PRINT history)
  // The platen balls: where platen_range held when HIST was given, by id, so that they stay the
  // same balls as they move. With a range, `ratio` is F1 / (A sigma2) and `axial` is the change of
  // the gap between the two platens over its first value (physics/measure.hpp `platens`).
  std::vector<std::int64_t> platen_ids;
  double platen_gap0 = 0;
  double area = 0, pressure = 0;           // A and sigma2 of `ratio`
  bool membrane_area = false;               // A is the membrane's, read at each record (it follows the sample)
  // The rows: all of them for a table in memory only; for one written to a file (which has every
  // row) the last kWindow at least, so that a long `every 1` run does not fill the memory.
  std::vector<std::vector<double>> rows;
  std::size_t recorded = 0;                // rows recorded since HIST (in the file, for a file table)
  static constexpr std::size_t kWindow = 10000;
  std::unique_ptr<std::ofstream> out;
  // The rows PLOT and PRINT history read: the window, or every row read back from the file when
  // the window no longer holds them all.
};

class History {
 public:
  // The item names HIST accepts, for parsing and completion.
  static const std::vector<std::string_view>& item_names();
  // Adds a table; opens (truncates) its file and writes the header. Throws std::runtime_error if the
  // file cannot be written.
  HistoryTable& add(std::vector<std::string> items, std::int64_t every, const std::string& file, Range platen_range);
  // The balls of a platen id list, as ascending indices (ids that left the model are skipped).
  static std::vector<std::size_t> platen_balls(const Model& model, const HistoryTable& table);
  // Records a row in every table whose period divides the model's cycle count.
  void sample(const Model& model, double volume);
  // Whether sample() records a row at this cycle.
  bool due(std::int64_t cycle) const {
    for (const auto& t : tables_)
      if (cycle % t->every == 0) return true;
    return false;
  }
  // Records a row in every table now, whatever the cycle.
  void sample_all(const Model& model, double volume);
  void clear();
  // Takes a table made elsewhere (read_history_csv).
  void adopt(std::unique_ptr<HistoryTable> table) { tables_.push_back(std::move(table)); }
  const std::vector<std::unique_ptr<HistoryTable>>& tables() const { return tables_; }
  // Finds a column by name in any table: (table, column index), or (nullptr, 0).
  std::pair<const HistoryTable*, std::size_t> find_column(const std::string& name) const;

 private:
  void record(HistoryTable& table, const Model& model, double volume);
  std::vector<std::unique_ptr<HistoryTable>> tables_;
};

// Reads a CSV file written by HIST ... file (a header row, then rows of numbers) as a table whose
// `file` is the path. Throws std::runtime_error naming the file and line of anything malformed.
std::unique_ptr<HistoryTable> read_history_csv(const std::string& path);

}  // namespace trubal
