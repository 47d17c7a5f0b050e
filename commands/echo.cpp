#include "commands/common.hpp"

namespace trubal {

static void run_echo(Context& ctx, Args& args) { ctx.out << args.rest() << '\n'; }

const Command echo_command = {
    "ECHO", {}, "ECHO text", "print a line of text", "Prints its words (after $variables are replaced).",
    "echo stage 2: shearing", {}, run_echo, true, false, OnRanks::Parts, HeldUse::Keep};

static void run_title(Context& ctx, Args& args) {
  std::string title = args.rest();
  ctx.session.set_title(title);
  ctx.out << "title: " << title << '\n';
}

const Command title_command = {
    "TITLE", {}, "TITLE text", "a title printed with output",
    "Sets the title shown by PRINT info and kept in saves. The title is the rest of the line as typed: commas, "
    "`=`, parentheses and the blanks between words are kept, not read as separators (`TITLE test 2, Al alloy` "
    "is the title `test 2, Al alloy`). A comment (`;`, `#`, `!` outside double quotes) still ends the line and "
    "$variables are still replaced; a title written as one double-quoted string loses its quotes, which is how "
    "a title holds a comment character (`TITLE \"run 2; dense\"`).",
    "title drained triaxial, 500 balls",
    {}, run_title, false, true, OnRanks::Parts, HeldUse::Keep};

static void run_stop(Context& ctx, Args& args) {
  args.done();
  ctx.interp.request_stop();
}

const Command stop_command = {
    "STOP", {"QUIT", "END", "EXIT"}, "STOP", "end the session",
    "Ends the session (a batch deck also ends at the end of its file). Typed at the shell's prompt with the "
    "model changed since the last SAVE, it asks first, as Ctrl-D does.",
    "stop", {}, run_stop, false, false, OnRanks::Parts, HeldUse::Keep};

}  // namespace trubal
