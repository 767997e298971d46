// trueaxis::ballgauge — gauge-block verification of a corrected CMM (in the manner of ISO 10360-2
// and of figure 10 of Oya, Hokari, Tamura 1988).
//
// Each measurement holds the two end points of a calibrated length as the CMM measured them (mm,
// machine frame, probe radius already compensated) and the length's calibrated value. The length
// error is |b − a| − nominal before correction and |X_b − X_a| − nominal after it, where X = x −
// Δ(x) is the corrected point (a grid map) or the identified parametric model's correction.
//
// What the "after" errors should be: the repeatability of the measurement itself (estimated from
// the repeats: rows with the same nominal length whose end points agree within
// `repeat_tolerance` belong to one position) and the correction's own uncertainty for that
// length. For a grid map, the length's uncertainty is d·(Δ(b) − Δ(a)) with the node
// uncertainties interpolated as variances and the two ends taken as independent (neighbouring
// nodes of a stitched map are positively correlated, so this leans high); a parametric model
// gives it exactly from its parameter covariance. predicted_after = sqrt(s_r² + mean u²). The
// grid's interpolation error between nodes is not in it (it is the part a simulation shows).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "trueaxis/map/error_map.hpp"

namespace trueaxis::ballgauge {

struct LengthMeasurement {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();  // measured end point (mm, machine frame)
  Eigen::Vector3d b = Eigen::Vector3d::Zero();  // measured end point (mm, machine frame)
  double nominal = 0;                           // calibrated length (mm), > 0
};

// A correction of measured points: `apply` maps measured x (3 × n, mm) to corrected X in place;
// `length_uncertainty(a, b)` is the standard uncertainty (mm) the correction adds to the length
// between measured points a and b (may be empty: taken as 0).
struct Correction {
  std::string name;  // e.g. "grid", "parametric"
  std::function<void(Eigen::Ref<Eigen::Matrix3Xd>)> apply;
  std::function<double(const Eigen::Vector3d&, const Eigen::Vector3d&)> length_uncertainty;
  // Optional: the same for many lengths at once (ends a.col(i), b.col(i)), used by
  // verify_lengths when present; a model whose uncertainty needs a design matrix per point
  // builds it once for all of them.
  std::function<Eigen::VectorXd(const Eigen::Matrix3Xd&, const Eigen::Matrix3Xd&)>
      length_uncertainties;
  // One point corrected (apply on a single column).
  Eigen::Vector3d corrected(const Eigen::Vector3d& x) const {
    Eigen::Matrix3Xd p = x;
    apply(p);
    return p.col(0);
  }
};

// The grid map's correction (trilinear unless `options` says cubic). Points outside the grid are
// refused unless options.outside is Clamp.
Correction grid_correction(const map::ErrorMap& map, const map::EvalOptions& options = {});

struct LengthOptions {
  double repeat_tolerance = 1.0;  // mm: rows are repeats when both ends agree this closely
  // Where length `index` (0-based) came from, for messages: end 1 or 2 (0: the length as a
  // whole), e.g. "lengths.csv:7:13: " for a file's line and column. Empty: the count alone.
  std::function<std::string(std::size_t index, int end)> locate;
  // mm: set-ups lie along one line, one ISO 10360-2 position, when their directions agree within
  // 2° and each one's middle lies this close to the line of the first.
  double line_tolerance = 25.0;
  void validate() const;  // throws Error
};

struct LengthRow {
  double nominal = 0;      // mm
  double before = 0;       // length error before correction (mm)
  double after = 0;        // after correction (mm)
  double uncertainty = 0;  // the correction's standard uncertainty for this length (mm)
  int position = 0;        // repeat group (0-based, in order of first appearance)
  // The line the set-up lies along, ISO 10360-2's "position" (0-based, in order of first
  // appearance); -1: not known (a file written before lines were found).
  int line = -1;
};

struct LengthStats {
  double min = 0, max = 0, mean = 0, rms = 0;  // mm
  double range() const { return max - min; }
};

struct LengthVerification {
  std::string correction;  // Correction::name
  std::vector<LengthRow> rows;
  LengthStats before, after;
  // Set-ups: a gauge length at one place (its end points within the repeat tolerance), measured
  // once or repeatedly. ISO 10360-2's positions are the lines set-ups lie along: 7 positions × 5
  // lengths make 35 set-ups.
  int positions = 0;
  double repeatability = 0;     // mm: pooled standard deviation of repeats (NaN: no repeats)
  double correction_u_rms = 0;  // mm: RMS over rows of the correction's length uncertainty
  double predicted_after = 0;   // mm: sqrt(repeatability² + correction_u_rms²) (NaN: no repeats)
  std::string summary() const;  // µm
  // The lines the set-ups lie along (ISO 10360-2's positions: 4 space diagonals and 3 others):
  // each one's unit direction in the machine frame, signed so that its largest component is
  // positive. Empty when not known.
  std::vector<Eigen::Vector3d> line_directions;
};

// A line's direction in words, a component below sin 2° taken as none: "along X", "XY plane
// diagonal (+X−Y)", "space diagonal (+X+Y−Z)" (a diagonal of the measuring volume, whatever its
// proportions; the signs are + and the minus sign U+2212, which a line is not broken after).
std::string direction_name(const Eigen::Vector3d& unit_direction);

// Throws Error: no measurements, a non-positive or non-finite nominal, non-finite or coincident
// end points, or (from the correction) points outside its domain; messages name the length by its
// 1-based count ("length 3: ...").
LengthVerification verify_lengths(const std::vector<LengthMeasurement>& lengths,
                                  const Correction& correction, const LengthOptions& options = {});

// A maximum permissible error of length measurement, ISO 10360-2 style: E0,MPE = A + L/K (µm, L
// in mm), optionally capped at B: written "A", "A+L/K" or "A+L/K,B" (e.g. "1.5+L/300").
struct Mpe {
  double a = 0;                                          // µm
  double k = 0;                                          // mm per µm; 0: no length term
  double cap = std::numeric_limits<double>::infinity();  // µm
  std::string text;                                      // as given
  double at(double length_mm) const;                     // µm
  // Throws Error naming what is wrong with the text.
  static Mpe parse(const std::string& text);
};

// The E0 check of one set of length errors against an MPE: every |E| ≤ MPE(L) passes (the
// simple acceptance of ISO 10360-2; the test's own uncertainty is not deducted).
struct MpeCheck {
  int lengths = 0, failed = 0;
  double worst_ratio = 0;  // largest |E| / MPE(L)
  bool pass() const { return failed == 0 && lengths > 0; }
};
MpeCheck check_mpe(const std::vector<LengthRow>& rows, const Mpe& mpe, bool after_correction);

}  // namespace trueaxis::ballgauge
