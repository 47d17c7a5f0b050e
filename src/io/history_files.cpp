// HIST's files: the CSV a table writes as it records, an earlier run's file read back and cut at
// the cycle a run resumes from, and read_history_csv (io/history.hpp).
#include "io/history.hpp"
#include "physics/bridge.hpp"
#include "support/comm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <optional>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "io/atomic_file.hpp"

#include "io/csv.hpp"
#include "model/edit.hpp"
#include "physics/measure.hpp"
#include "physics/measure_sphere.hpp"
#include "physics/sample.hpp"
#include "physics/walls.hpp"


#include "io/history_files.hpp"

namespace trubal {


namespace history_files {

// Writes the header row to a freshly truncated stream; throws naming the file and the reason.
void write_header(std::ofstream& out, const HistoryTable& t) {
  errno = 0;
  for (std::size_t k = 0; k < t.columns.size(); ++k) out << (k ? "," : "") << t.columns[k];
  out << '\n' << std::flush;
  if (!out)
    throw std::runtime_error(fmt::format("cannot write the history file '{}' ({})", t.file,
                                         errno ? std::strerror(errno) : "write failed"));
}

std::string csv_row(const std::vector<double>& row) {
  std::string line;
  for (std::size_t k = 0; k < row.size(); ++k) {
    if (k) line += ',';
    line += csv_real(row[k]);
  }
  line += '\n';
  return line;
}


// The rows of an existing history file (every row kept where `cycle` is the largest), or nullopt
// when there is no such file (or it is empty). Throws for a file that is there but not a history
// (read_history_csv's message).
std::optional<FileRows> existing(const std::string& path, double cycle) {
  std::error_code ec;
  // Only a regular file can hold an earlier run's rows: a device (/dev/full, /dev/null) or a fifo
  // is written to, never read (reading /dev/full never ends).
  if (!std::filesystem::is_regular_file(path, ec) || std::filesystem::file_size(path, ec) == 0 || ec) return std::nullopt;
  FileRows f;
  std::uint64_t torn = std::numeric_limits<std::uint64_t>::max();
  scan_history_csv(
      path, [&](std::vector<std::string>& columns) { f.columns = std::move(columns); },
      [&](std::vector<double>& row, std::uint64_t offset) {
        if (f.dropped == 0 && !(row[0] > cycle)) {
          if (f.kept++ == 0) f.first_kept = row[0];
          f.last_kept = row[0];
          f.tail.push_back(std::move(row));
          if (f.tail.size() > HistoryTable::kWindow) f.tail.pop_front();
          return;
        }
        if (f.dropped++ == 0) { f.first_dropped = row[0]; f.cut = offset; }
        f.last_dropped = row[0];
      },
      &torn);
  if (torn != std::numeric_limits<std::uint64_t>::max()) {
    f.torn = true;
    if (f.dropped == 0) f.cut = torn;
  }
  return f;
}

}  // namespace history_files

using namespace history_files;

std::string History::append_to_file(HistoryTable& t, std::int64_t cycle, bool resumed) {
  check_replaceable(t.file, true);   // (written in place: a link would be followed, a FIFO would block)
  std::optional<FileRows> old;
  std::string why_afresh;
  try {
    old = existing(t.file, static_cast<double>(cycle));
    if (!old) why_afresh = "it was not there";
  } catch (const std::runtime_error& e) {
    if (!resumed) throw std::runtime_error(fmt::format("cannot append to '{}': {}", t.file, e.what()));
    why_afresh = e.what();
  }
  if (old && old->columns != t.columns) {
    if (!resumed)
      throw std::runtime_error(fmt::format("cannot append to '{}': its columns are {}, not this history's {} (give "
                                           "`new` to replace it, or another file)",
                                           t.file, fmt::join(old->columns, ","), fmt::join(t.columns, ",")));
    why_afresh = fmt::format("its columns were {}", fmt::join(old->columns, ","));
    old.reset();
  }
  if (!old) {
    std::string note;
    // Started afresh: the header, then (after RESTART) the rows the save kept in memory.
    t.out = std::make_unique<std::ofstream>(t.file, std::ios::trunc);
    if (!*t.out) throw std::runtime_error(fmt::format("cannot write the history file '{}' ({})", t.file, std::strerror(errno)));
    write_header(*t.out, t);
    for (const auto& row : t.rows) *t.out << csv_row(row);
    *t.out << std::flush;
    if (resumed)
      note = fmt::format("{}: started afresh ({}) with the {} rows the save kept{}", t.file, why_afresh, t.rows.size(),
                         t.recorded > t.rows.size() ? fmt::format("; the {} before them are lost", t.recorded - t.rows.size())
                                                    : std::string());
    t.recorded = t.rows.size();
    return note;
  }
  // Keep the rows up to the present cycle; later ones are of a part of the run that is not this one.
  // The file is cut where they start, its bytes before that copied as they are (through a
  // temporary and a rename: a failure leaves the file whole).
  std::string dropped_note;
  if (old->dropped > 0 || old->torn) {
    const std::uint64_t cut = old->cut;
    write_file_atomically(t.file, [&](std::ostream& to) {
      std::ifstream from(t.file, std::ios::binary);
      std::vector<char> buffer(1 << 16);
      for (std::uint64_t left = cut; left > 0;) {
        const auto n = static_cast<std::streamsize>(std::min<std::uint64_t>(left, buffer.size()));
        if (!from.read(buffer.data(), n))
          throw std::runtime_error(fmt::format("cannot read the history file '{}' again", t.file));
        to.write(buffer.data(), n);
        left -= static_cast<std::uint64_t>(n);
      }
    });
    if (old->dropped > 0)
      dropped_note = fmt::format("dropped its {} rows after cycle {}{}, of a later part of the run that wrote it",
                                 old->dropped, cycle, old->dropped_cycles());
    if (old->torn)
      dropped_note += fmt::format("{}dropped its last row, cut short where the writing stopped",
                                  dropped_note.empty() ? "" : "; ");
  }
  std::string note;
  if (!resumed)
    note = fmt::format("{}: appending to its {} rows{}{}", t.file, old->kept, old->kept_cycles(),
                       dropped_note.empty() ? "" : "; " + dropped_note);
  else if (!dropped_note.empty())
    note = fmt::format("{}: {}", t.file, dropped_note);
  // Rows the save kept that the file lacks (the file stops short of the save's cycle: its last
  // rows were torn or never written) are written again from the save.
  std::vector<std::vector<double>> refill;
  if (resumed)
    for (auto& row : t.rows)
      if (!row.empty() && (old->kept == 0 || row[0] > old->last_kept) && !(row[0] > static_cast<double>(cycle)))
        refill.push_back(std::move(row));
  t.recorded = old->kept;
  t.rows.assign(std::make_move_iterator(old->tail.begin()), std::make_move_iterator(old->tail.end()));
  t.out = std::make_unique<std::ofstream>(t.file, std::ios::app);
  if (!*t.out) throw std::runtime_error(fmt::format("cannot write the history file '{}' ({})", t.file, std::strerror(errno)));
  if (!refill.empty()) {
    errno = 0;
    for (const auto& row : refill) *t.out << csv_row(row);
    *t.out << std::flush;
    if (!*t.out)
      throw std::runtime_error(fmt::format("cannot write the history file '{}' ({})", t.file,
                                           errno ? std::strerror(errno) : "write failed"));
    note += fmt::format("{}wrote {} rows{} again from the save", note.empty() ? t.file + ": " : "; ", refill.size(),
                        FileRows::span(refill.front()[0], refill.back()[0]));
    for (auto& row : refill) keep_row(t, std::move(row));
  }
  return note;
}

std::vector<std::string> History::resume_files(std::int64_t cycle) {
  std::vector<std::string> notes;
  if (!comm::root()) return notes;
  for (auto& t : tables_) {
    if (t->file.empty()) continue;
    std::string note = append_to_file(*t, cycle, true);
    if (!note.empty()) notes.push_back(std::move(note));
  }
  return notes;
}

void scan_history_csv(const std::string& path, const std::function<void(std::vector<std::string>&)>& header,
                      const std::function<void(std::vector<double>&, std::uint64_t offset)>& row_read,
                      std::uint64_t* torn) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error(fmt::format("the history file '{}' is not a regular file", path));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("cannot open the history file '{}'", path));
  auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::size_t start = 0;
    for (;;) {
      auto comma = line.find(',', start);
      cells.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
      if (comma == std::string::npos) return cells;
      start = comma + 1;
    }
  };
  std::string line;
  int line_no = 0;
  std::size_t columns = 0;
  std::uint64_t offset = 0, next = 0;   // where this line starts, and the next
  std::vector<double> row;
  while (std::getline(in, line)) {
    ++line_no;
    offset = next;
    next += line.size() + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    if (torn && columns > 0 && in.eof()) {   // no newline after it: the writer stopped inside this row
      *torn = offset;
      break;
    }
    auto cells = split(line);
    if (columns == 0) {
      columns = cells.size();
      header(cells);
      continue;
    }
    if (cells.size() != columns)
      throw std::runtime_error(fmt::format("{}:{}: {} values where the header has {} columns", path, line_no,
                                           cells.size(), columns));
    row.clear();
    for (const auto& c : cells) {
      char* end = nullptr;
      double v = std::strtod(c.c_str(), &end);
      if (c.empty() || end != c.c_str() + c.size())
        throw std::runtime_error(fmt::format("{}:{}: '{}' is not a number", path, line_no, c));
      row.push_back(v);
    }
    row_read(row, offset);
  }
  if (in.bad()) throw std::runtime_error(fmt::format("cannot read the history file '{}'", path));
  if (columns == 0) throw std::runtime_error(fmt::format("'{}' is empty: no header row", path));
}

std::unique_ptr<HistoryTable> read_history_csv(const std::string& path) {
  auto table = std::make_unique<HistoryTable>();
  table->file = path;
  scan_history_csv(
      path, [&](std::vector<std::string>& columns) { table->columns = std::move(columns); },
      [&](std::vector<double>& row, std::uint64_t) { table->rows.push_back(row); });
  table->recorded = table->rows.size();
  return table;
}

}  // namespace trubal
