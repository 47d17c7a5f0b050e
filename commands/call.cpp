#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_call(Context& ctx, Args& args) {
  std::string file = args.word("file name");
  args.done();
  ctx.interp.call_file(file);
}

const Command call_command = {
    "CALL", {"INCLUDE"}, "CALL file", "read commands from a file",
    "Reads and runs the commands in a file, then continues. Calls nest; a file that calls itself (directly "
    "or not) is an error. A relative name is looked up in the working directory, then beside the calling "
    "file. An error inside names that file and line.",
    "call materials.dat",
    {}, run_call, false, false, OnRanks::Parts, HeldUse::Keep};

}  // namespace trubal
