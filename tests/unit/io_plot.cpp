// PLOT: a PNG of the expected size (read from its IHDR chunk), SVG by extension, and errors that
// name what is wrong. The tests that draw are skipped where gnuplot is not installed.
#include <cstdlib>

#include "io/plot.hpp"
#include "io_support.hpp"
#include "skip.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// A PNG starts with its 8-byte signature, then the IHDR chunk: length 13, "IHDR", width, height
// (big-endian 32-bit), bit depth, colour type, ...
struct PngSize {
  bool valid = false;
  std::uint32_t width = 0, height = 0;
};

PngSize png_size(const std::string& bytes) {
  static const std::string signature = "\x89PNG\r\n\x1a\n";
  PngSize s;
  if (bytes.size() < 33 || bytes.compare(0, 8, signature) != 0 || bytes.compare(12, 4, "IHDR") != 0) return s;
  auto be32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 4; ++k) v = v << 8 | static_cast<unsigned char>(bytes[at + k]);
    return v;
  };
  s.valid = be32(8) == 13 && bytes.find("IEND") != std::string::npos;
  s.width = be32(16);
  s.height = be32(20);
  return s;
}

const std::string kRecorded = std::string(kPressedRow) + "hist energy unbal every 2\nhist contacts every 5\ncycle 40\n";

const char* const kNoGnuplot = "gnuplot is not installed (Debian: gnuplot-nox)";

}  // namespace

TEST_CASE("io_plot: several series, a reference line and a title make a PNG of the asked size", "[io][plot][system]") {
  if (!on_path("gnuplot")) TRUBAL_SKIP(kNoGnuplot);
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck(kRecorded + "plot ke strain_energy vs time file e.png line y 0.05 \"theory\" title \"Energy\" size 640 480\n"));
  INFO(h.err.str());
  const PngSize s = png_size(slurp(dir.path() / "e.png"));
  CHECK(s.valid);
  CHECK(s.width == 640);
  CHECK(s.height == 480);
  CHECK_THAT(h.out.str(), Catch::Contains("plotted ke, strain_energy against time to e.png"));
  // The default size, the default x (cycle), and the default file name.
  REQUIRE(h.deck("plot coordination\n"));
  const PngSize d = png_size(slurp(dir.path() / "coordination_vs_cycle.png"));
  CHECK(d.valid);
  CHECK(d.width == 800);
  CHECK(d.height == 600);
  for (const auto& e : fs::directory_iterator(dir.path())) CHECK(e.path().string().find(".tmp") == std::string::npos);
}

TEST_CASE("io_plot: an .svg file name gives SVG", "[io][plot][system]") {
  if (!on_path("gnuplot")) TRUBAL_SKIP(kNoGnuplot);
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck(kRecorded + "plot unbal vs cycle file u.SVG line 0.5\n"));
  INFO(h.err.str());
  const std::string svg = slurp(dir.path() / "u.SVG");
  CHECK_THAT(svg, Catch::Contains("<svg"));
  CHECK_THAT(svg, Catch::Contains("</svg>"));
}

TEST_CASE("io_plot: unknown columns, columns of different HISTs, other formats and a missing gnuplot", "[io][plot][system]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness none;
  CHECK_FALSE(none.deck(std::string(kPressedRow) + "plot ke\n"));
  CHECK_THAT(none.first_error_line(), Catch::Contains("nothing is recorded yet"));

  Harness h;
  REQUIRE(h.deck(kRecorded));
  CHECK_FALSE(h.deck("plot ratio vs axial file r.png\n"));
  CHECK_THAT(h.first_error_line(),
             Catch::Contains("unknown history column 'ratio' (recorded: cycle, time, ke, strain_energy, friction_work, "
                             "damping_work, boundary_work, potential, unbal, contacts, sliding, coordination)"));
  Harness h2;
  REQUIRE(h2.deck(kRecorded));
  CHECK_FALSE(h2.deck("plot ke vs coordination\n"));
  CHECK_THAT(h2.first_error_line(), Catch::Contains("recorded by different HIST commands"));
  Harness h3;
  REQUIRE(h3.deck(kRecorded));
  CHECK_FALSE(h3.deck("plot ke file k.jpg\n"));
  CHECK_THAT(h3.first_error_line(), Catch::Contains(".png or .svg"));
  CHECK_FALSE(fs::exists(dir.path() / "k.jpg"));

  Harness h4;
  REQUIRE(h4.deck(kRecorded));
  const std::string saved = std::getenv("PATH") ? std::getenv("PATH") : "";
  ::setenv("PATH", (dir.path() / "empty").c_str(), 1);
  const bool ok = h4.deck("plot ke file k.png\n");
  ::setenv("PATH", saved.c_str(), 1);
  CHECK_FALSE(ok);
  CHECK_THAT(h4.first_error_line(), Catch::Contains("PLOT needs gnuplot, which is not on PATH"));
  CHECK_FALSE(fs::exists(dir.path() / "k.png"));
}

TEST_CASE("io_plot: PLOT ... from draws the histories of other runs from their CSV files", "[io][plot][system]") {
  if (!on_path("gnuplot")) TRUBAL_SKIP(kNoGnuplot);
  TempDir dir;
  WorkingDir wd(dir.path());
  {
    Harness a;   // two runs of different length, each writing its history file
    REQUIRE(a.deck(std::string(kPressedRow) + "hist energy every 2 file one.csv\ncycle 20\n"));
    Harness b;
    REQUIRE(b.deck(std::string(kPressedRow) + "hist energy every 4 file two.csv\ncycle 40\n"));
  }
  Harness h;   // no model at all: the files are enough
  REQUIRE(h.deck("plot ke vs time from one.csv two.csv file both.png size 400 300\n"));
  INFO(h.err.str());
  const PngSize s = png_size(slurp(dir.path() / "both.png"));
  CHECK(s.valid);
  CHECK(s.width == 400);
  // A column one file lacks, and a malformed file, are named with file and line.
  dir.write("bad.csv", "cycle,time,ke\n1,0.1,2\n2,0.2,x\n");
  CHECK_FALSE(h.deck("plot ke vs time from one.csv bad.csv file b.png\n", "p.dat"));
  CHECK_THAT(h.err.str(), Catch::Contains("bad.csv:3: 'x' is not a number"));
  CHECK_FALSE(h.deck("plot contacts vs time from one.csv file c.png\n", "p.dat"));
  CHECK_THAT(h.err.str(), Catch::Contains("unknown history column 'contacts'"));
}

TEST_CASE("plot: a history written to a file keeps a window in memory, and PLOT and the file have every row", "[io][hard][system]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  // 25,000 rows at every 1: more than two windows of 10,000.
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e5 dens 1000\nball 0 0 0 0.1\ninit xvel 1e-3\n"
                 "hist time every 1 file h.csv\ncycle 25000\n"));
  const auto& table = *h.session.history().tables().at(0);
  CHECK(table.recorded == 25000);
  CHECK(table.rows.size() < 2 * HistoryTable::kWindow);
  CHECK(table.rows.size() >= HistoryTable::kWindow);
  CHECK(table.rows.back()[0] == 25000);                        // the window is the last rows
  CHECK(lines_of(slurp(dir.path() / "h.csv")).size() == 25001);   // the header and every row
  REQUIRE(h.deck("print history\n"));
  CHECK_THAT(h.out.str(), Catch::Contains("25000 rows (the last"));
}

TEST_CASE("plot: a history longer than its window in memory is drawn from its file", "[io][plot][system]") {
  if (!on_path("gnuplot")) TRUBAL_SKIP(kNoGnuplot);
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e5 dens 1000\nball 0 0 0 0.1\ninit xvel 1e-3\n"
                 "hist time every 1 file h.csv\ncycle 25000\n"));
  REQUIRE(h.session.history().tables().at(0)->rows.size() < 25000);   // rows have left the window
  REQUIRE(h.deck("plot time vs cycle file t.png\n"));
  CHECK(fs::file_size(dir.path() / "t.png") > 0);
}

TEST_CASE("plot: axis labels name the quantity, or what xlabel and ylabel say", "[io]") {
  CHECK(column_label("e33") == "axial strain e33 (compression +)");
  CHECK(column_label("evol") == "volumetric strain (compression +)");
  CHECK(column_label("w2_stress") == "wall 2 stress (compression +)");
  CHECK(column_label("w12_fz") == "wall 12 force z");
  CHECK(column_label("made_up") == "made_up");
}

TEST_CASE("plot: xlabel, ylabel and title are drawn", "[io][plot][system]") {
  if (!on_path("gnuplot")) TRUBAL_SKIP(kNoGnuplot);
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e5 dens 1000\nball 0 0 0 0.1\ninit xvel 1e-3\n"
                 "hist energy every 10\ncycle 100\n"
                 "plot ke vs time file k.png xlabel \"t (s)\" ylabel \"E (J)\" title \"kinetic\"\n"));
  CHECK(fs::file_size(dir.path() / "k.png") > 0);
}
