// One command table entry and the argument cursor its handler reads words with.
#pragma once

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "interp/lexer.hpp"

namespace trubal {

class Session;
class Interpreter;

// The words after a keyword, read left to right. Every reader throws InputError with a message
// that says what was expected and shows the command's usage.
class Args {
 public:
  Args(std::string_view usage, std::vector<std::string> words) : usage_(usage), words_(std::move(words)) {}

  bool empty() const { return pos_ >= words_.size(); }
  std::size_t remaining() const { return words_.size() - pos_; }
  const std::string& peek() const;
  std::string word(std::string_view what);
  double real(std::string_view what);
  // A whole number in [min, max]; a real here is an error.
  std::int64_t count(std::string_view what, std::int64_t min = 0, std::int64_t max = INT64_MAX);
  // Matches the next word against options (keyword rules); consumes it and returns the option's
  // index if it matches, nullopt (nothing consumed) if it does not.
  std::optional<std::size_t> keyword(const std::vector<std::string_view>& options);
  // As keyword(), but a missing or unknown word is an error that lists the options.
  std::size_t expect(const std::vector<std::string_view>& options, std::string_view what);
  // True (and consumed) if the next word is this keyword.
  bool accept(std::string_view option);
  // Everything left, joined by blanks.
  std::string rest();
  // Errors if words are left over.
  void done() const;
  [[noreturn]] void fail(const std::string& message) const;

 private:
  std::string_view usage_;
  std::vector<std::string> words_;
  std::size_t pos_ = 0;
};

// What a handler works with.
struct Context {
  Session& session;
  Interpreter& interp;
  std::ostream& out;
  void warn(const std::string& message) const;
};

// What a command needs of the model under mpirun. Rank 0 holds the whole model, current: its
// output reads that. The others hold no more of the whole than its light state (settings,
// materials, walls, groups) and its balls' ids, types and radii, and after a CYCLE their own part
// of the model (cycle/brick_step.hpp).
enum class OnRanks : std::uint8_t {
  Whole,      // every rank gets the whole model first (Session::whole_everywhere), then runs it
              // (START, BACKEND, RENUMBER, TABLE)
  RankZero,   // only reads the model, and only rank 0's reading is printed or written: rank 0 alone runs it
              // (PRINT, SAVE, PLOT)
  Parts,      // every rank runs it on the model as it is (CYCLE, SOLVE; the settings: DAMP, FRAC, TSTEP, GRAV;
              // the cell's: STRAIN, SERVO; SAMPLE; the commands that do not read the balls; RESTART, which
              // rank 0 alone reads and the others take the light state of: Session::restart)
  ModelOnZero,   // changes the model alone: rank 0 alone runs it, on its whole model, the parts' state
                 // given to it first (Session::model_on_zero); the others take rank 0's model but the
                 // balls' arrays before the next command of another kind (Session::light_everywhere)
                 // (BALL, GEN, LATTICE, PROP, INIT, APPLY, FIX, FREE, GROUP, DELETE, WALL, BOND,
                 // MEMBRANE; some forms run on the parts where the ranks keep them: ranks_for)
};

// What a command does with BALL lines a batch deck's ranks hold (Session::hold_balls,
// model/held_balls.hpp).
enum class HeldUse : std::uint8_t {
  Place,   // reads the balls: they are placed in the model first (Session::place_held)
  Keep,    // reads no ball (a setting, a material, text, PRINT info and counters' counts): kept
  Add,     // BALL: holds one more
  Split,   // CYCLE, SOLVE: placed in the ranks' parts where they can be, without rank 0 holding
           // them all (Session::place_held_as_parts); else as Place
  Generate,   // GEN: where the model holds no ball and none is held, rank 0 generates the balls and
              // every rank holds those its hash picks, as BALL lines (Session::generates_held,
              // hand_out_generated); else as Place
  Delete,     // DELETE: where the model holds no ball but held ones, every rank deletes those of
              // its held balls where the range holds (Session::deletes_held); else as Place
};

struct Command {
  std::string_view name;                     // canonical keyword, capitals
  std::vector<std::string_view> aliases;     // other full keywords (CREATE for BALL)
  std::string_view usage;                    // one line: "CYCLE n"
  std::string_view summary;                  // one line for HELP's table
  std::string_view help;                     // paragraphs for HELP name and the man page
  std::string_view example;                  // a line as a deck would hold it: HELP's and the man page's "Example:"
  std::vector<std::string_view> words;       // argument keywords, for Tab completion
  void (*run)(Context&, Args&);
  // Ends within microseconds whatever the model (a deck may hold a million of it, as BALL lines):
  // a batch deck's echo of it is not flushed before it runs (a write per line is most of the time
  // such a deck takes, and under mpirun each goes through mpirun's forwarding); any other command,
  // an error or a warning flushes it.
  bool quick = false;
  // Reads the rest of its line as typed, one word (TITLE): commas, `=` and parentheses are kept,
  // not taken as separators (the lexer's text_after_keyword).
  bool raw_text = false;
  OnRanks on_ranks = OnRanks::Whole;
  HeldUse held = HeldUse::Place;
  // Where held is Keep for some forms alone: the first words of those (PRINT info and counters);
  // the others place the balls.
  std::vector<std::string_view> keeps_held_after = {};
  // Where some forms run otherwise than on_ranks says: their way, from the command's words and
  // whether the ranks keep their parts (the same on every rank). WALL's motion alone, where the
  // ranks keep their parts: every rank changes its walls (Session::edit_walls); PROP, INIT, APPLY,
  // FIX, FREE and GROUP likewise its materials or its part's balls (parts_where_kept).
  OnRanks (*ranks_for)(const Args& args, bool parts_kept) = nullptr;
  // Where held is Keep but for some forms: the first words of those, which place the balls
  // (SERVO off, whose change of the cell's rates changes the balls' velocities).
  std::vector<std::string_view> places_held_after = {};
};

// What this line of the command does with held balls (Command::held, keeps_held_after,
// places_held_after).
HeldUse held_use(const Command& command, const Args& args);

// The command table (commands/table.cpp): the dispatcher, HELP, completion and the man-page test
// all read this one list.
const std::vector<const Command*>& command_table();
// The command a keyword names (exact or unique prefix of 3+ letters). Throws InputError for an
// unknown or ambiguous keyword.
const Command& find_command(std::string_view keyword);

}  // namespace trubal
