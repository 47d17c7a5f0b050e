// The command table: the one list the dispatcher, HELP, Tab completion and the man page read.
#include "commands/common.hpp"

namespace trubal {

const std::vector<const Command*>& command_table() {
#define TRUBAL_COMMAND_ENTRY(name) &name##_command,
  static const std::vector<const Command*> table = {TRUBAL_COMMANDS(TRUBAL_COMMAND_ENTRY)};
#undef TRUBAL_COMMAND_ENTRY
  return table;
}

}  // namespace trubal
