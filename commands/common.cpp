#include "commands/common.hpp"
#include "cycle/pipeline.hpp"
#include "support/comm.hpp"

#include <algorithm>
#include <chrono>

#include <fmt/format.h>

#include "physics/overlap.hpp"

namespace trubal {

const std::vector<std::string_view> kRangeWords = {"range", "id", "x", "y", "z", "type", "group",
                                                   "sphere", "cylinder", "octagon", "not"};

Range read_range(Args& args, const std::vector<std::string_view>& stop) {
  Range range;
  if (args.empty()) return range;
  if (!args.accept("range")) args.done();
  using K = RangeElement::Kind;
  static const std::vector<std::string_view> kinds = {"id", "x", "y", "z", "type", "group", "sphere", "cylinder",
                                                      "octagon"};
  if (args.empty()) args.fail("RANGE needs at least one element (id, x, y, z, type, group, sphere, cylinder, octagon)");
  while (!args.empty() && !(range.size() && match_keyword(args.peek(), stop))) {
    RangeElement e;
    e.kind = K::Id;
    e.negate = args.accept("not");
    auto k = args.expect(kinds, "range element");
    e.kind = static_cast<K>(k);
    auto optional_real = [&](double fallback) { return parse_real(args.peek()) ? args.real("value") : fallback; };
    switch (e.kind) {
      case K::Id: {
        e.v[0] = static_cast<double>(args.count("id", 1));
        e.v[1] = parse_integer(args.peek()) ? static_cast<double>(args.count("last id", 1)) : e.v[0];
        break;
      }
      case K::X: case K::Y: case K::Z:
        e.v[0] = args.real("lower bound");
        e.v[1] = args.real("upper bound");
        if (e.v[1] < e.v[0]) args.fail("a range's upper bound is below its lower bound");
        break;
      case K::Type: e.v[0] = static_cast<double>(args.count("type", 1, 1000000)); break;
      case K::Group:
        e.group = to_lower(args.word("group name"));
        break;
      case K::Sphere:
        for (int a = 0; a < 3; ++a) e.v[a] = args.real("sphere centre");
        e.v[3] = args.real("sphere radius");
        break;
      case K::Cylinder:
        e.v[0] = args.real("cylinder x");
        e.v[1] = args.real("cylinder y");
        e.v[2] = args.real("cylinder radius");
        break;
      case K::Octagon:
        e.v[0] = args.real("octagon centre x");
        e.v[1] = args.real("octagon centre y");
        e.v[2] = args.real("octagon side distance a");
        e.v[3] = optional_real(e.v[2]);
        break;
    }
    range.push_back(e);
  }
  return range;
}

Range read_range(Args& args, const Session& session, const std::vector<std::string_view>& stop) {
  Range range = read_range(args, stop);
  const auto& groups = session.state().groups;
  for (const RangeElement& e : range) {
    if (e.kind != RangeElement::Kind::Group || groups.count(e.group)) continue;
    std::vector<std::string_view> names;
    for (const auto& [name, ids] : groups) names.push_back(name);
    if (names.empty()) args.fail(fmt::format("no group '{}': there are no groups yet (GROUP name range ... makes one)", e.group));
    if (const auto near = nearest_word(e.group, names))
      args.fail(fmt::format("no group '{}': did you mean '{}'?", e.group, names[*near]));
    std::string list;
    for (std::size_t k = 0; k < names.size() && k < 10; ++k) list += fmt::format("{}{}", k ? ", " : "", names[k]);
    if (names.size() > 10) list += fmt::format(" and {} more", names.size() - 10);
    args.fail(fmt::format("no group '{}' (the groups are {})", e.group, list));
  }
  return range;
}

std::array<double, 3> read_xyz(Args& args, std::string_view what) {
  std::array<double, 3> v{};
  for (int a = 0; a < 3; ++a) v[a] = args.real(fmt::format("{} {}", what, "xyz"[a]));
  return v;
}

namespace {

// 42 s, 3 min 05 s, 2 h 07 min.
std::string duration_text(double seconds) {
  if (!(seconds < 1e9)) return "?";
  const auto s = static_cast<std::int64_t>(seconds + 0.5);
  if (s < 60) return fmt::format("{} s", s);
  if (s < 3600) return fmt::format("{} min {:02d} s", s / 60, s % 60);
  return fmt::format("{} h {:02d} min", s / 3600, s % 3600 / 60);
}

}  // namespace

ProgressReporter::ProgressReporter(Context& ctx, bool limit)
    : ctx_(ctx),
      bar_(ctx.interp.interactive && ctx.interp.output().terminal && ctx.interp.output().log_path().empty()),
      limit_(limit),
      interval_(ctx.interp.output().progress_seconds),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

ProgressReporter::~ProgressReporter() {
  try {
    finish();
  } catch (...) {
  }
}

std::function<void(std::int64_t, std::int64_t)> ProgressReporter::callback() {
  if (!bar_ && !(interval_ > 0)) return {};
  return [this](std::int64_t done, std::int64_t total) { report(done, total); };
}

void ProgressReporter::report(std::int64_t done, std::int64_t total) {
  const auto now = std::chrono::steady_clock::now();
  const double since = std::chrono::duration<double>(now - last_).count();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  // A bar appears after half a second (short runs never flicker) and is redrawn four times a second.
  if (bar_ ? (since < 0.25 || elapsed < 0.5) : since < interval_) return;
  last_ = now;
  const double rate = done / std::max(elapsed, 1e-9);
  const double left = rate > 0 ? (total - done) / rate : 0;
  const double fraction = std::clamp(static_cast<double>(done) / static_cast<double>(std::max<std::int64_t>(total, 1)), 0.0, 1.0);
  const std::string left_text = (limit_ ? "at most " : "") + duration_text(left) + " left";
  if (bar_) {
    constexpr int width = 24;
    const int filled = static_cast<int>(fraction * width);
    ctx_.out << fmt::format("\r[{}{}] {:3.0f}%  cycle {}/{}  {:.0f} cycles/s  {}\033[K", std::string(filled, '#'),
                            std::string(width - filled, '.'), 100 * fraction, done, total, rate, left_text)
             << std::flush;
    shown_ = true;
  } else {
    ctx_.out << fmt::format("  cycle {}/{} ({:.0f}%), {:.0f} cycles/s, {}\n", done, total, 100 * fraction, rate,
                            left_text)
             << std::flush;
  }
}

void ProgressReporter::finish() {
  if (!shown_) return;
  shown_ = false;
  ctx_.out << "\r\033[K" << std::flush;
}

// Overlaps past kOverlapWarning of the smaller radius at the end of a run (physics/overlap.hpp):
// said once, and again only where the largest doubles or after they all came back below.
static void warn_of_overlaps(Context& ctx) {
  // (Rank 0 alone warns; where rank 0's whole model is hollow, every rank's part takes part.)
  const bool hollow = ctx.session.pipeline().whole_hollow(ctx.session.state());
  if (comm::size() > 1 && !comm::root() && !hollow) return;
  const LargestOverlap big = ctx.session.largest_overlap_now();   // (the positions: no contact result is read or made)
  if (comm::size() > 1 && !comm::root()) return;
  const Model& m = ctx.session.state();
  double& warned = ctx.session.overlap_warned;
  if (big.beyond == 0) {
    warned = 0;
    return;
  }
  if (!(big.ratio > 2 * warned)) return;
  warned = big.ratio;
  const std::string pair = big.wall ? fmt::format("ball {} on wall {}", big.ball, big.other)
                                    : fmt::format("balls {} and {}", big.ball, big.other);
  const std::string others = big.beyond > 1 ? fmt::format("; {} contacts are past {:g}", big.beyond, kOverlapWarning) : "";
  ctx.warn(fmt::format(
      "at cycle {} the overlap of {} is {:.3g} of ball {}'s radius{}: past {:g} of a radius the contact law no longer "
      "describes a stiff grain (a load, wall or servo too fast or too strong for the stiffness kn, or shear G? balls "
      "generated overlapping?); said again where the largest overlap doubles",
      m.cycle, pair, big.ratio, big.ball, others, kOverlapWarning));
}

void report_cycle_result(Context& ctx, const CycleResult& r, std::int64_t asked) {
  if (r.destroyed > 0)
    ctx.out << fmt::format("{} left the box and {} destroyed ({} since START)\n", count_of(r.destroyed, "ball"),
                           r.destroyed == 1 ? "was" : "were",
                           ctx.session.state().space.destroyed);
  if (r.unstable || r.left_box) throw std::runtime_error(r.message);
  warn_of_overlaps(ctx);
  if (!r.energy_warning.empty()) ctx.warn(r.energy_warning);
  if (r.interrupted)
    ctx.out << fmt::format("interrupted after {} of {} cycles; the model is kept (cycle {})\n", r.done, asked,
                           ctx.session.state().cycle);
}

}  // namespace trubal
