#include "commands/common.hpp"

namespace trubal {

static void run_echo(Context& ctx, Args& args) { ctx.out << args.rest() << '\n'; }

const Command echo_command = {"ECHO", {}, "ECHO text", "print a line of text",
                              "Prints its words (after $variables are replaced).", {}, run_echo, true};

static void run_title(Context& ctx, Args& args) {
  std::string title = args.rest();
  ctx.session.set_title(title);
  ctx.out << "title: " << title << '\n';
}

const Command title_command = {"TITLE", {}, "TITLE text", "a title printed with output",
                               "Sets the title shown by PRINT info and kept in saves.", {}, run_title};

static void run_stop(Context& ctx, Args& args) {
  args.done();
  ctx.interp.request_stop();
}

const Command stop_command = {"STOP", {"QUIT", "END", "EXIT"}, "STOP", "end the session",
                              "Ends the session (a batch deck also ends at the end of its file).", {}, run_stop};

}  // namespace trubal
