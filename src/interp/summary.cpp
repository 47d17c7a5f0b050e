#include "interp/summary.hpp"

#include <algorithm>
#include <utility>
#include <vector>

#include <fmt/format.h>

namespace trubal {
namespace {

// The phases with their seconds; "other" is the loop's own work (energy guard, snapshots,
// progress) and clock noise.
std::vector<std::pair<std::string, double>> phases(const PhaseTimes& t, double seconds) {
  std::vector<std::pair<std::string, double>> out;
  const double split = t.detect + t.forces + t.motion;
  if (split > 0) {
    out = {{"contact detection", t.detect}, {"forces", t.forces}, {"motion", t.motion}};
    // What the backend spent outside its own timers belongs to the step as a whole.
    if (t.step > split) out.push_back({"step (rest)", t.step - split});
  } else {
    out = {{"detection+forces+motion", t.step}};
  }
  out.push_back({"output", t.output});
  out.push_back({"other", std::max(0.0, seconds - t.step - t.output)});
  return out;
}

}  // namespace

std::string phase_split(const PhaseTimes& times, double seconds) {
  std::string line;
  if (!(seconds > 0)) return line;
  for (const auto& [name, s] : phases(times, seconds)) {
    // The loop's own work and the unsplit rest are noise unless they are not.
    if ((name == "other" || name == "step (rest)") && s < 0.005 * seconds) continue;
    const std::string shortname = name == "contact detection" ? "detect" : name;
    line += fmt::format("{}{} {:.0f}%", line.empty() ? "" : ", ", shortname, 100 * s / seconds);
  }
  return line;
}

std::string run_summary(std::int64_t cycles, double ball_cycles, double cycling_seconds, double wall_seconds,
                        const PhaseTimes& times) {
  if (cycles <= 0) return "";
  std::string out = fmt::format("run summary: {} cycles in {:.3f} s of cycling ({:.3f} s wall), {:.3g} ball-cycles/s\n",
                                cycles, cycling_seconds, wall_seconds,
                                cycling_seconds > 0 ? ball_cycles / cycling_seconds : 0.0);
  out += fmt::format("  {:<24} {:>10} {:>7}\n", "phase", "seconds", "%");
  for (const auto& [name, s] : phases(times, cycling_seconds))
    out += fmt::format("  {:<24} {:>10.3f} {:>6.1f}%\n", name, s,
                       cycling_seconds > 0 ? 100 * s / cycling_seconds : 0.0);
  return out;
}

}  // namespace trubal
