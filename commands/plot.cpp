#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands/common.hpp"
#include "support/comm.hpp"
#include "io/plot.hpp"

namespace trubal {

static void run_plot(Context& ctx, Args& args) {
  static const std::vector<std::string_view> options = {"file", "line", "title", "size", "from", "xlabel", "ylabel"};
  auto is_option = [](const std::string& w) {
    const std::string l = to_lower(w);
    return l == "file" || l == "line" || l == "title" || l == "size" || l == "vs" || l == "from" || l == "xlabel" ||
           l == "ylabel";
  };
  History from_files;
  PlotRequest request;
  while (!args.empty() && !is_option(args.peek())) request.y.push_back(to_lower(args.word("history column")));
  if (request.y.empty()) args.fail("name the history columns to draw (PRINT history lists them)");
  if (args.accept("vs")) request.x = to_lower(args.word("column to plot against"));
  while (!args.empty()) {
    switch (args.expect(options, "PLOT option")) {
      case 0: request.file = args.word("file name (.png or .svg)"); break;
      case 1: {
        args.accept("y");
        PlotRequest::Reference line;
        line.y = args.real("reference line's y");
        if (!args.empty() && !is_option(args.peek())) line.label = args.word("label");
        request.lines.push_back(line);
        break;
      }
      case 2: request.title = args.word("title"); break;
      case 3:
        request.width = static_cast<int>(args.count("width (pixels)", 16, 10000));
        request.height = static_cast<int>(args.count("height (pixels)", 16, 10000));
        break;
      case 4:
        do {
          const std::string csv = args.word("history CSV file");
          if (comm::root()) from_files.adopt(read_history_csv(csv));   // rank 0 reads and draws
        } while (!args.empty() && !is_option(args.peek()));
        request.every_table = true;
        break;
      case 5: request.xlabel = args.word("x axis label"); break;
      case 6: request.ylabel = args.word("y axis label"); break;
    }
  }
  if (request.file.empty()) request.file = fmt::format("{}_vs_{}.png", request.y.front(), request.x);
  if (!request.every_table) ctx.session.require_started();
  render_plot(request.every_table ? from_files : ctx.session.history(), request);
  ctx.out << fmt::format("plotted {} against {} to {}\n", fmt::join(request.y, ", "), request.x, request.file);
}

const Command plot_command = {
    "PLOT", {}, "PLOT y... [vs x] [from a.csv ...] [file f.png|f.svg] [line [y] v [label]] [title text] [xlabel text] "
    "[ylabel text] [size w h]",
    "draw recorded histories as PNG or SVG",
    "Draws history columns (recorded by HIST; PRINT history lists them) against another column (`vs x`, "
    "default cycle) as a PNG or SVG picture, chosen by the file's extension (default y_vs_x.png). Several "
    "columns give several series on one figure; each must be recorded by the same HIST as x (cycle and "
    "time are in every table). `line y 2.56 \"theory\"` adds a dashed horizontal reference line with a "
    "label (repeatable); `title \"...\"` a title; `xlabel \"...\"` and `ylabel \"...\"` the axis labels "
    "(by default the quantity the column is: axial strain e33, stress ratio, volumetric strain, wall 2 stress, "
    "...); the legend sits below the plot, clear of the data; `size w h` the size in pixels (default 800 600). "
    "Example: "
    "`PLOT ratio vs axial file rowe.png line y 2.56 \"Rowe\"`. `from a.csv b.csv` draws the columns from CSV "
    "files written by HIST ... file (one series per file, named after it) instead of this run's histories, so "
    "runs of different decks share one figure. Drawn by gnuplot (Debian: gnuplot-nox), run "
    "with a generated script; the picture is written under a temporary name and renamed.",
    "plot s33 vs e33 from tri.csv file q.png",
    {"vs", "from", "file", "line", "title", "xlabel", "ylabel", "size"}, run_plot, false, false, OnRanks::RankZero};

}  // namespace trubal
