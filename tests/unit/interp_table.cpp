// The command table is the one list the dispatcher, HELP, Tab completion and the man page read:
// these tests check that they agree with it and with each other.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <algorithm>
#include <map>
#include <set>

#include <fmt/format.h>

#include "interp/command.hpp"
#include "interp/lexer.hpp"
#include "interp/manpage.hpp"
#include "interp/shell.hpp"
#include "interp_support.hpp"

using namespace trubal;
using trubal::test::Harness;
using trubal::test::lines_of;

namespace {

std::vector<std::string> all_names() {
  std::vector<std::string> names;
  for (const Command* c : command_table()) {
    names.emplace_back(c->name);
    for (auto a : c->aliases) names.emplace_back(a);
  }
  return names;
}

std::string man_page() { return trubal::test::slurp(std::string(TRUBAL_SOURCE_DIR) + "/man/trubal.1"); }

}  // namespace

TEST_CASE("interp table: entries are well formed and names are unique", "[interp][table]") {
  std::set<std::string> seen;
  for (const Command* c : command_table()) {
    INFO("command " << c->name);
    CHECK(c->name == to_upper(c->name));
    CHECK(c->name.size() >= 3);   // a keyword can always be typed in full, and 3 letters is the shortest prefix
    CHECK(c->usage.starts_with(c->name));
    CHECK_FALSE(c->summary.empty());
    CHECK_FALSE(c->help.empty());
    CHECK(c->run != nullptr);
    CHECK(seen.insert(std::string(c->name)).second);
    for (auto a : c->aliases) {
      CHECK(a == to_upper(a));
      CHECK(seen.insert(std::string(a)).second);
      CHECK(&find_command(a) == c);   // an alias runs its command
    }
    CHECK(&find_command(c->name) == c);
  }
  // doc/language.md's table: every command it lists is here (aliases included).
  for (const char* name : {"START", "GEN", "BALL", "CREATE", "LATTICE", "DELETE", "GROUP", "PROP", "DAMP", "FRAC",
                           "TSTEP", "GRAV", "FIX", "FREE", "INIT", "APPLY", "MEMBRANE", "STRAIN", "SERVO", "CYCLE",
                           "SOLVE", "PRINT", "HIST", "PLOT", "DUMP", "SAVE", "RESTART", "RESTORE", "BACKEND", "SET",
                           "CALL", "INCLUDE", "TITLE", "HELP", "STOP", "QUIT", "END", "EXIT"}) {
    INFO("doc/language.md command " << name);
    CHECK(seen.count(name) == 1);
  }
}

TEST_CASE("interp table: HELP lists every command and alias and HELP name shows its usage", "[interp][table]") {
  Harness h;
  h.interp.interactive = true;   // no echo of the command
  REQUIRE(h.line("help"));
  auto lines = lines_of(h.out.str());
  REQUIRE(lines.size() == command_table().size() + 1);
  for (std::size_t k = 0; k < command_table().size(); ++k) {
    const Command* c = command_table()[k];
    std::string names = "  ";   // built by appending: g++ 12 -Wrestrict misfires on "  " + names
    names.append(c->name);
    for (auto a : c->aliases) names.append("/").append(a);
    names.push_back(' ');
    INFO("HELP line: " << lines[k + 1]);
    CHECK(lines[k + 1].starts_with(names));
    CHECK_THAT(lines[k + 1], Catch::EndsWith(std::string(c->summary)));
  }
  for (const auto& name : all_names()) {
    Harness one;
    one.interp.interactive = true;
    INFO("HELP " << name);
    REQUIRE(one.line("help " + to_lower(name)));
    CHECK(one.out.str().starts_with("usage: " + std::string(find_command(name).usage) + "\n"));
  }
  Harness bad;
  CHECK_FALSE(bad.line("help frobnicate"));
  CHECK(bad.first_error_line().starts_with("<stdin>:1: error: unknown command 'frobnicate'"));
}

TEST_CASE("interp table: the man page names every command and its COMMANDS section is made from the table",
          "[interp][table]") {
  const std::string man = man_page();
  REQUIRE_FALSE(man.empty());   // man/trubal.1 is part of the source tree
  std::vector<std::string> missing;
  for (const Command* c : command_table()) {
    if (man.find(".B " + std::string(c->name)) == std::string::npos) missing.emplace_back(c->name);
    for (auto a : c->aliases)
      if (man.find("\\fB" + std::string(a) + "\\fR") == std::string::npos) missing.emplace_back(a);
  }
  INFO("commands and aliases not in man/trubal.1: " << ::Catch::Detail::stringify(missing));
  CHECK(missing.empty());
  const std::string begin = ".\\\" BEGIN COMMANDS\n", end = ".\\\" END COMMANDS\n";
  auto a = man.find(begin), b = man.find(end);
  REQUIRE(a != std::string::npos);
  REQUIRE(b != std::string::npos);
  REQUIRE(a < b);
  std::string section = man.substr(a + begin.size(), b - a - begin.size());
  // Report the first line that differs, not two pages of roff.
  auto have = lines_of(section), want = lines_of(man_commands_section());
  std::string difference;
  for (std::size_t k = 0; k < std::max(have.size(), want.size()) && difference.empty(); ++k) {
    std::string h = k < have.size() ? have[k] : "(end of section)", w = k < want.size() ? want[k] : "(end of section)";
    if (h != w) difference = "line " + std::to_string(k + 1) + ": man/trubal.1 has '" + h + "', the table gives '" + w + "'";
  }
  INFO("regenerate the section with man/update-commands.sh build/trubal");
  CHECK(difference == "");
  CHECK(section.size() == man_commands_section().size());   // and nothing after the last line
}

TEST_CASE("interp table: the man-page section is valid roff for every entry", "[interp][table]") {
  const std::string s = man_commands_section();
  REQUIRE(s.starts_with(".SH COMMANDS\n"));
  std::size_t entries = 0;
  for (const auto& l : lines_of(s)) {
    if (l == ".TP") ++entries;
    // A text line starting with . or ' would be read as a roff request.
    if (!l.empty() && (l[0] == '.' || l[0] == '\''))
      CHECK((l == ".SH COMMANDS" || l == ".TP" || l == ".br" || l.starts_with(".B ")));
  }
  CHECK(entries == command_table().size());
}

TEST_CASE("interp table: Tab completion offers keywords and each command's words", "[interp][table]") {
  using V = std::vector<std::string>;
  CHECK(completions("", "cyc") == V{"cycle"});
  CHECK(completions("", "CYC") == V{"CYCLE"});   // the case the user types
  CHECK(completions("", "inc") == V{"include"});  // aliases too
  CHECK(completions("print ", "bal") == V{"balls"});
  CHECK(completions("PRINT ", "BAL") == V{"BALLS"});
  CHECK(completions("prin ", "coo") == V{"coordination"});   // after an abbreviated keyword
  CHECK(completions("help ", "cy") == V{"cycle"});            // HELP completes command names
  CHECK(completions("set ", "ec") == V{"echo"});
  CHECK(completions("", "zz").empty());
  CHECK(completions("frobnicate ", "x").empty());
  CHECK(completions("cycle ", "unt") == V{"until"});           // CYCLE takes a number, or `until`
  CHECK(completions("frac ", "").empty());                    // FRAC takes a number only

  auto s = completions("", "s");
  for (const char* want : {"start", "solve", "save", "set", "stop", "strain", "servo", "sample"})
    CHECK(std::find(s.begin(), s.end(), want) != s.end());
  for (const auto& w : s) CHECK(w.starts_with("s"));

  // With nothing typed at the start of a line: every keyword and alias, once.
  auto everything = completions("", "");
  CHECK(everything.size() == all_names().size());
  CHECK(std::set<std::string>(everything.begin(), everything.end()).size() == everything.size());

  // Every word a command lists completes from its first letters, after the full or abbreviated keyword.
  for (const Command* c : command_table())
    for (auto w : c->words) {
      std::string word = to_lower(w);
      for (const std::string& before : {to_lower(c->name) + " ", to_lower(c->name.substr(0, 3)) + " x "}) {
        auto got = completions(before, word.substr(0, 1));
        INFO(before << "| " << word);
        CHECK(std::find(got.begin(), got.end(), word) != got.end());
      }
    }
}

TEST_CASE("interp table: every command has an example that HELP and the man page show and a deck runs",
          "[interp][table]") {
  // Where the example runs: a small box of balls with a group, a material file to CALL and a save to
  // RESTART; the periodic cell for STRAIN and SERVO; a lattice for MEMBRANE; a history for PLOT.
  const std::string box = "start box 0 0.1 0 0.1 0 0.2\nprop kn 1e6 ks 1e6 fric 30 dens 2650\n"
                          "gen 40 0.004 0.006 seed 3\ngroup platens range z 0 0.02\nsave dense.sav\n";
  const std::map<std::string, std::string> scene = {
      {"STRAIN", "start 0.1 0.1 0.1\nprop kn 1e6 ks 1e6 dens 2650\ngen 40 0.004 0.006\n"},
      {"SERVO", "start 0.1 0.1 0.1\nprop kn 1e6 ks 1e6 dens 2650\ngen 40 0.004 0.006\n"},
      {"MEMBRANE", "start box 0 0.1 0 0.1 0 0.1\nprop kn 1e6 dens 2650\nlattice fcc 0.01 4 4 4 origin 0.03 0.03 0.03\n"},
      {"PLOT", box + "hist stress strain every 10 file tri.csv\ncycle 50\n"},
      {"SAMPLE", box + "wall id 1 plane 0 0 0 0 0 1\nwall id 2 plane 0 0 0.2 0 0 -1\n"
                       "wall id 3 cylinder 0.05 0.05 0 0 0 1 radius 0.05 length 0.2\n"},
  };
  for (const Command* c : command_table()) {
    INFO(c->name << ": example '" << c->example << "'");
    REQUIRE_FALSE(c->example.empty());
    CHECK(c->example.find('\n') == std::string_view::npos);
    // Its first word is this command's keyword (or an alias).
    const auto words = split_words(c->example);
    REQUIRE_FALSE(words.empty());
    CHECK(&find_command(words[0]) == c);
    Harness help;
    REQUIRE(help.deck(fmt::format("help {}\n", c->name)));
    CHECK_THAT(help.out.str(), Catch::EndsWith(fmt::format("Example:\n  {}\n", c->example)));
    // And it runs as written.
    trubal::test::TempDir dir;
    dir.write("materials.dat", "prop kn 1e6 ks 1e6 fric 30 dens 2650\n");
    trubal::test::WorkingDir in(dir.path());
    Harness run;
    const auto it = scene.find(std::string(c->name));
    const bool ran = run.deck((it == scene.end() ? box : it->second) + std::string(c->example) + "\n");
    INFO(run.err.str());
    CHECK(ran);
  }
  // The man page's entries (made from the table, and checked to match man/trubal.1 above) show them.
  const std::string section = man_commands_section();
  std::size_t shown = 0;
  for (auto at = section.find(".br\nExample: \\fB"); at != std::string::npos; at = section.find(".br\nExample: \\fB", at + 1))
    ++shown;
  CHECK(shown == command_table().size());
}

TEST_CASE("interp table: HELP speaks of what a user does, not of the program's insides", "[interp][table]") {
  // How a run is spread over processes, and the copy a failed step is taken back to, are the
  // program's business (doc/distributed.md, doc/developer.md), not a command's description.
  for (const Command* c : command_table()) {
    const std::string text = to_lower(std::string(c->summary) + "\n" + std::string(c->help));
    INFO(c->name << ": " << text);
    for (const char* word : {" rank", "rescue", "snapshot"}) CHECK(text.find(word) == std::string::npos);
  }
}
