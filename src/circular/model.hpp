// The circular test's diagnosis model: the samples a fit runs over, the causes' signatures as
// the columns of a design matrix, and the least squares that sizes them (the public header
// include/trueaxis/circular/circular.hpp states each signature and its sign convention).
// Internal to src/circular.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <string>
#include <vector>

#include "trueaxis/circular/circular.hpp"

namespace trueaxis::circular::detail {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kTwoPi = 2 * kPi;

double wrap(double angle);  // into [0, 2π)
inline double sign(double v) {
  return v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0;
}

// A column of the design: what it is; its values are the design matrix' column of the same index.
struct Column {
  std::string key, name, unit;
  double to_unit;  // library value × to_unit = value in `unit`
};

// The samples a design is built over: angle, its cosine and sine, and the direction's sign
// (+1 ccw, −1 cw), computed once.
struct Samples {
  Eigen::VectorXd th, w, cs, sn, s;  // w: θ wrapped into [0, 2π)
  Eigen::Index size() const { return th.size(); }
  static Samples of(const Trace& t, const std::vector<Eigen::Index>& idx);
  Samples subset(const std::vector<Eigen::Index>& idx) const;  // idx: positions in this
};

// The columns that do not depend on the spikes' decay or the reversals' delay (centre offset,
// radius, squareness, scale and lag mismatch, straightness, cyclic errors of given pitches),
// their values written into F (n × fixed_count(o)); returns what they are.
Eigen::Index fixed_count(const Options& o);
std::vector<Column> fixed_columns(const Samples& x, const Options& o,
                                  Eigen::Ref<Eigen::MatrixXd> F);

// The columns that do: backlash per axis, then the reversal spikes per axis and direction run
// (the ones run: `ccw`, `cw`), written into V (n × varying_count(ccw, cw)). The spike after a
// reversal at r, Δθ = the angle travelled since r, is exp(−Δθ/d), summed over the axis' last
// two reversals. An axis reverses `delay` (rad) after the commanded reversal, in the direction
// of travel (its following lag's phase).
int varying_count(bool ccw, bool cw);
void varying_matrix(const Samples& x, double decay, const std::array<double, 2>& delay, bool ccw,
                    bool cw, Eigen::Ref<Eigen::MatrixXd> V);
std::vector<Column> varying_columns(const Options& o, bool ccw, bool cw);
// Parts of V, for a search that moves one axis' delay or the decay at a time: the backlash of
// `axis` (V's column `axis`); its spike columns, from V's column spike_column(axis, ccw, cw).
void backlash_column(const Samples& x, int axis, double delay, Eigen::Ref<Eigen::VectorXd> v);
void spike_columns(const Samples& x, int axis, double decay, double delay, bool ccw, bool cw,
                   Eigen::Ref<Eigen::MatrixXd> V, Eigen::Index col);
Eigen::Index spike_column(int axis, bool ccw, bool cw);
// The angle travelled since `axis` last reversed, per sample: in [0, π), as an axis reverses
// twice a turn.
Eigen::ArrayXd since_reversal(const Samples& x, int axis, double delay);

struct Fit {
  Eigen::VectorXd beta;                    // per column (NaN where dropped)
  Eigen::MatrixXd cov_unit;                // (JᵀJ)⁻¹ over the kept columns, library units
  std::vector<int> kept;                   // column indices solved for
  std::vector<std::vector<int>> confused;  // groups the data cannot tell apart
  double rss = 0;                          // yᵀy − βᵀJᵀy (the normal equations' own)
};

// Least squares from the normal equations N = JᵀJ, c = Jᵀy, yy = yᵀy over the columns, scaled to
// unit norm: the columns the data cannot tell apart are found from N's near-null directions and
// all but the first of each group left out; the rest solved by Cholesky. Columns with no effect
// (zero diagonal) are left out. With the columns scaled, N's condition is that of the
// signatures' correlations (|corr| < 0.995 kept apart: a condition below ~10⁴). Without
// `covariance`, cov_unit is left empty.
Fit solve_normal(const Eigen::MatrixXd& N0, const Eigen::VectorXd& c0, double yy,
                 bool covariance = true);

}  // namespace trueaxis::circular::detail
