// trueaxis::report — self-contained HTML reports with interactive plots.
//
// Plots are drawn by uPlot (npm package, embedded in the file: reports open offline). Every plot
// can be zoomed (drag) and read with the cursor. Long series are decimated for display to at
// most `max_points` points per series (min/max per bucket, so peaks survive); the numbers in
// tables are computed from the full data.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "trueaxis/separation/separation.hpp"

namespace trueaxis::report {

struct Series {
  std::string label;
  Eigen::VectorXd y;
  Eigen::VectorXd band;  // optional: half-width of a shaded band around y (same unit)
  std::string color;     // CSS colour; empty: automatic
  bool dashed = false;
};

struct Plot {
  std::string title;
  std::string x_label;  // with unit
  std::string y_label;  // with unit
  Eigen::VectorXd x;    // shared by all series
  std::vector<Series> series;
};

struct Section {
  std::string title;
  std::string intro_html;                       // trusted HTML (escape user text!)
  std::vector<std::vector<std::string>> table;  // first row = header; cells are escaped
  std::vector<Plot> plots;
};

std::string escape(const std::string& text);

// Renders a complete HTML document.
std::string render(const std::string& title, const std::vector<Section>& sections,
                   std::size_t max_points = 4000);

// Writes `html` to `path`, creating parent directories. Throws Error on failure.
void write(const std::string& path, const std::string& html);

// A section for a separation result: workpiece, guide (with ±2u bands when uncertainties
// exist) and pitch, the straightness values, reference and unobservable modes. If `truth` is
// given (same grids, same reference), it is overlaid and the recovery error tabulated.
Section separation_section(const std::string& title, const separation::Result& result,
                           const separation::Result* truth = nullptr);

}  // namespace trueaxis::report
