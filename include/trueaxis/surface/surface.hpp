// trueaxis::surface — error surfaces from networks of straightness lines (Moody 1955 for
// plates; straightness lines by the sequential two-point method, "Trend of straightness measuring
// method and development of sequential two-point method", Seisan Kenkyu 34(6), 25–34, 1982).
//
// Frame: plane coordinates x, y in mm (right-handed; for a surface plate x from West to East and
// y from South to North); heights z in mm along the plane normal, positive up. Each measured line
// gives heights along its own direction, known only up to an offset and a tilt (a + b·t); the
// builder chooses them so that the lines agree where they cross.
//
// What a network can determine: the plane part (c0 + c1·x + c2·y) never (it is the reference,
// fixed here as the least-squares plane of all points); the twist c3·x·y only when some line is
// not parallel to an axis (a diagonal). Result::unobservable names what was free and
// Result::gauge says how it was fixed.
#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace trueaxis::surface {

// One straightness line on the plane.
struct Line {
  std::string name;
  Eigen::Vector2d start = Eigen::Vector2d::Zero();       // station 0 (mm)
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();  // unit vector (normalised by validate())
  double spacing = 0;                                    // mm between stations, > 0
  Eigen::VectorXd heights;                               // mm at stations 0..n-1 (n >= 2)
  Eigen::Vector2d station(long k) const {
    return start + direction * (static_cast<double>(k) * spacing);
  }
  double length() const { return spacing * static_cast<double>(heights.size() - 1); }
};

// Heights from slope readings (autocollimator or level): one slope (rad) per foot of length
// `spacing`, the i-th over stations i-1..i. Returns n+1 heights with h_0 = 0.
Eigen::VectorXd heights_from_slopes(const Eigen::VectorXd& slopes, double spacing);

enum class Method {
  Seed,  // the two-point patent's construction: X lines hung on the two boundary Y lines at their
         // ends
  Lsq    // all offsets and tilts jointly, crossings agreeing in the least-squares sense
};

struct Options {
  Method method = Method::Lsq;
  // Two lines cross when their centre lines pass within this distance (mm) inside both extents.
  double crossing_tolerance = 1e-6;
};

struct Point {
  int line = 0;  // index into Result::lines
  long station = 0;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double height = 0;  // mm, relative to the reference (see Result::reference)
};

struct Crossing {
  int a = 0, b = 0;       // line indices
  double ta = 0, tb = 0;  // mm along each line
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double residual = 0;  // height on a minus height on b after assembly (mm)
};

// Heights on a rectangular lattice, when every lattice point of the layout was measured.
struct Grid {
  Eigen::VectorXd x, y;    // mm, ascending
  Eigen::MatrixXd height;  // height(iy, ix), mm
};

struct Result {
  std::string method;  // "seed", "lsq", "moody" or "moody-lsq"
  std::vector<std::string> lines;
  std::vector<Point> points;  // every station of every line
  std::vector<Crossing> crossings;
  double closure_rms = 0, closure_max = 0;        // over crossings (mm)
  double flatness_ls = 0, flatness_min_zone = 0;  // mm
  std::string reference;                          // what height zero means
  std::vector<std::string> unobservable;          // e.g. "plane", "twist"
  std::string gauge;                              // how the free modes were fixed
  std::optional<Grid> grid;
  // Why the flatness carries no uncertainty, in words: the lines come without a noise level, and
  // their closure at the crossings is shown instead (never a zero uncertainty).
  std::string no_uncertainty() const;
  std::string summary() const;  // human-readable, µm
};

// Assembles a surface from lines. Throws Error for invalid lines, lines that cross no other line
// (or networks in several unconnected pieces), and, in seed mode, layouts without an X family
// and two boundary Y lines at its ends.
Result build(std::vector<Line> lines, const Options& options = {});

// Moody's Union Jack (1955). The eight lines by their file names; readings in arc-seconds, one
// per foot of `foot_spacing` mm.
inline constexpr const char* kMoodyLines[8] = {"NW_SE", "NE_SW", "NE_NW", "SE_SW",
                                               "E_W",   "NE_SE", "NW_SW", "N_S"};
struct MoodyData {
  std::map<std::string, Eigen::VectorXd> readings;  // arc-seconds, keys from kMoodyLines
  double foot_spacing = 0;                          // mm
};
// Classic worksheet (Moody 1955): heights with the lowest point at zero, exactly as Moody's
// tables. `least_squares`: the same lines assembled by build() with Method::Lsq (closure at every
// crossing, heights about the LS plane).
Result moody(const MoodyData& data, bool least_squares = false);

}  // namespace trueaxis::surface
