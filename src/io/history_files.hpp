// The helpers HIST's recording and its files share (io/history.cpp, io/history_files.cpp).
#pragma once

#include <cstdint>
#include <deque>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "io/csv.hpp"
#include "io/history.hpp"

namespace trubal::history_files {

// Writes the header row to a freshly truncated stream; throws naming the file and the reason.
void write_header(std::ofstream& out, const HistoryTable& t);
// One row as a CSV line, its numbers written to read back to the same doubles.
std::string csv_row(const std::vector<double>& row);

// An earlier run's history file, read a row at a time: its columns, and about its rows, split at the
// first one past `cycle` (that row and all after it are of a part of the run that is not this one):
// the count before it, their first and last cycles and the last kWindow of them; the count from it
// on, their first and last cycles, and the byte its line starts at.
struct FileRows {
  std::vector<std::string> columns;
  std::size_t kept = 0, dropped = 0;
  double first_kept = 0, last_kept = 0, first_dropped = 0, last_dropped = 0;
  std::deque<std::vector<double>> tail;   // the last kWindow rows kept
  std::uint64_t cut = 0;                  // where the first row dropped starts
  bool torn = false;                      // the file ends inside a row (cut at `cut` with the rest)

  std::string kept_cycles() const { return kept ? span(first_kept, last_kept) : std::string(); }
  std::string dropped_cycles() const { return dropped ? span(first_dropped, last_dropped) : std::string(); }
  static std::string span(double a, double b) { return fmt::format(" (cycles {} to {})", csv_real(a), csv_real(b)); }
};

// The rows of an existing history file (every row kept where `cycle` is the largest), or nullopt
// when there is no such file (or it is empty). Throws for a file that is there but not a history
// (read_history_csv's message).
std::optional<FileRows> existing(const std::string& path, double cycle = std::numeric_limits<double>::infinity());

}  // namespace trubal::history_files
