// The interactive shell: GNU readline editing, history kept between sessions, Tab completion from
// the command table, Ctrl-C clears the line (or stops a running CYCLE), Ctrl-D leaves.
#pragma once

#include <string>
#include <vector>

namespace trubal {

class Interpreter;

// Runs the shell until STOP or Ctrl-D. Returns the number of commands that failed.
int run_shell(Interpreter& interp);
// Where the shell keeps its history: $TRUBAL_HISTORY, else ~/.trubal_history.
std::string history_path();
// Candidates for completing `text` when the line so far is `line_before` (for tests too).
std::vector<std::string> completions(const std::string& line_before, const std::string& text);

}  // namespace trubal
