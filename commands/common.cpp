#include "commands/common.hpp"

#include <unistd.h>

#include <chrono>

#include <fmt/format.h>

namespace trubal {

const std::vector<std::string_view> kRangeWords = {"range", "id", "x", "y", "z", "type", "group",
                                                   "sphere", "cylinder", "octagon", "not"};

Range read_range(Args& args) {
  Range range;
  if (args.empty()) return range;
  if (!args.accept("range")) args.done();
  using K = RangeElement::Kind;
  static const std::vector<std::string_view> kinds = {"id", "x", "y", "z", "type", "group", "sphere", "cylinder",
                                                      "octagon"};
  if (args.empty()) args.fail("RANGE needs at least one element (id, x, y, z, type, group, sphere, cylinder, octagon)");
  while (!args.empty()) {
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

std::array<double, 3> read_xyz(Args& args, std::string_view what) {
  std::array<double, 3> v{};
  for (int a = 0; a < 3; ++a) v[a] = args.real(fmt::format("{} {}", what, "xyz"[a]));
  return v;
}

std::function<void(std::int64_t, std::int64_t)> progress_reporter(Context& ctx) {
  const bool tty = ::isatty(STDOUT_FILENO) && ctx.interp.output().log_path().empty();
  auto start = std::chrono::steady_clock::now();
  auto last = start;
  return [&ctx, tty, start, last](std::int64_t done, std::int64_t total) mutable {
    auto now = std::chrono::steady_clock::now();
    double since = std::chrono::duration<double>(now - last).count();
    double elapsed = std::chrono::duration<double>(now - start).count();
    if (since < (tty ? 0.25 : 10.0) || elapsed < 1.0) return;
    last = now;
    double rate = done / std::max(elapsed, 1e-9);
    double left = rate > 0 ? (total - done) / rate : 0;
    if (tty)
      ctx.out << fmt::format("\r  cycle {}/{} ({:.0f}%), {:.0f} cycles/s, {:.0f} s left   ", done, total,
                             100.0 * done / std::max<std::int64_t>(total, 1), rate, left)
              << std::flush;
    else
      ctx.out << fmt::format("  cycle {}/{}, {:.0f} cycles/s, {:.0f} s left\n", done, total, rate, left) << std::flush;
  };
}

void report_cycle_result(Context& ctx, const CycleResult& r, std::int64_t asked) {
  if (::isatty(STDOUT_FILENO)) ctx.out << "\r\033[K";
  if (r.unstable) throw std::runtime_error(r.message);
  if (r.interrupted)
    ctx.out << fmt::format("interrupted after {} of {} cycles; the model is kept (cycle {})\n", r.done, asked,
                           ctx.session.model().cycle);
}

}  // namespace trubal
