#include "io/plot.hpp"
#include "support/comm.hpp"

#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include <fmt/format.h>

#include "io/csv.hpp"

extern char** environ;

namespace trubal {
namespace {

namespace fs = std::filesystem;

// A gnuplot single-quoted string: nothing is special inside (no backquote substitution) but the
// quote, which is doubled, and a line break, which would end the command: control characters
// become spaces.
std::string quoted(const std::string& text) {
  std::string q = "'";
  for (char c : text) q += c == '\'' ? "''" : std::string(1, static_cast<unsigned char>(c) < 0x20 ? ' ' : c);
  return q + "'";
}

// A file name as an error shows it: control characters as \xNN.
std::string printable_name(const std::string& name) {
  std::string s;
  for (char c : name)
    s += static_cast<unsigned char>(c) < 0x20 ? fmt::format("\\x{:02x}", static_cast<unsigned char>(c)) : std::string(1, c);
  return s;
}

std::string join(const std::vector<std::string>& words) {
  std::string s;
  for (const auto& w : words) s += (s.empty() ? "" : ", ") + w;
  return s;
}

// The table recording both columns (cycle and time are in every table).
const HistoryTable* table_with(const History& history, const std::string& x, const std::string& y) {
  for (const auto& t : history.tables()) {
    const auto& c = t->columns;
    if (std::find(c.begin(), c.end(), x) != c.end() && std::find(c.begin(), c.end(), y) != c.end()) return t.get();
  }
  return nullptr;
}

std::size_t column_index(const HistoryTable& t, const std::string& name) {
  return static_cast<std::size_t>(std::find(t.columns.begin(), t.columns.end(), name) - t.columns.begin());
}

class TempFolder {
 public:
  TempFolder() {
    std::string pattern = (fs::temp_directory_path() / "trubal-plot-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("PLOT: cannot make a temporary folder");
    path_ = pattern;
  }
  ~TempFolder() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// Runs `gnuplot script` with its output and errors in `log`; returns the exit status (-1: no start).
int run_gnuplot(const std::string& program, const fs::path& script, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::string arg0 = program, arg1 = script.string();
  char* argv[] = {arg0.data(), arg1.data(), nullptr};
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, program.c_str(), &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -1;
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

std::vector<std::string> known_columns(const History& history) {
  std::vector<std::string> names;
  for (const auto& t : history.tables())
    for (const auto& c : t->columns)
      if (std::find(names.begin(), names.end(), c) == names.end()) names.push_back(c);
  return names;
}

std::string find_gnuplot() {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    std::size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    std::string dir = dirs.substr(start, end - start);
    fs::path candidate = fs::path(dir.empty() ? "." : dir) / "gnuplot";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    start = end + 1;
  }
  return "";
}

std::string column_label(const std::string& c) {
  static const std::pair<const char*, const char*> known[] = {
      {"cycle", "cycle"}, {"time", "time"},
      {"p", "mean stress p (compression +)"}, {"q", "deviator stress q (sigma1 - sigma3)"},
      {"ea", "axial strain (compression +)"}, {"ev", "volumetric strain (compression +)"},
      {"sig1", "axial stress sigma1 (compression +)"}, {"sig3", "confining stress sigma3 (compression +)"},
      {"s11", "stress s11 (compression +)"}, {"s22", "stress s22 (compression +)"}, {"s33", "stress s33 (compression +)"},
      {"s12", "stress s12"}, {"s13", "stress s13"}, {"s23", "stress s23"},
      {"e11", "strain e11 (compression +)"}, {"e22", "strain e22 (compression +)"}, {"e33", "axial strain e33 (compression +)"},
      {"e12", "shear strain e12"}, {"e13", "shear strain e13"}, {"e23", "shear strain e23"},
      {"evol", "volumetric strain (compression +)"}, {"ratio", "stress ratio"}, {"sratio", "stress ratio sigma1/sigma3"},
      {"axial", "axial strain"}, {"platen", "platen force"}, {"ke", "kinetic energy"},
      {"strain_energy", "strain energy"}, {"friction_work", "friction work"}, {"damping_work", "damping work"}, {"rolling_work", "rolling work"}, {"capillary_work", "capillary work"}, {"bridges", "capillary bridges"},
      {"boundary_work", "boundary work"}, {"unbal", "unbalanced-force ratio"}, {"contacts", "contacts"},
      {"sliding", "sliding fraction"}, {"coordination", "coordination number"}};
  for (const auto& [name, label] : known)
    if (c == name) return label;
  // wN_fx ...: wall N's
  if (c.size() > 2 && c[0] == 'w' && std::isdigit(static_cast<unsigned char>(c[1]))) {
    const auto cut = c.find('_');
    if (cut != std::string::npos) {
      const std::string id = c.substr(1, cut - 1), what = c.substr(cut + 1);
      if (what == "stress") return "wall " + id + " stress (compression +)";
      if (what == "pos") return "wall " + id + " position";
      return "wall " + id + " force " + what.substr(1);
    }
  }
  return c;
}

void render_plot(const History& history, const PlotRequest& request) {
  if (!comm::root()) return;   // a distributed run's pictures are rank 0's to draw
  std::string ext = fs::path(request.file).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".png" && ext != ".svg")
    throw std::runtime_error(fmt::format("PLOT writes .png or .svg files, not '{}'", request.file));
  // gnuplot never sees this name (it draws into our temporary folder), but one that gnuplot would
  // read as a command, or that holds a line break, is a mistake or an attack: refused.
  if (request.file[0] == '|' || request.file[0] == '<' ||
      std::any_of(request.file.begin(), request.file.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20; }))
    throw std::runtime_error(fmt::format(
        "PLOT: will not write '{}': a file name may not start with '|' or '<' or hold a control character",
        printable_name(request.file)));
  if (request.y.empty()) throw std::runtime_error("PLOT: name at least one history column to draw");
  const auto known = known_columns(history);
  if (known.empty()) throw std::runtime_error("PLOT: nothing is recorded yet (HIST what... first, then CYCLE)");
  // One series per column asked for; with several tables read from files (PLOT ... from), one
  // per file and column, each named after its file.
  struct Series {
    const HistoryTable* table;
    std::string y, title;
  };
  std::vector<Series> series;
  for (const auto& y : request.y) {
    for (const auto& name : {y, request.x})
      if (std::find(known.begin(), known.end(), name) == known.end())
        throw std::runtime_error(fmt::format("PLOT: unknown history column '{}' (recorded: {})", name, join(known)));
    if (request.every_table) {
      for (const auto& t : history.tables()) {
        if (column_index(*t, y) == t->columns.size() ||
            column_index(*t, request.x) == t->columns.size())
          throw std::runtime_error(fmt::format("PLOT: '{}' has no column '{}' or '{}'", t->file, y, request.x));
        std::string stem = fs::path(t->file).stem().string();
        series.push_back({t.get(), y, request.y.size() == 1 ? stem : stem + " " + y});
      }
      continue;
    }
    const HistoryTable* t = table_with(history, request.x, y);
    if (!t)
      throw std::runtime_error(fmt::format(
          "PLOT: '{}' and '{}' are recorded by different HIST commands; record them in one to plot one against "
          "the other",
          y, request.x));
    series.push_back({t, y, y});
  }
  for (const auto& s : series)
    if (s.table->rows.empty())
      throw std::runtime_error(fmt::format("PLOT: no rows of '{}' are recorded yet (CYCLE first)", s.y));
  const std::string gnuplot = find_gnuplot();
  if (gnuplot.empty())
    throw std::runtime_error("PLOT needs gnuplot, which is not on PATH (Debian: apt-get install gnuplot-nox)");

  // A table whose window has let rows go is drawn from its file, which holds them all.
  std::vector<std::unique_ptr<HistoryTable>> reread;
  for (auto& s : series)
    if (!s.table->file.empty() && s.table->recorded > s.table->rows.size()) {
      reread.push_back(read_history_csv(s.table->file));
      s.table = reread.back().get();
    }
  TempFolder temp;
  std::string plots;
  for (std::size_t s = 0; s < series.size(); ++s) {
    const HistoryTable& t = *series[s].table;
    const std::size_t xi = column_index(t, request.x), yi = column_index(t, series[s].y);
    const fs::path data = temp.path() / fmt::format("series{}.dat", s);
    std::ofstream f(data);
    for (const auto& row : t.rows) f << csv_real(row[xi]) << ' ' << csv_real(row[yi]) << '\n';
    if (!f) throw std::runtime_error("PLOT: cannot write its data file in the temporary folder");
    plots += fmt::format("{}{} using 1:2 with {} lw 2 title {}", plots.empty() ? "" : ", \\\n     ",
                         trubal::quoted(data.string()), t.rows.size() > 1 ? "lines" : "points", trubal::quoted(series[s].title));
  }
  for (const auto& line : request.lines)
    plots += fmt::format(", \\\n     {} with lines dashtype 2 lw 1.5 lc rgb 'black' title {}", csv_real(line.y),
                         line.label.empty() ? std::string("notitle") : quoted(line.label));
  // notitle is a keyword, not a string: drop the `title` before it.
  for (std::size_t at; (at = plots.find("title notitle")) != std::string::npos;) plots.replace(at, 13, "notitle");

  check_replaceable(request.file);
  // gnuplot draws into our temporary folder, under a name we made: the file named in the deck is
  // never handed to it (`set output '|cmd'` runs cmd). The picture is then copied beside its
  // target and renamed over it (write_file_atomically).
  const std::string partial = (temp.path() / ("picture" + ext)).string();
  std::string script;
  if (ext == ".png")
    script += fmt::format(
        "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {{ set terminal pngcairo size {0},{1} noenhanced }} "
        "else {{ set terminal png size {0},{1} noenhanced }}\n",
        request.width, request.height);
  else
    script += fmt::format("set terminal svg size {},{} noenhanced background rgb 'white'\n", request.width,
                          request.height);
  script += fmt::format("set output {}\n", quoted(partial));
  if (!request.title.empty()) script += fmt::format("set title {}\n", quoted(request.title));
  // Axis labels name the quantity unless given; the legend sits below the plot, clear of the data.
  std::string ylabel = request.ylabel;
  if (ylabel.empty()) {
    for (const auto& y : request.y) ylabel += (ylabel.empty() ? "" : ", ") + column_label(y);
  }
  script += fmt::format("set xlabel {}\nset ylabel {}\nset grid\nset key below\n",
                        trubal::quoted(request.xlabel.empty() ? column_label(request.x) : request.xlabel),
                        trubal::quoted(ylabel));
  for (const auto& line : request.lines)
    if (!line.label.empty())
      script += fmt::format("set label {} at graph 0.99, first {} right offset 0,0.7\n", quoted(line.label),
                            csv_real(line.y));
  script += "plot " + plots + "\nset output\n";
  const fs::path script_path = temp.path() / "plot.gp", log = temp.path() / "gnuplot.log";
  {
    std::ofstream f(script_path);
    f << script;
  }
  const int status = run_gnuplot(gnuplot, script_path, log);
  std::error_code ec;
  if (status != 0 || !fs::exists(partial, ec) || fs::file_size(partial, ec) == 0) {
    fs::remove(partial, ec);
    std::string said = slurp(log);
    while (!said.empty() && (said.back() == '\n' || said.back() == ' ')) said.pop_back();
    throw std::runtime_error(fmt::format("PLOT: gnuplot ({}) failed to draw '{}'{}{}", gnuplot, request.file,
                                         said.empty() ? "" : ": ", said));
  }
  try {
    write_file_atomically(request.file, slurp(partial));
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("PLOT: {}", e.what()));
  }
}

}  // namespace trubal
