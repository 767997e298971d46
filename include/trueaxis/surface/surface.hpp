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
  // State the flatness's uncertainty (Result::U; 200 assemblies of noise, reusing the network's
  // factorisation): off where only the heights are wanted.
  bool uncertainty = true;
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
  // The flatness's expanded uncertainty (95 %, mm), from the readings' noise as the lines'
  // disagreement at the crossings shows it: every reading (a height, or a Moody slope) is taken
  // independent, with one standard deviation for all lines, estimated from the closure and
  // propagated through the same assembly by Monte Carlo (JCGM 101:2008, 200 trials); then
  // U = detail::peak_to_valley_U(u_max, points). Unset when the network cannot show the noise
  // (no redundant crossing, or lines that agree to round-off): no_uncertainty() says why.
  std::optional<double> U;
  double sigma = 0;        // estimated standard deviation of one reading, in sigma_unit
  std::string sigma_unit;  // "um" (heights) or "arc-second" (Moody's slopes)
  int redundancy = 0;      // independent closure conditions: crossings less the modes they fix
  double u_max = 0;        // mm, the largest standard uncertainty of a point's height
  std::optional<bool> resolved() const {
    if (!U) return std::nullopt;
    return *U < flatness_min_zone;
  }
  // Why the flatness carries no uncertainty, in words (empty when U is set); never a zero.
  std::string no_uncertainty() const { return no_uncertainty_reason; }
  std::string no_uncertainty_reason;
  // How U was obtained, in words ("reading noise 0.12 um from the closure at 22 crossings, 9
  // degrees of freedom"); empty without U.
  std::string uncertainty_basis() const;
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
