// trueaxis::report — self-contained HTML reports with interactive plots.
//
// Plots are drawn by uPlot (npm package, embedded in the file: reports open offline). Every plot
// can be zoomed (drag) and read with the cursor. Long series are decimated for display to at
// most `max_points` points per series (min/max per bucket, so peaks survive); the numbers in
// tables are computed from the full data.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "trueaxis/map/error_map.hpp"
#include "trueaxis/separation/separation.hpp"

namespace trueaxis::report {

// One colour per error component in every plot: X and A (about X) blue, Y and B red, Z and C
// green. `component` 0..5 = X, Y, Z, A, B, C.
inline const char* component_colour(int component) {
  static const char* kColours[3] = {"#1f77b4", "#d62728", "#2ca02c"};
  return kColours[((component % 3) + 3) % 3];
}

struct Series {
  std::string label;
  Eigen::VectorXd y;
  Eigen::VectorXd band;  // optional: the band is y ± 2·band (same unit), shaded
  std::string color;     // CSS colour; empty: automatic
  bool dashed = false;
  bool points = false;  // markers only, no line (a scatter plot; x need not be distinct)
  // What the shaded band is, for the page's note (said once per kind of band).
  std::string band_meaning = "±2 standard uncertainties (about 95 %)";
  // false: no legend entry (the second line of a pair that another series' entry names).
  bool in_legend = true;
};

struct Plot {
  std::string title;
  std::string x_label;  // with unit
  std::string y_label;  // with unit
  Eigen::VectorXd x;    // shared by all series
  std::vector<Series> series;
  bool log_y = false;  // logarithmic y axis (values must be positive)
  // Lines pass over a series' missing values (NaN) instead of breaking there: for series sampled
  // at some of the shared x only.
  bool span_gaps = false;
  // The x axis counts things (positions, points): ticks at whole numbers only.
  bool whole_x = false;
  // x holds days since 1970-01-01 (UTC): the axis, the cursor and the CSV show dates.
  bool x_dates = false;
};

// A colour map of values over the plane, drawn as static SVG at true aspect ratio (hover shows
// the numbers). Either or both of: grid cells (value(iy, ix) at (grid_x[ix], grid_y[iy]); each
// cell reaches half-way to its neighbours) and points (dots, optionally joined by `lines`, each
// a list of point indices: the measured lines of a surface).
struct HeatMap {
  std::string title;
  std::string x_label, y_label, value_label;  // with units
  Eigen::VectorXd grid_x, grid_y;
  Eigen::MatrixXd grid_value;
  Eigen::VectorXd px, py, pvalue;
  std::vector<std::vector<Eigen::Index>> lines;
  bool symmetric = true;          // diverging colours symmetric about 0; false: sequential min..max
  double vmin = NAN, vmax = NAN;  // colour scale limits (NaN: from the data), e.g. to share one
  int width = 520;                // px
  // Contour lines over the field (thin, dark), each a polyline (2 × k, plot coordinates).
  std::vector<Eigen::Matrix2Xd> contours;
  // > 0: the grid cells are filled contour bands of this step (value unit), each band one colour
  // (its middle's) and without per-cell tooltips: for a field interpolated between measured
  // points, whose cells carry no measured value of their own.
  double band_step = 0;
  // Write each point's value beside its dot (for a few points whose numbers matter, such as a
  // surface's closures: a value at the scale's centre is otherwise a white dot).
  bool label_points = false;
};

// A distorted grid: the nodes (u[i], v[j]) of a plane of the machine, moved by their magnified
// in-plane errors (du, dv at (j, i)), with the out-of-plane error as the node colour. The
// nominal grid is drawn in grey underneath.
struct DistortedGrid {
  std::string title;
  std::string u_label, v_label, normal_label;  // axis names with units; colour quantity
  Eigen::VectorXd u, v;                        // mm
  Eigen::MatrixXd du, dv, normal;              // µm, rows = v, columns = u
  double magnification = 0;                    // 0: automatic (largest error → 40 % of a step)
  int width = 520;                             // px
  // Colour scale limits of the out-of-plane error (NaN: from this grid), e.g. to give the levels
  // of one map one scale.
  double vmin = NAN, vmax = NAN;
};

// An isometric 3-D view of a surface, as a surface-plate report shows it: the lines along which
// heights were measured (a Union Jack's eight lines, a grid's rows and columns) drawn at their
// magnified height over the x-y plane, each segment coloured by height, over the same lines at
// zero height in grey. Each line is 3 × n: x, y (mm) and height (µm); at least 2 points.
struct SurfaceView {
  std::string title;
  std::string value_label;  // the height with its unit, e.g. "height (µm)"
  std::vector<Eigen::Matrix3Xd> lines;
  double magnification = 0;        // heights drawn ×this; 0: automatic (span → 15 % of size)
  int width = 620;                 // px
  std::string base = "the plate";  // what the heights stand over, for the caption
  std::string x_name = "x", y_name = "y";  // the plane's axes, at their arrows
};

// Curves in a plane at true aspect ratio, each in its own colour with a legend: e.g. a scanned
// section's design, corrected design, measured points and the true part. Each curve is 2 × n in
// plane coordinates (mm); `points` draws markers instead of a line.
struct PlaneView {
  struct Curve {
    std::string label;
    Eigen::Matrix2Xd xy;
    std::string color;  // CSS colour
    bool dashed = false, points = false, closed = false;
  };
  std::string title;
  std::string x_label, y_label;  // with units
  std::vector<Curve> curves;
  int width = 560;  // px
};

struct Section {
  std::string title;       // what the section shows ("Positioning accuracy of a linear axis")
  std::string source;      // the data it was made from (a file's name), shown under the title
  std::string intro_html;  // trusted HTML (escape user text!)
  std::vector<std::string> warnings;            // plain text, shown prominently before the intro
  std::vector<std::string> references;          // sources the section's methods follow (text)
  std::vector<std::vector<std::string>> table;  // first row = header; cells are escaped
  // Further tables after the first, each with a caption (first row = header).
  std::vector<std::pair<std::string, std::vector<std::vector<std::string>>>> more_tables;
  // Tables with a caption drawn after the figures: long listings the figures summarise.
  std::vector<std::pair<std::string, std::vector<std::vector<std::string>>>> tables_after;
  std::vector<Plot> plots;
  std::vector<SurfaceView> views;    // drawn first among the figures
  std::vector<HeatMap> heat_maps;    // drawn after the plots, side by side when they fit
  std::vector<DistortedGrid> grids;  // drawn after the heat maps
  std::vector<PlaneView> planes;     // drawn after the grids
  // The section's headline in one line of plain text ("flatness 4.3 µm (U = 0.4 µm)"): listed
  // with its title in the contents at the top of a report of three sections or more.
  std::string summary;
};

std::string escape(const std::string& text);

// Adds the reference lines of ISO 12780 to a plot of the profile y(x) (x and y in mm, the plot's
// y in mm × `scale`): the least-squares line (dashed) and the minimum zone, the two parallel
// lines closest together that enclose the profile (one legend entry for both). The figures
// themselves belong in the section's table, with their uncertainty. Each line carries values at
// the profile's two ends only (NaN between) and the plot spans gaps (Plot::span_gaps): a
// straight line needs no more. Precondition: x.size() == y.size() >= 2, x not all equal.
void add_reference_lines(Plot& plot, const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                         double scale);

// Sources cited by the sections (listed once under "References" at the end of a report).
namespace refs {
inline constexpr const char* kThreePoint =
    "Mitsubishi Heavy Industries, straightness measurement by the three-point method with pitch "
    "(sequential three-point method), Japanese patent JPH0464003B2.";
inline constexpr const char* kIso12780 =
    "ISO 12780-1/-2:2011, Geometrical product specifications: straightness (least-squares and "
    "minimum-zone reference lines).";
inline constexpr const char* kIso16610 =
    "ISO 16610-21:2011, Filtration: linear profile filters, Gaussian filters.";
inline constexpr const char* kMoody =
    "J. C. Moody, How to calibrate surface plates in the plant, The Tool Engineer, October 1955 "
    "(the Union Jack method).";
inline constexpr const char* kIso230 =
    "ISO 230-1:2012, Test code for machine tools, Part 1: geometric accuracy (error names "
    "E<component><axis>, squareness).";
inline constexpr const char* kIso230_2 =
    "ISO 230-2:2014, Test code for machine tools, Part 2: positioning accuracy and "
    "repeatability.";
inline constexpr const char* kIso230_4 =
    "ISO 230-4:2005, Test code for machine tools, Part 4: circular tests for numerically "
    "controlled machine tools (circular deviation G, radial deviation F, circular hysteresis H).";
inline constexpr const char* kVdi3441 =
    "VDI/DGQ 3441:1977, Statistical testing of the operational and positional accuracy of machine "
    "tools: basis (positional uncertainty P, deviation Pa, scatter Ps, reversal span U).";
inline constexpr const char* kIso1 =
    "ISO 1:2022, Geometrical product specifications: standard reference temperature (20 °C).";
inline constexpr const char* kOya =
    "M. Oya, H. Hokari, H. Tamura, A method of improving the accuracy of the three-coordinate "
    "measuring machine (2nd report: calibration method using the three-dimensional standard), "
    "Transactions of the JSME (C), 1988.";
inline constexpr const char* kIso10360_2 =
    "ISO 10360-2:2009, Acceptance and reverification tests for CMMs, Part 2: CMMs used for "
    "measuring linear dimensions (E0, the seven positions).";
inline constexpr const char* kIso10360_6 =
    "ISO 10360-6:2001, Estimation of errors in computing Gaussian associated features.";
inline constexpr const char* kShakarji =
    "C. M. Shakarji, Least-squares fitting algorithms of the NIST algorithm testing system, "
    "J. Res. NIST 103(6), 633-641, 1998.";
inline constexpr const char* kGum =
    "JCGM 100:2008, Evaluation of measurement data: Guide to the expression of uncertainty in "
    "measurement (GUM); expanded uncertainty U = k·u, k = 2.";
}  // namespace refs

// The plane of an error map spanned by axes a and b (0..2 = x, y, z) at node `at` of the third
// axis: in-plane errors as the node displacements, the third component as colour (µm). `name`
// starts the title, e.g. "XY plane".
DistortedGrid distorted_plane(const map::ErrorMap& map, int a, int b, Eigen::Index at,
                              const std::string& name, double magnification = 0);

// The SVG figures alone (an <svg> element each), for embedding elsewhere.
std::string svg(const HeatMap& h);
std::string svg(const DistortedGrid& g);
std::string svg(const SurfaceView& v);
std::string svg(const PlaneView& v);
// The largest "nice" magnification (1, 2 or 5 × 10^k) that draws an error of `max_error_um` as at
// most `fraction` of `step_mm`.
double nice_magnification(double max_error_um, double step_mm, double fraction = 0.4);

// Renders a complete HTML document.
// What the report is about, shown in its header after the date: (name, value) pairs such as
// ("machine", "Zeiss Prismo 7"), ("operator", "K. Tanaka"), ("temperature", "20.1 °C").
using Meta = std::vector<std::pair<std::string, std::string>>;

// Renders a complete HTML document: a header (title, date, `meta`, coverage factor), the
// sections, each table and plot with a CSV download link, and the references.
std::string render(const std::string& title, const std::vector<Section>& sections,
                   std::size_t max_points = 4000, const Meta& meta = {});

// Writes `html` to `path`, creating parent directories. Throws Error on failure.
void write(const std::string& path, const std::string& html);

// A section for a separation result: workpiece, guide (with ±2u bands when uncertainties
// exist) and pitch, the straightness values, reference and unobservable modes. If `truth` is
// given (same grids, same reference), it is overlaid and the recovery error tabulated.
Section separation_section(const std::string& title, const separation::Result& result,
                           const separation::Result* truth = nullptr);

}  // namespace trueaxis::report
