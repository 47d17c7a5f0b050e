// HIST: quantities recorded every n cycles, kept in memory (PRINT history, PLOT) and written as CSV
// rows as they come (flushed, so a crash loses nothing already recorded).
#pragma once

#include <cstdint>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "model/model.hpp"
#include "model/range.hpp"
#include "physics/measure.hpp"
#include "physics/bond.hpp"
#include "physics/measure_sphere.hpp"

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

// Where a record's sums come from, in a distributed run whose ranks keep their parts through a
// CYCLE's output steps: Love's stress sums and the contact sums merged over the parts
// (Pipeline::stress_on_parts, contact_sums_on_parts: collective calls, the same numbers on every
// rank and serial's bits). Unset: the model's own.
struct HistorySums {
  std::function<StressSums()> stress;
  std::function<ContactSums()> contacts;
  // A ball's item: read(balls, k) on the ball of that id where it is, its values to every rank
  // (NaN where no ball has it).
  using BallRead = std::function<std::vector<double>(const Balls&, std::size_t)>;
  std::function<std::vector<double>(std::int64_t id, std::size_t count, const BallRead& read)> ball;
  // The capillary bridges intact, between balls and to walls.
  std::function<std::size_t()> bridges;
  // A measurement sphere's measurement (throws std::runtime_error as measure_sphere).
  std::function<SphereMeasurement(const MeasureSphere&)> sphere;
  // The platen balls of these ids, in the model's order.
  std::function<PlatenBalls(const std::vector<std::int64_t>& ids)> platens;
  // The bonds' counts by fate.
  std::function<BondCounts()> bonds;
};

// What HIST ... file does with a file that is there: `new` starts it afresh, `append` keeps its rows
// up to the present cycle and adds to them; the default is `new`, saying how many rows it replaces.
enum class HistoryFileMode { Default, New, Append };

// What History::add did: a new table, or (`continued`) the live table that already writes that
// file with the same columns and period (a HIST repeated after RESTART resumed it). `note`: what it
// did to a file that was there (replaced rows, kept rows, dropped later rows), or "".
struct HistoryAdded {
  HistoryTable& table;
  bool continued = false;
  std::string note;
};

class History {
 public:
  // The item names HIST accepts, for parsing and completion.
  static const std::vector<std::string_view>& item_names();
  // The quantities `ball <id>` records, any of them in any order: position, velocity, spin and the
  // unbalanced force of the last step (as PRINT balls shows them). Its item is "ball <id> <q>...",
  // its columns b<id>_<q>.
  static const std::vector<std::string_view>& ball_quantities();
  // Adds a table; opens its file as `mode` says (at the model's `cycle`) and writes the header.
  // Throws std::runtime_error if the file cannot be written, if `append` finds other columns in it,
  // or if another live table writes the same file with other columns.
  HistoryAdded add(std::vector<std::string> items, std::int64_t every, const std::string& file, Range platen_range,
                   HistoryFileMode mode = HistoryFileMode::Default, std::int64_t cycle = 0);
  // After RESTART: reopens the file of every table taken from the save, for appending. A file's
  // rows after `cycle` (a later part of the run that wrote it) are dropped; a file that is missing
  // or holds other columns is started afresh with the rows the save kept. Returns what it did, one
  // note per table that needed one.
  std::vector<std::string> resume_files(std::int64_t cycle);
  // Whether a table's items are ones HIST makes (a wall's id, a measurement sphere's numbers) and
  // its columns theirs: what a save file's tables must pass (a checksum cannot vouch for a file
  // written by hand).
  static bool valid_table(const HistoryTable& table);
  // The balls of a platen id list, as ascending indices (ids that left the model are skipped).
  static std::vector<std::size_t> platen_balls(const Model& model, const HistoryTable& table);
  // Records a row in every table whose period divides the model's cycle count.
  void sample(const Model& model, double volume);
  // Whether every table's items are ones each rank can record at a CYCLE's output step from the
  // sums merged over the parts and the light state it holds (the model's clock, cell, walls'
  // loads and energies, the balls' radii) and a ball's values its owner sends: stress, pq, ratio
  // and axial without platens, sratio, strain, volumetric, energy, rolling, unbal, contacts, time,
  // wall, sample, porosity, ball, bridges and measure.
  bool recorded_on_parts() const;
  // sample() on every rank at once (a collective call), the sums from `sums`; rank 0 writes the
  // files, and every rank keeps the rows. A failure to write is every rank's.
  void sample_on_parts(const Model& model, double volume, const HistorySums& sums);
  // Whether sample() records a row at this cycle.
  bool due(std::int64_t cycle) const {
    for (const auto& t : tables_)
      if (cycle % t->every == 0) return true;
    return false;
  }
  // Records a row in every table now, whatever the cycle.
  void sample_all(const Model& model, double volume);
  // Each table's count of rows recorded (the marks share_rows takes).
  std::vector<std::size_t> recorded() const;
  // A distributed run whose ranks other than 0 do not hold the whole model current at an output step
  // (cycle/run.cpp): rank 0 samples, and this hands its rows recorded since `marks` to the others,
  // which record them as their own (no file: rank 0 writes those); `marks` then holds the counts.
  // A collective call.
  void share_rows(std::vector<std::size_t>& marks);
  void clear();
  // Takes a table made elsewhere (read_history_csv).
  void adopt(std::unique_ptr<HistoryTable> table) { tables_.push_back(std::move(table)); }
  const std::vector<std::unique_ptr<HistoryTable>>& tables() const { return tables_; }
  // Finds a column by name in any table: (table, column index), or (nullptr, 0).
  std::pair<const HistoryTable*, std::size_t> find_column(const std::string& name) const;

 private:
  void record(HistoryTable& table, const Model& model, double volume);
  // A table's row now (`sums`: from the parts; else the model's own), and its line in the file.
  static std::vector<double> row_of(const HistoryTable& table, const Model& model, double volume,
                                    const HistorySums* sums);
  static void write_row(HistoryTable& table, const std::vector<double>& row, std::int64_t cycle);
  // Adds a recorded row to the table (its window of rows kept).
  static void keep_row(HistoryTable& table, std::vector<double> row);
  // Opens t.file for appending after keeping its rows up to `cycle`; "" or a note.
  static std::string append_to_file(HistoryTable& t, std::int64_t cycle, bool resumed);
  std::vector<std::unique_ptr<HistoryTable>> tables_;
};

// The item string of a measurement sphere (`measure <id> x y z r`, reals in round-trip form, so
// that a saved history measures the same sphere), and the sphere back from it.
std::string measure_item(std::int64_t id, const MeasureSphere& sphere);
MeasureSphere measure_item_sphere(const std::string& item);

// Reads a CSV file written by HIST ... file (a header row, then rows of numbers) as a table whose
// `file` is the path. Throws std::runtime_error naming the file and line of anything malformed.
std::unique_ptr<HistoryTable> read_history_csv(const std::string& path);
// The same file a row at a time, nothing kept (a long `every 1` run's file may hold millions of
// rows): `header` gets the column names, then `row` each row of numbers and the byte offset where
// its line starts. The same checks and messages as read_history_csv. Given `torn`, a last line that
// no newline ends (a row cut short when the disk filled or the run was killed) is not read: `torn`
// is set to the byte it starts at (and left alone where the file ends in a newline).
void scan_history_csv(const std::string& path, const std::function<void(std::vector<std::string>&)>& header,
                      const std::function<void(std::vector<double>&, std::uint64_t offset)>& row,
                      std::uint64_t* torn = nullptr);

}  // namespace trubal
