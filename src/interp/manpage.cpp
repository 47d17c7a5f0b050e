#include "interp/manpage.hpp"

#include "interp/command.hpp"

namespace trubal {

// roff: backslashes doubled, hyphens as \-, and no line may start with . or '.
static std::string roff(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '\\') out += "\\e";
    else if (c == '-') out += "\\-";
    else out += c;
  }
  if (!out.empty() && (out[0] == '.' || out[0] == '\'')) out.insert(0, "\\&");
  return out;
}

std::string man_commands_section() {
  std::string s = ".SH COMMANDS\n";
  for (const Command* c : command_table()) {
    s += ".TP\n.B " + roff(c->usage) + "\n";
    s += roff(c->help) + "\n";
    s += ".br\nExample: \\fB" + roff(c->example) + "\\fR\n";
    if (!c->aliases.empty()) {
      s += ".br\nAlso spelled";
      for (auto a : c->aliases) s += " \\fB" + roff(a) + "\\fR";
      s += ".\n";
    }
  }
  return s;
}

}  // namespace trubal
