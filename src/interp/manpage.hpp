// The COMMANDS section of man/trubal.1, made from the command table (so the man page cannot
// disagree with HELP). `trubal --man-commands` prints it; man/update-commands.sh splices it in.
#pragma once

#include <string>

namespace trubal {

std::string man_commands_section();

}  // namespace trubal
