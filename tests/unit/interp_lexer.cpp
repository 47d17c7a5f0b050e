// The lexical rules of doc/language.md, one test per rule: first on the lexer's pieces, then through the
// interpreter where the rule shows in what a deck does.
#include <catch2/catch.hpp>

#include <map>
#include <sstream>

#include "interp/command.hpp"
#include "interp/lexer.hpp"
#include "interp_support.hpp"

using namespace trubal;
using trubal::test::Harness;

namespace {

// All logical lines of a text, with the physical line each started on.
std::vector<std::pair<int, std::string>> logical_lines(const std::string& text) {
  std::istringstream in(text);
  LineReader reader(in);
  std::vector<std::pair<int, std::string>> out;
  while (auto l = reader.next()) out.emplace_back(reader.line(), *l);
  return out;
}

std::vector<std::string> words(const std::string& line) { return split_words(line); }

}  // namespace

TEST_CASE("interp lexer: continuation with ampersand and backslash and comment lines inside", "[interp][lexer]") {
  // Both continuation characters join the next physical line; the logical line is numbered by the
  // physical line it started on, and the line after it keeps its own number.
  auto lines = logical_lines("ball 1 2 &\n  3 4\nfrac 0.5 \\\n\nstop\necho after\n");
  REQUIRE(lines.size() == 3);
  CHECK(words(lines[0].second) == std::vector<std::string>{"ball", "1", "2", "3", "4"});
  CHECK(lines[0].first == 1);
  // An empty line inside a continuation ends nothing: `frac 0.5 \` goes on to `stop`.
  CHECK(words(lines[1].second) == std::vector<std::string>{"frac", "0.5", "stop"});
  CHECK(lines[1].first == 3);
  CHECK(lines[2].first == 6);

  // Comment lines (`;` and `*` in column 1) inside a continuation are skipped, they do not end it.
  auto with_comments = logical_lines("echo one &\n; a comment line\n* a Fortran comment line\n  two\necho three\n");
  REQUIRE(with_comments.size() == 2);
  CHECK(words(with_comments[0].second) == std::vector<std::string>{"echo", "one", "two"});
  CHECK(with_comments[1].first == 5);

  // A continuation mark inside a comment is part of the comment: the line does not continue.
  auto in_comment = logical_lines("echo a ; not continued &\necho b\n");
  REQUIRE(in_comment.size() == 2);
  CHECK(words(in_comment[0].second) == std::vector<std::string>{"echo", "a"});

  // Through the interpreter: one ECHO spread over three lines prints one line.
  Harness h;
  REQUIRE(h.deck("set echo off\necho alpha &\n  ; comment\n  beta \\\n  gamma\n"));
  CHECK(h.out.str() == "alpha beta gamma\n");
}

TEST_CASE("interp lexer: comment characters and star in column 1 and hash inside quotes", "[interp][lexer]") {
  CHECK(strip_comment("cycle 10 ; PFC style") == "cycle 10 ");
  CHECK(strip_comment("cycle 10 # other codes") == "cycle 10 ");
  CHECK(strip_comment("cycle 10 ! Fortran 90") == "cycle 10 ");
  CHECK(strip_comment("* a whole-line comment; with cycle 10") == "");
  // `*` counts only in column 1: elsewhere it is an ordinary character.
  CHECK(strip_comment(" * not a comment") == " * not a comment");
  CHECK(strip_comment("echo \"a # b ; c ! d\" ; real comment") == "echo \"a # b ; c ! d\" ");

  Harness h;
  REQUIRE(h.deck("set echo off\n* column-1 comment\necho \"a # b\" # gone\necho c ; gone\necho d ! gone\n; cycle 5\n"));
  CHECK(h.out.str() == "a # b\nc\nd\n");
  // A `*` not in column 1 is not a comment: it is read as a (unknown) command word.
  Harness h2;
  CHECK_FALSE(h2.deck(" * indented\n"));
  CHECK(h2.first_error_line().starts_with("deck.dat:1: error: unknown command '*'"));
}

TEST_CASE("interp lexer: keywords are case-insensitive", "[interp][lexer]") {
  const Command& canonical = find_command("CYCLE");
  CHECK(&find_command("cycle") == &canonical);
  CHECK(&find_command("CyClE") == &canonical);
  CHECK(&find_command("cyc") == &canonical);
  CHECK(match_keyword("BALLS", {"info", "balls"}) == std::optional<std::size_t>(1));
  Harness h;
  REQUIRE(h.deck("SET ECHO OFF\nEcHo mixed\nset Echo Off\n"));
  CHECK(h.out.str() == "mixed\n");
}

TEST_CASE("interp lexer: unique prefixes of 3 or more letters abbreviate and shorter or ambiguous ones are errors",
          "[interp][lexer]") {
  CHECK(find_command("CYC").name == "CYCLE");
  CHECK(find_command("PRIN").name == "PRINT");
  CHECK(find_command("GRAV").name == "GRAV");
  CHECK(find_command("gra").name == "GRAV");
  // RES is a prefix of RESTART and of its alias RESTORE: the same command, so not ambiguous.
  CHECK(find_command("RES").name == "RESTART");
  CHECK(find_command("restore").name == "RESTART");
  CHECK(find_command("INC").name == "CALL");
  // Two letters are too few even when only one command starts with them.
  CHECK_THROWS_WITH(find_command("CY"), Catch::Contains("too short") && Catch::Contains("3 letters"));
  CHECK_THROWS_WITH(find_command("zzz"), Catch::Contains("unknown command 'zzz'"));

  // Every prefix (3+ letters) of every name and alias either names its own command or, when it
  // starts names of different commands, is reported as ambiguous listing them.
  std::vector<std::pair<std::string, const Command*>> names;
  for (const Command* c : command_table()) {
    names.emplace_back(std::string(c->name), c);
    for (auto a : c->aliases) names.emplace_back(std::string(a), c);
  }
  for (const auto& [name, owner] : names) {
    for (std::size_t len = 3; len <= name.size(); ++len) {
      std::string prefix = to_lower(name.substr(0, len));
      std::vector<std::string> starts;
      bool other = false;
      for (const auto& [n2, o2] : names)
        if (to_lower(n2).starts_with(prefix)) starts.push_back(n2), other = other || o2 != owner;
      bool exact = false;
      for (const auto& [n2, o2] : names) exact = exact || to_lower(n2) == prefix;
      INFO("prefix " << prefix << " of " << name);
      if (other && !exact) {
        try {
          find_command(prefix);
          FAIL("an ambiguous prefix was accepted");
        } catch (const InputError& e) {
          CHECK_THAT(e.what(), Catch::Contains("ambiguous"));
          for (const auto& s : starts) CHECK_THAT(e.what(), Catch::Contains(s));
        }
      } else if (!exact) {
        CHECK(&find_command(prefix) == owner);
      }
    }
  }

  // Word keywords follow the same rule: `str` starts both STRESS and STRAIN.
  CHECK_THROWS_WITH(match_keyword("str", {"stress", "strain"}),
                    Catch::Contains("'str' is ambiguous") && Catch::Contains("STRESS, STRAIN"));
  CHECK(match_keyword("stre", {"stress", "strain"}) == std::optional<std::size_t>(0));
  CHECK(match_keyword("st", {"stress", "strain"}) == std::nullopt);
  // An exact name wins over being the prefix of a longer one.
  CHECK(match_keyword("vel", {"xvel", "vel", "velocity"}) == std::optional<std::size_t>(1));
}

TEST_CASE("interp lexer: blanks tabs commas equals and parentheses separate words", "[interp][lexer]") {
  CHECK(words("prop kn=1.5e9, ks=1.5e9") == words("prop kn 1.5e9 ks 1.5e9"));
  CHECK(words("prop kn 1.5e9 ks 1.5e9") == std::vector<std::string>{"prop", "kn", "1.5e9", "ks", "1.5e9"});
  CHECK(words("grav(0,0,-9.81)") == std::vector<std::string>{"grav", "0", "0", "-9.81"});
  CHECK(words("\tcycle\t\t10  ") == std::vector<std::string>{"cycle", "10"});
  CHECK(words(",,= ( )") .empty());
  // A quoted string is one word, separators and all.
  CHECK(words("title \"a, b = (c)\" d") == std::vector<std::string>{"title", "a, b = (c)", "d"});
  CHECK_THROWS_WITH(split_words("title \"open"), Catch::Contains("unterminated quoted string"));

  Harness h;
  REQUIRE(h.deck("set echo off\necho\ta,b=c(d)  e\n"));
  CHECK(h.out.str() == "a b c d e\n");
}

TEST_CASE("interp lexer: TITLE keeps the rest of its line as typed, commas included", "[interp][lexer]") {
  CHECK(text_after_keyword("title test 2, Al alloy") == "test 2, Al alloy");
  CHECK(text_after_keyword("  TITLE\t a = (b),  c  \t") == "a = (b),  c");
  CHECK(text_after_keyword("title, x") == "x");
  CHECK(text_after_keyword("title \"a; b, c\"") == "a; b, c");
  CHECK(text_after_keyword("title \"a\" and \"b\"") == "\"a\" and \"b\"");
  CHECK(text_after_keyword("title").empty());

  Harness h;
  REQUIRE(h.deck("set echo off\nset n 2\ntitle test $n, Al alloy (T6)  x=1 ; a comment\nprint info\n"
                 "title \"run 2; dense\"\n"));
  CHECK_THAT(h.out.str(), Catch::Contains("title: test 2, Al alloy (T6)  x=1\ntitle: "));   // TITLE's echo
  CHECK_THAT(h.out.str(), Catch::Contains("\ntitle: test 2, Al alloy (T6)  x=1\nspace: none"));   // PRINT info
  CHECK(h.session.model().title == "run 2; dense");
  // The quotes are still checked: an unclosed one is an error, as on any line.
  Harness open;
  CHECK_FALSE(open.deck("title \"never closed\n"));
}

TEST_CASE("interp lexer: every Fortran number form is read and malformed numbers are refused", "[interp][lexer]") {
  struct Case { const char* text; double value; };
  const Case good[] = {{"20", 20},          {"20.", 20},           {".5", 0.5},         {"1.5e9", 1.5e9},
                       {"1.5E+09", 1.5e9},  {"1.5d9", 1.5e9},      {"1.5D+09", 1.5e9},  {"1.5e-3", 1.5e-3},
                       {"1.5D-03", 1.5e-3}, {"-20", -20},          {"+20.", 20},        {"-.5", -0.5},
                       {"+1.5d9", 1.5e9},   {"-1.5E+09", -1.5e9},  {"1e5", 1e5},        {"0", 0},
                       {"007", 7},          {"2.5e0", 2.5}};
  for (const auto& c : good) {
    INFO("number " << c.text);
    auto v = parse_real(c.text);
    REQUIRE(v.has_value());
    // Exact: each form names one decimal that strtod rounds correctly, the same as the e form.
    CHECK(*v == c.value);
  }
  const char* bad[] = {"1e", "1e+", "inf", "nan", "-inf", "infinity", "0x10", ".", "e5", "-", "+", "",
                       "1.5.3", "1..5", "--1", "1e5.0", "1.5f", "1,5", "d9", "1.5q9", "1 5", "0x1p3"};
  for (const char* b : bad) {
    INFO("malformed number '" << b << "'");
    CHECK_FALSE(parse_real(b).has_value());
  }
  // Counts: whole numbers only.
  CHECK(parse_integer("20") == std::optional<std::int64_t>(20));
  CHECK(parse_integer("-3") == std::optional<std::int64_t>(-3));
  CHECK(parse_integer("+3") == std::optional<std::int64_t>(3));
  CHECK_FALSE(parse_integer("20.").has_value());
  CHECK_FALSE(parse_integer("1e3").has_value());
  CHECK_FALSE(parse_integer("1.5").has_value());
  CHECK_FALSE(parse_integer("+").has_value());
  CHECK_FALSE(parse_integer("").has_value());
  CHECK_FALSE(parse_integer("99999999999999999999999").has_value());  // overflows int64

  // Through Args: a real where a count is expected is an error that says so.
  Args reals("TEST x", {"1.5D+09", ".5"});
  CHECK(reals.real("x") == 1.5e9);
  CHECK(reals.real("y") == 0.5);
  Args counts("CYCLE n", {"1.5"});
  CHECK_THROWS_WITH(counts.count("n"), Catch::Contains("whole number") && Catch::Contains("real '1.5'"));
  CHECK_FALSE(parse_real("1e999").has_value());   // beyond the doubles: not infinity
  CHECK(real_out_of_range("1e999"));
  CHECK(real_out_of_range("-2.5D+400"));
  CHECK_FALSE(real_out_of_range("1e308"));
  CHECK_FALSE(real_out_of_range("nan"));
  Args junk("GRAV gx gy gz", {"nan"});
  CHECK_THROWS_WITH(junk.real("gx"), Catch::Contains("expected a number for gx, got 'nan'"));
}

TEST_CASE("interp lexer: dollar-name and dollar-brace variables are replaced by SET values", "[interp][lexer]") {
  std::map<std::string, std::string> vars = {{"n", "5"}, {"kn", "1.5e9"}};
  auto lookup = [&](const std::string& name) -> std::optional<std::string> {
    auto it = vars.find(name);
    if (it == vars.end()) return std::nullopt;
    return it->second;
  };
  CHECK(expand_variables("cycle $n", lookup) == "cycle 5");
  CHECK(expand_variables("cycle ${n}0", lookup) == "cycle 50");
  CHECK(expand_variables("prop kn=$kn,ks=$KN", lookup) == "prop kn=1.5e9,ks=1.5e9");  // names ignore case
  CHECK(expand_variables("$n$n", lookup) == "55");
  CHECK_THROWS_WITH(expand_variables("cycle $nope", lookup), Catch::Contains("undefined variable $nope"));
  CHECK_THROWS_WITH(expand_variables("cycle $ 5", lookup), Catch::Contains("variable name"));
  CHECK_THROWS_WITH(expand_variables("cycle ${n", lookup), Catch::Contains("closing }"));

  Harness h;
  REQUIRE(h.deck("set echo off\nset n 5\nset label two words\necho $n ${n}0 [$label]\n"));
  CHECK(h.out.str() == "5 50 [two words]\n");
}

TEST_CASE("interp lexer: lines longer than 80 characters are read whole", "[interp][lexer]") {
  std::string long_word(300, 'x');
  Harness h;
  // The number at column 300+ must still be read: TRUBAL's 80-column cut would drop it.
  std::string deck = "set echo off\nset padding " + long_word + "\necho " + std::string(200, ' ') + "end " +
                     long_word + "\n";
  REQUIRE(h.deck(deck));
  CHECK(h.out.str() == "end " + long_word + "\n");
  CHECK(h.interp.variable("padding") == long_word);
  // A continuation of long lines stays whole too.
  auto lines = logical_lines(std::string(100, 'a') + " &\n" + std::string(100, 'b') + "\n");
  REQUIRE(lines.size() == 1);
  CHECK(lines[0].second.size() == 202);
}

TEST_CASE("interp lexer: DOS line endings and a UTF-8 byte-order mark are read like plain text", "[interp][lexer]") {
  // Decks edited on Windows: CR LF endings (also before a continuation mark) and a BOM before line 1.
  Harness h;
  REQUIRE(h.deck("\xEF\xBB\xBF" "echo one\r\necho two &\r\n  three ; comment\r\n* note\r\necho four\r\n"));
  CHECK(h.out.str() == "one\ntwo three\nfour\n");
  // Only at the start of the file: elsewhere those bytes are an (unknown) word.
  Harness later;
  CHECK_FALSE(later.deck("echo one\n\xEF\xBB\xBF" "echo two\n"));
  CHECK(later.first_error_line().starts_with("deck.dat:2: error: unknown command '\\xef\\xbb\\xbfecho'"));
}
