// PLOT: recorded history columns against another, drawn by gnuplot (a separate program, run with a
// generated script and data files in a temporary folder) as PNG or SVG by the file's extension.
#pragma once

#include <string>
#include <vector>

#include "io/history.hpp"

namespace trubal {

struct PlotRequest {
  std::vector<std::string> y;       // history columns, one series each
  std::string x = "cycle";
  bool every_table = false;         // a series per table and column (tables read from CSV files)
  std::string file;                 // .png or .svg
  struct Reference {
    double y = 0;
    std::string label;
  };
  std::vector<Reference> lines;     // horizontal reference lines
  std::string title;
  std::string xlabel, ylabel;       // "": named after the quantity (column_label)
  int width = 800, height = 600;    // pixels (SVG: its nominal size)
};

// What a history column is, for an axis label ("axial strain e33" for e33, "stress ratio" for ratio).
std::string column_label(const std::string& column);

// Every column some table records, in the order first recorded (for messages and completion).
std::vector<std::string> known_columns(const History& history);
// The gnuplot program on PATH, or "" if there is none.
std::string find_gnuplot();
// Renders the plot and renames it into place, so `file` is either the old file or the whole new
// one. Throws std::runtime_error with a message for people: an unknown column (listing the known
// ones), nothing recorded, gnuplot missing or failing (with what it said).
void render_plot(const History& history, const PlotRequest& request);

}  // namespace trubal
