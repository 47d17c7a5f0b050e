// Histories across SAVE and RESTART: SAVE keeps them, RESTART resumes them and appends
// to their files; HIST ... file says what it does to a file that is there (new, append).
#include <catch2/catch.hpp>

#include <cstring>
#include <fstream>

#include <fmt/format.h>

#include "io/save.hpp"
#include "io_support.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

const std::string kScene = std::string(kPressedRow) + "grav 0 0 -9.81\n";

// The data rows of a history file (its lines less the header).
std::size_t data_rows(const std::string& csv) {
  const auto lines = lines_of(csv);
  return lines.empty() ? 0 : lines.size() - 1;
}

// The file of a history every 5 cycles of an unbroken 80-cycle run, made in `dir` (u.csv).
std::string unbroken_history(const TempDir& dir) {
  Harness h;
  REQUIRE(h.deck(kScene + "hist stress energy every 5 file u.csv\ncycle 80\n"));
  return slurp(dir.path() / "u.csv");
}

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f << text;
  REQUIRE(f.good());
}

}  // namespace

TEST_CASE("io history: RESTART resumes the saved histories and their files, byte for byte the unbroken run",
          "[io][history][restart]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  const std::string unbroken = unbroken_history(dir);
  REQUIRE(data_rows(unbroken) == 16);
  Harness first;
  // A run that saves at 50 and goes on to 80, so that h.csv has 6 rows past the save.
  REQUIRE(first.deck(kScene + "hist stress energy every 5 file h.csv\ncycle 50\nsave s.sav\ncycle 30\n"));
  REQUIRE(data_rows(slurp(dir.path() / "h.csv")) == 16);
  Harness second;   // another session, as a second deck would be
  REQUIRE(second.deck("restart s.sav\n"));
  INFO(second.out.str() << second.err.str());
  // The rows of the later part of the first run are dropped, and RESTART says so.
  CHECK_THAT(second.err.str(), Catch::Contains("h.csv: dropped its 6 rows after cycle 50"));
  CHECK(data_rows(slurp(dir.path() / "h.csv")) == 10);
  REQUIRE(second.session.history().tables().size() == 1);
  CHECK(second.session.history().tables()[0]->recorded == 10);
  second.out.str("");
  REQUIRE(second.deck("print history\n"));
  CHECK_THAT(second.out.str(), Catch::Contains("history every 5 cycles -> h.csv: 10 rows"));
  // The deck repeats its HIST: that history goes on rather than a second one truncating the file.
  second.out.str("");
  REQUIRE(second.deck("hist stress energy every 5 file h.csv\ncycle 30\n"));
  CHECK_THAT(second.out.str(), Catch::Contains("going on: 10 rows so far"));
  CHECK(second.session.history().tables().size() == 1);
  // Every row, the header included, is the unbroken run's: same cycles, same bits.
  std::string resumed = slurp(dir.path() / "h.csv");
  CHECK(resumed == unbroken);
}

TEST_CASE("io history: a row torn when the writing stopped costs that row alone, and rows the save holds are "
          "written again", "[io][history][restart]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  const std::string unbroken = unbroken_history(dir);
  // Cuts h.csv inside its row `from_end` rows before the last (half of that row's line is left,
  // no newline after it), as a full disk or a kill leaves it.
  auto tear = [&](std::size_t from_end) {
    std::string text = slurp(dir.path() / "h.csv");
    auto end = text.size() - 1;   // the last newline
    for (std::size_t k = 0; k < from_end; ++k) end = text.rfind('\n', end - 1);
    const auto start = text.rfind('\n', end - 1) + 1;
    write_text(dir.path() / "h.csv", text.substr(0, start + (end - start) / 2));
  };
  SECTION("the torn row is past the save: the rows before it are kept, the later part dropped") {
    Harness first;
    REQUIRE(first.deck(kScene + "hist stress energy every 5 file h.csv\ncycle 50\nsave s.sav\ncycle 30\n"));
    tear(0);   // the row of cycle 80
    Harness second;
    REQUIRE(second.deck("restart s.sav\n"));
    INFO(second.err.str());
    CHECK_THAT(second.err.str(), Catch::Contains("h.csv: dropped its 5 rows after cycle 50 (cycles 55 to 75), of a "
                                                 "later part of the run that wrote it; dropped its last row, cut short where the writing stopped"));
    CHECK_THAT(second.err.str(), !Catch::Contains("afresh"));
    CHECK(data_rows(slurp(dir.path() / "h.csv")) == 10);
    REQUIRE(second.deck("cycle 30\n"));
    CHECK(slurp(dir.path() / "h.csv") == unbroken);
  }
  SECTION("the torn row is before the save's cycle: it and the rows after it come back from the save") {
    Harness first;
    REQUIRE(first.deck(kScene + "hist stress energy every 5 file h.csv\ncycle 50\nsave s.sav\n"));
    tear(1);   // the row of cycle 45; the row of cycle 50 is gone with it
    Harness second;
    REQUIRE(second.deck("restart s.sav\n"));
    INFO(second.err.str());
    CHECK_THAT(second.err.str(), Catch::Contains("h.csv: dropped its last row, cut short where the writing stopped; "
                                                 "wrote 2 rows (cycles 45 to 50) again from the save"));
    CHECK(data_rows(slurp(dir.path() / "h.csv")) == 10);
    REQUIRE(second.session.history().tables().size() == 1);
    CHECK(second.session.history().tables()[0]->recorded == 10);
    REQUIRE(second.deck("cycle 30\n"));
    CHECK(slurp(dir.path() / "h.csv") == unbroken);
  }
  SECTION("HIST ... append to a file that ends in a torn row drops that row and appends after the rest") {
    Harness first;
    REQUIRE(first.deck(kScene + "hist stress energy every 5 file h.csv\ncycle 20\n"));
    tear(0);
    Harness second;
    REQUIRE(second.deck(kScene + "cycle 20\nhist stress energy every 5 file h.csv append\n"));
    CHECK_THAT(second.err.str(), Catch::Contains("appending to its 3 rows (cycles 5 to 15); dropped its last row"));
    CHECK(data_rows(slurp(dir.path() / "h.csv")) == 3);
  }
}

TEST_CASE("io history: a history in memory only keeps its rows through SAVE and RESTART", "[io][history][restart]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness first;
  REQUIRE(first.deck(kScene + "hist energy unbal every 10\ncycle 40\nsave s.sav\n"));
  Harness second;
  REQUIRE(second.deck("restart s.sav\n"));
  const auto& a = first.session.history().tables();
  const auto& b = second.session.history().tables();
  REQUIRE(b.size() == 1);
  CHECK(b[0]->columns == a[0]->columns);
  CHECK(b[0]->every == 10);
  REQUIRE(b[0]->rows.size() == 4);
  CHECK(b[0]->rows == a[0]->rows);   // the same doubles: the save holds their bits
  REQUIRE(second.deck("cycle 20\n"));
  CHECK(b[0]->rows.size() == 6);
  CHECK(b[0]->rows.back()[0] == 60);
}

TEST_CASE("io history: HIST ... file on a file of an earlier run replaces it (saying so), or appends",
          "[io][history]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  {
    Harness h;
    REQUIRE(h.deck(kScene + "hist stress every 5 file h.csv\ncycle 40\nsave s.sav\n"));
  }
  REQUIRE(data_rows(slurp(dir.path() / "h.csv")) == 8);
  SECTION("the default replaces the rows and says how many") {
    Harness h;
    REQUIRE(h.deck(kScene + "hist stress every 5 file h.csv\n"));
    CHECK_THAT(h.err.str(), Catch::Contains("h.csv: replaced its 8 rows (cycles 5 to 40) of an earlier run"));
    CHECK(data_rows(slurp(dir.path() / "h.csv")) == 0);
  }
  SECTION("`new` replaces them without a word") {
    Harness h;
    REQUIRE(h.deck(kScene + "hist stress every 5 file h.csv new\n"));
    CHECK(h.err.str().empty());
    CHECK(data_rows(slurp(dir.path() / "h.csv")) == 0);
  }
  SECTION("`append` keeps the rows up to the present cycle and adds to them") {
    Harness h;
    // From the save at 40 the file's rows are all kept; from a fresh model (cycle 0) none would be.
    REQUIRE(h.deck("restart s.sav\nhist reset\nhist stress every 5 file h.csv append\ncycle 10\n"));
    CHECK_THAT(h.err.str(), Catch::Contains("h.csv: appending to its 8 rows (cycles 5 to 40)"));
    const auto lines = lines_of(slurp(dir.path() / "h.csv"));
    REQUIRE(lines.size() == 11);
    CHECK(lines[0] == "cycle,time,s11,s22,s33,s12,s13,s23");
    CHECK(lines[10].rfind("50,", 0) == 0);
    CHECK(h.session.history().tables()[0]->recorded == 10);
  }
  SECTION("`append` from an earlier cycle drops the rows past it") {
    Harness h;
    REQUIRE(h.deck(kScene + "cycle 20\nhist stress every 5 file h.csv append\n"));
    CHECK_THAT(h.err.str(), Catch::Contains("appending to its 4 rows (cycles 5 to 20); dropped its 4 rows after cycle 20"));
    CHECK(data_rows(slurp(dir.path() / "h.csv")) == 4);
  }
  SECTION("`append` to a file of other columns is an error naming the line") {
    Harness h;
    CHECK_FALSE(h.deck(kScene + "hist energy every 5 file h.csv append\n"));
    CHECK_THAT(h.first_error_line(), Catch::StartsWith("deck.dat:10: error: cannot append to 'h.csv': its columns are "
                                                       "cycle,time,s11"));
    CHECK(data_rows(slurp(dir.path() / "h.csv")) == 8);   // untouched
  }
}

TEST_CASE("io history: `append` reads a long file a row at a time, keeping its bytes and the last rows",
          "[io][history]") {
  // A long `every 1` run's file may hold millions of rows: HIST ... append keeps the last kWindow of
  // them in memory (what PRINT history and the SAVE keep), and where it drops rows after the present
  // cycle it cuts the file there, its bytes before the cut as they were (here a number written
  // "2.50", as a spreadsheet might, and CRLF line ends), rather than writing the rows kept again.
  TempDir dir;
  WorkingDir cd(dir.path());
  const std::string header = "cycle,time,s11,s22,s33,s12,s13,s23\r\n";
  auto row = [](double cycle, int k) {
    return fmt::format("{},{},2.50,{},0,0,0,0\r\n", cycle, 0.001 * k, k);
  };
  SECTION("rows past the present cycle are cut off, the rest byte for byte") {
    std::string kept = header, all;
    for (int k = 1; k <= 20; ++k) kept += row(k, k);
    all = kept;
    for (int k = 21; k <= 25000; ++k) all += row(k, k);
    write_text(dir.path() / "h.csv", all);
    Harness h;
    REQUIRE(h.deck(kScene + "cycle 20\nhist stress every 5 file h.csv append\n"));
    CHECK_THAT(h.err.str(), Catch::Contains("appending to its 20 rows (cycles 1 to 20); dropped its 24980 rows after "
                                            "cycle 20 (cycles 21 to 25000)"));
    CHECK(slurp(dir.path() / "h.csv") == kept);
    const HistoryTable& t = *h.session.history().tables()[0];
    CHECK(t.recorded == 20);
    REQUIRE(t.rows.size() == 20);
    CHECK(t.rows.front()[0] == 1);
    CHECK(t.rows.back()[3] == 20);   // s22 of the last row kept
  }
  SECTION("every row kept: the file untouched, the last kWindow rows in memory") {
    // 25,000 rows, their cycles below the present one (fractions of a cycle, which the file allows).
    std::string all = header;
    for (int k = 1; k <= 25000; ++k) all += row(k / 2000.0, k);
    write_text(dir.path() / "h.csv", all);
    Harness h;
    REQUIRE(h.deck(kScene + "cycle 20\nhist stress every 5 file h.csv append\n"));
    CHECK_THAT(h.err.str(), Catch::Contains("h.csv: appending to its 25000 rows (cycles 0.0005 to 12.5)"));
    CHECK(slurp(dir.path() / "h.csv") == all);
    const HistoryTable& t = *h.session.history().tables()[0];
    CHECK(t.recorded == 25000);
    REQUIRE(t.rows.size() == HistoryTable::kWindow);
    CHECK(t.rows.front()[3] == 25000 - HistoryTable::kWindow + 1);
    CHECK(t.rows.back()[3] == 25000);
    REQUIRE(h.deck("cycle 5\n"));   // and the next row goes after them
    CHECK(t.recorded == 25001);
    const auto lines = lines_of(slurp(dir.path() / "h.csv"));
    CHECK(lines.back().rfind("25,", 0) == 0);
  }
}

TEST_CASE("io history: bad HIST file words are errors naming the line", "[io][history]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  CHECK_FALSE(h.deck(kScene + "hist stress append\n"));
  CHECK_THAT(h.first_error_line(), Catch::StartsWith("deck.dat:10: error:") &&
                                       Catch::Contains("`new` and `append` go with `file f.csv`"));
  Harness two;
  CHECK_FALSE(two.deck(kScene + "hist stress file h.csv\nhist energy file h.csv\n"));
  CHECK_THAT(two.first_error_line(), Catch::StartsWith("deck.dat:11: error: 'h.csv' is the file of a history already "
                                                       "recording"));
}

TEST_CASE("io history: a save of format 5 (before histories) restarts with none", "[io][history][restart]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  REQUIRE(h.deck(kScene + "hist energy every 5\ncycle 10\nsave s.sav\n"));
  std::string data = slurp(dir.path() / "s.sav");
  std::uint32_t version = 0;
  std::memcpy(&version, data.data() + 8, sizeof version);
  REQUIRE(version == 13);
  // Format 7 keeps the energy terms of the last force pass: PRINT energy after RESTART is the run's.
  Harness now;
  REQUIRE(now.deck(kScene + "restart s.sav\n"));
  REQUIRE(now.session.model().energy_at_step.valid);
  CHECK(energy(now.session.model()).kinetic_translation == energy(h.session.model()).kinetic_translation);
  CHECK(energy(now.session.model()).total() == energy(h.session.model()).total());
  // The same model in format 5, which had no histories.
  save_model(h.session.model(), (dir.path() / "old.sav").string(), &h.session.history(), 5);
  data = slurp(dir.path() / "old.sav");
  std::memcpy(&version, data.data() + 8, sizeof version);
  REQUIRE(version == 5);
  Harness old;
  REQUIRE(old.deck(kScene + "hist stress\nrestart old.sav\n"));
  CHECK(old.session.history().tables().empty());
  CHECK_FALSE(old.session.model().energy_at_step.valid);   // before format 7: the state as it is
  CHECK(old.session.model().cycle == 10);
  CHECK(old.session.model().balls.x == h.session.model().balls.x);
}

TEST_CASE("io history: a save whose history names no quantity HIST knows is refused as damaged", "[io][history][restart]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  REQUIRE(h.deck(kScene + "hist unbal every 5\ncycle 10\nsave s.sav\n"));
  std::string data = slurp(dir.path() / "s.sav");
  const std::size_t header = 8 + 4 + 8 + 8;
  // The item's text, made another word of the same length, with a checksum that matches: the file
  // is whole, but not one HIST could have written.
  const auto at = data.find("unbal", header);
  REQUIRE(at != std::string::npos);
  data.replace(at, 5, "xxxxx");
  std::uint64_t sum = 1469598103934665603ull;   // FNV-1a, as save.cpp
  for (std::size_t k = header; k < data.size(); ++k) sum = (sum ^ static_cast<unsigned char>(data[k])) * 1099511628211ull;
  std::memcpy(data.data() + 20, &sum, sizeof sum);
  dir.write("bad.sav", data);
  Harness other;
  CHECK_FALSE(other.deck("restart bad.sav\n"));
  CHECK_THAT(other.first_error_line(), Catch::StartsWith("deck.dat:1: error:") && Catch::Contains("is damaged"));
}
