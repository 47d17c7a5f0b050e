#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

// Wraps text to a width, for HELP's paragraphs.
static std::string wrap(std::string_view text, std::size_t width, std::string_view indent) {
  std::string out, line;
  std::size_t k = 0;
  while (k < text.size()) {
    auto end = text.find(' ', k);
    if (end == std::string_view::npos) end = text.size();
    std::string_view word = text.substr(k, end - k);
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      out += std::string(indent) + line + '\n';
      line.clear();
    }
    if (!line.empty()) line += ' ';
    line += word;
    k = end + 1;
  }
  if (!line.empty()) out += std::string(indent) + line + '\n';
  return out;
}

static void run_help(Context& ctx, Args& args) {
  if (args.empty()) {
    ctx.out << "Commands (a keyword may be shortened to 3 letters; HELP name for details):\n";
    for (const Command* c : command_table()) {
      std::string names(c->name);
      for (auto a : c->aliases) names.append("/").append(a);
      ctx.out << fmt::format("  {:<22} {}\n", names, c->summary);
    }
    return;
  }
  std::string word = args.word("command");
  args.done();
  const Command& c = find_command(word);
  ctx.out << "usage: " << c.usage << '\n';
  if (!c.aliases.empty()) {
    ctx.out << "also:";
    for (auto a : c.aliases) ctx.out << ' ' << a;
    ctx.out << '\n';
  }
  ctx.out << wrap(c.help, 76, "  ");
  ctx.out << "Example:\n  " << c.example << '\n';
}

const Command help_command = {
    "HELP", {}, "HELP [command]", "the command table, or one command in detail",
    "Without a word, lists every command with a one-line summary; `HELP cycle` shows the usage and details "
    "of one command.",
    "help cycle",
    {}, run_help, false, false, OnRanks::Parts, HeldUse::Keep};

}  // namespace trubal
