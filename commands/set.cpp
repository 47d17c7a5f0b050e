#include <cctype>
#include <utility>

#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

// The command that sets what a word names, where a PFC user might SET it; null for other words.
static const char* setting_command(const std::string& name) {
  // (Only words PFC sets with its own `set`: property names, as `set kn 1e6` for `prop kn $kn`,
  // are common variables.)
  static const std::pair<const char*, const char*> known[] = {
      {"gravity", "GRAV gx gy gz"}, {"grav", "GRAV gx gy gz"}, {"dt", "TSTEP dt (or FRAC f)"},
      {"timestep", "TSTEP dt (or FRAC f)"}, {"damp", "DAMP"}, {"damping", "DAMP"},
      {"backend", "BACKEND name [threads n]"}, {"threads", "BACKEND name threads n"}};
  for (const auto& [word, setter] : known)
    if (name == word) return setter;
  return nullptr;
}

static void run_set(Context& ctx, Args& args) {
  std::string name = to_lower(args.word("name"));
  if (name == "echo") {
    auto k = args.expect({"on", "off"}, "echo setting");
    args.done();
    ctx.interp.echo = k == 0;
    return;
  }
  if (name == "seed") {
    ctx.session.seed = static_cast<std::uint64_t>(args.count("seed", 0));
    args.done();
    return;
  }
  if (name == "log") {
    std::string file = args.empty() ? "" : args.word("log file");
    if (match_keyword(file, {"off"})) file.clear();
    args.done();
    ctx.interp.output().set_log(file);
    return;
  }
  if (name == "progress") {
    double seconds = args.real("seconds between progress lines");
    args.done();
    if (seconds < 0) args.fail("the progress period must not be negative (0: no progress lines)");
    ctx.interp.output().progress_seconds = seconds;
    return;
  }
  if (name == "sort") {
    const std::int64_t every = args.count("cycles between sorts", 0);
    args.done();
    ctx.session.set_sort_every(every);
    return;
  }
  if (name == "volume") {
    double v = args.real("volume");
    args.done();
    if (v < 0) args.fail("the volume must not be negative (0: the START box or periodic cell)");
    ctx.session.volume = v;
    return;
  }
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_'))
      args.fail(fmt::format("a variable name has letters, digits and _ only, not '{}'", printable(name)));
  if (std::isdigit(static_cast<unsigned char>(name[0]))) args.fail("a variable name must not start with a digit");
  if (args.empty()) args.fail(fmt::format("missing the value of {}", name));
  // A setting typed as PFC's `set` takes it (`set gravity 0 0 -9.81`) makes a variable here and
  // changes nothing else: said once, with the command that sets it.
  if (const char* setter = setting_command(name))
    ctx.warn(fmt::format("SET {0} defines the variable ${0} and sets nothing else; {0} is set by {1}", name, setter));
  ctx.interp.set_variable(name, args.rest());
}

const Command set_command = {
    "SET", {}, "SET name value  |  SET echo on|off  |  SET seed n  |  SET log file|off  |  SET progress s  |  SET sort n  |  SET volume v",
    "a variable or a setting",
    "`SET name value` defines a variable: $name (or ${name}) in later lines is replaced by the value. Settings: "
    "echo (echo each command in batch mode), seed (default seed of GEN), log (copy everything shown to a "
    "file, appending, never through a symbolic link to a file (/dev/stderr and a link to a device or pipe are followed); `SET log off` stops; while a log is on, progress comes as plain lines), progress (seconds "
    "between the plain progress lines of a long CYCLE or SOLVE, default 10; 0: none), sort (the balls are put in "
    "space order in memory, so that neighbours in space are read together, at every cycle number that is a multiple "
    "of n, default 1000 as LAMMPS's `atom_modify sort`, and at the first step after balls were added; 0: never, the balls stay in the order they were made. "
    "It changes no result's meaning, only the order each ball's contact forces are added in, the same on every "
    "backend and however the run is cut; ids never change), volume (the volume for the average stress in free space; 0 uses the START "
    "box). PFC's settings are commands here: `SET gravity`, `dt`, `timestep`, `damp`, `damping`, `backend` or "
    "`threads` makes a variable, with a warning naming the command that sets it (GRAV, TSTEP or FRAC, DAMP, BACKEND).",
    "set seed 42",
    {"echo", "seed", "log", "progress", "sort", "volume", "on", "off"}, run_set, false, false, OnRanks::Parts};

}  // namespace trubal
