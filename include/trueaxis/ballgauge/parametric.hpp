// trueaxis::ballgauge — the 21 rigid-body errors of a CMM identified from ball-gauge data (beyond
// Oya, Hokari, Tamura 1988, who map error vectors only; the errors are ISO 230-1's, the model that
// of sim/machine.hpp).
//
// Every error function of axis k (E_Xk … E_Ck) is a polynomial of degree `degree` in the axis
// coordinate, (u/1 m)^q for q = 0..degree, plus the three squareness errors. A ball measured at
// reading x (machine frame, mm; its command is c = x − offset) whose true centre is X = R_p·U_i +
// t_p (placement p's unknown pose, gauge coordinates U_i) obeys
//
//     x = X − e(c),   e(c) = actual(c) − nominal(c)   (sim/machine.hpp, exact rotations),
//
// so the unknowns are the polynomial coefficients and six pose parameters per placement. Each
// placement may be probed with a stylus of its own (Placement::stylus_offset): its commands are
// its readings less its offset, and its design columns are the model's at that offset, so that a
// horizontal stylus lets the data see the roll errors a vertical one cannot. The
// equations are linearised about zero errors (first order, the usual small-error model of
// identification: the design columns are central differences of the exact model) and solved by
// Gauss–Newton on the exact model until the step vanishes, with a rank-revealing SVD of the
// column-scaled design: the data cannot tell a rigid motion of the whole map, nor an error function
// that does not move this stylus tip (e.g. E_CZ, roll about the ram, when the stylus hangs straight
// down), and those directions take the minimum-norm value. Placements need no overlap and no
// alignment type: each one's pose is estimated with the errors.
//
// Each axis must be sampled at more than `degree` distinct positions; otherwise a polynomial could
// wiggle unseen between them, and identify() refuses. The identified machine's range is the span
// of the measured commands: the model is not extrapolated.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::ballgauge {

struct ParametricOptions {
  std::string chain = "FYXZ";  // kinematic chain (sim/machine.hpp)
  // The stylus offset (mm) of every placement that states none (Placement::stylus_offset), and the
  // stylus the identified model corrects for (parametric_correction).
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  int degree = 3;                   // polynomial degree of every error function, 1..8
  double position_tolerance = 1;    // mm: axis positions closer than this count as one
  long min_points = 5;              // probed points per ball
  double outlier_tolerance = 0.02;  // mm: wrong touches, as for the map (ballgauge.hpp)
  bool drop_outliers = false;
  int max_iterations = 10;  // Gauss–Newton
  void validate() const;    // throws Error
};

// The identified machine's ISO 230-1 figures at the tool point (sim::reference_lines over the
// identified span, the other axes mid-span): straightness about each axis' reference line and
// squareness as the angles between reference lines, with standard uncertainties from the
// parameter covariance (first order). Unlike the model's own squareness parameters, these do
// not depend on how the data's unfixed rigid rotation splits between the straightness slopes and
// the squareness parameters.
struct IsoFigures {
  sim::ReferenceLines lines;
  std::array<std::array<double, 2>, 3> u_straightness{};  // mm, as lines.straightness
  double u_c0y = 0, u_b0z = 0, u_a0z = 0;                 // rad
};

struct ParametricResult {
  sim::Machine model;  // identified errors (polynomials); range = the measured span per axis
  // The parameters: per axis k, per component j (X, Y, Z, A, B, C), the coefficients of the
  // Chebyshev polynomials T_q(s), q = 0..degree, s = (u_k − centre_k)/half_span_k ∈ [−1, 1] over
  // the measured span (index (k·6 + j)·(degree+1) + q; mm or rad), then E_C0Y, E_B0Z, E_A0Z (rad).
  // The model's polynomials are the same functions in powers of u/1 m (sim::ErrorFunction).
  Eigen::VectorXd parameters;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();     // mm, per axis
  Eigen::Vector3d half_span = Eigen::Vector3d::Ones();  // mm, per axis
  Eigen::MatrixXd covariance;  // of `parameters` (pseudo-inverse on the unobservable part)
  double residual_rms = 0;     // mm, ball centre components after the fit
  double sigma = 0;            // mm, estimated standard deviation of a centre component
  int balls = 0, placements = 0, unknowns = 0, rank = 0, iterations = 0;
  // The styli the placements were probed with (offsets, mm; model.offset is options.offset), in
  // the order of first use, each with the names of the placements that used it.
  struct Stylus {
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    std::vector<std::string> placements;
  };
  std::vector<Stylus> styli;
  std::vector<std::string> unobservable;  // error functions with no effect on these data
  int degree = 3;
  IsoFigures iso;               // from model and covariance (iso_figures)
  std::string summary() const;  // µm, µrad

  // The error e(c) = actual − nominal (mm) at commands c (3 × n) and its first-order design
  // matrix d e / d parameters (3 × parameters.size()) at one command.
  Eigen::MatrixXd design(const Eigen::Vector3d& command) const;
};

// Throws Error: invalid options, fewer than 3 balls in a placement, too few points on a ball,
// unknown ball indices, an axis sampled at too few positions for the degree.
ParametricResult identify(const Gauge& gauge, const std::vector<Placement>& placements,
                          const ParametricOptions& options = {});

// The ISO 230-1 figures of an identified model (its model, degree, centre, half_span,
// parameters and covariance).
IsoFigures iso_figures(const ParametricResult& result);

// Correction X = x + e(x − offset) by the identified model, refusing points whose command lies
// outside the identified span (tolerance 1e-6 mm); its length uncertainty comes from the
// parameter covariance (correlations included).
Correction parametric_correction(const ParametricResult& result);

}  // namespace trueaxis::ballgauge
