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
  Range platen_range;                      // balls whose reaction is `platen`
  std::vector<std::vector<double>> rows;
  std::unique_ptr<std::ofstream> out;
};

class History {
 public:
  // The item names HIST accepts, for parsing and completion.
  static const std::vector<std::string_view>& item_names();
  // Adds a table; opens (truncates) its file and writes the header. Throws std::runtime_error if the
  // file cannot be written.
  HistoryTable& add(std::vector<std::string> items, std::int64_t every, const std::string& file, Range platen_range);
  // Records a row in every table whose period divides the model's cycle count.
  void sample(const Model& model, double volume);
  // Records a row in every table now, whatever the cycle.
  void sample_all(const Model& model, double volume);
  void clear();
  const std::vector<std::unique_ptr<HistoryTable>>& tables() const { return tables_; }
  // Finds a column by name in any table: (table, column index), or (nullptr, 0).
  std::pair<const HistoryTable*, std::size_t> find_column(const std::string& name) const;

 private:
  void record(HistoryTable& table, const Model& model, double volume);
  std::vector<std::unique_ptr<HistoryTable>> tables_;
};

}  // namespace trubal
