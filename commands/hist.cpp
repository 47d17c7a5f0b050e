#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands/common.hpp"

namespace trubal {

static void run_hist(Context& ctx, Args& args) {
  ctx.session.require_started();
  if (args.accept("reset")) {
    args.done();
    ctx.session.history().clear();
    ctx.out << "histories cleared\n";
    return;
  }
  std::vector<std::string> items;
  std::int64_t every = 10;
  std::string file;
  const auto& names = History::item_names();
  while (!args.empty() && !match_keyword(args.peek(), {"range"})) {
    if (args.accept("every")) { every = args.count("every", 1); continue; }
    if (args.accept("file")) { file = args.word("file name"); continue; }
    items.emplace_back(names[args.expect(names, "history item")]);
  }
  if (items.empty()) args.fail("name at least one quantity to record");
  Range range = read_range(args);
  bool platen = std::find(items.begin(), items.end(), "platen") != items.end();
  if (!range.empty() && !platen) args.fail("a RANGE goes with `platen` (the balls whose reaction is recorded)");
  auto& t = ctx.session.history().add(items, every, file, range);
  ctx.out << fmt::format("recording {} every {} cycles{}\n", fmt::join(t.columns, ","), every,
                         file.empty() ? "" : " to " + file);
}

const Command hist_command = {
    "HIST", {}, "HIST what... [every n] [file f.csv] [range ...]  |  HIST reset",
    "record quantities every n cycles",
    "Records quantities every n cycles (default 10): stress (s11 s22 s33 s12 s13 s23), strain (e11 e22 e33), "
    "ratio (s33 over the mean of s11 and s22), axial (e33), platen (z reaction force of the fixed balls in the "
    "range), energy (ke strain_energy friction_work damping_work boundary_work), unbal (mean unbalanced-force "
    "ratio), contacts (contacts sliding coordination), time. With `file` the rows are written as CSV (header "
    "cycle,time,... then one row per record, flushed as they come). `HIST reset` forgets all histories.",
    {"stress", "strain", "ratio", "axial", "platen", "energy", "unbal", "contacts", "time", "every", "file", "reset",
     "range"},
    run_hist};

}  // namespace trubal
