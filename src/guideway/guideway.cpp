#include "trueaxis/guideway/guideway.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "../common/eigen_instances.hpp"
#include "../common/figures.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::guideway {

namespace {

std::vector<int> indices(const std::array<bool, kErrors>& keep) {
  std::vector<int> v;
  for (int j = 0; j < kErrors; ++j)
    if (keep[static_cast<std::size_t>(j)]) v.push_back(j);
  return v;
}

Eigen::MatrixXd columns(const Eigen::MatrixXd& a, const std::vector<int>& cols) {
  Eigen::MatrixXd out(a.rows(), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t k = 0; k < cols.size(); ++k)
    out.col(static_cast<Eigen::Index>(k)) = a.col(cols[k]);
  return out;
}

// Columns scaled to unit norm (zero columns stay zero), so mm and rad unknowns compare.
Eigen::MatrixXd normalised(Eigen::MatrixXd a) {
  for (Eigen::Index j = 0; j < a.cols(); ++j) {
    const double n = a.col(j).norm();
    if (n > 0) a.col(j) /= n;
  }
  return a;
}

Eigen::VectorXd singular_values(const Eigen::MatrixXd& a) {
  if (a.cols() == 0) return {};
  return Eigen::JacobiSVD<Eigen::MatrixXd>(a).singularValues();
}

constexpr double kRankTol = 1e-10;

int rank(const Eigen::MatrixXd& a) {
  const Eigen::VectorXd sv = singular_values(a);
  if (sv.size() == 0 || sv[0] == 0) return 0;
  int r = 0;
  for (Eigen::Index i = 0; i < sv.size(); ++i) r += sv[i] > kRankTol * sv[0];
  return r;
}

// Infinite when rank-deficient, including fewer readings than unknowns (`cols`).
double condition(const Eigen::VectorXd& sv, Eigen::Index cols) {
  if (sv.size() < cols || sv.size() == 0 || !(sv[sv.size() - 1] > kRankTol * sv[0]))
    return std::numeric_limits<double>::infinity();
  return sv[0] / sv[sv.size() - 1];
}

std::string names_of(const std::vector<int>& idx) {
  std::string s;
  for (int j : idx) s += (s.empty() ? "" : ", ") + std::string(kErrorNames[j]);
  return s;
}

// v minus its least-squares line over s (closed form, no temporaries: these are 10⁶ long).
Eigen::VectorXd detrend(const Eigen::VectorXd& s, const Eigen::VectorXd& v) {
  const Eigen::Index n = s.size();
  const double sm = s.mean(), vm = v.mean();
  double sxx = 0, sxv = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double ds = s[i] - sm;
    sxx += ds * ds;
    sxv += ds * (v[i] - vm);
  }
  const double slope = sxx > 0 ? sxv / sxx : 0.0;
  Eigen::VectorXd out(n);
  for (Eigen::Index i = 0; i < n; ++i) out[i] = v[i] - vm - slope * (s[i] - sm);
  return out;
}

}  // namespace

void Qpd::validate() const {
  if (table_signal.size() != table_displacement.size())
    throw Error("qpd: the calibration table's signal and displacement lists differ in length");
  if (table_signal.size() == 1) throw Error("qpd: the calibration table needs at least 2 points");
  for (Eigen::Index i = 1; i < table_signal.size(); ++i)
    if (!(table_signal[i] > table_signal[i - 1]) ||
        !(table_displacement[i] > table_displacement[i - 1]))
      throw Error(fmt::format(
          "qpd: the calibration table must increase strictly in signal and displacement (entry "
          "{})",
          i + 1));
  if (table_signal.size() &&
      (!(table_signal.cwiseAbs().maxCoeff() < 1) || !table_displacement.allFinite()))
    throw Error("qpd: calibration signals must lie within (-1, 1) and displacements be finite");
  if (table_signal.size() == 0 && (!(gain > 0) || !std::isfinite(gain)))
    throw Error("qpd: give a positive gain (µm per unit signal) or a calibration table");
  if (!(min_sum >= 0) || !(max_signal > 0 && max_signal <= 1))
    throw Error("qpd: min_sum must be >= 0 and max_signal in (0, 1]");
}

double Qpd::displacement(double signal) const {
  if (table_signal.size() >= 2) {
    const Eigen::Index n = table_signal.size();
    if (!(signal >= table_signal[0] && signal <= table_signal[n - 1]))
      throw Error(fmt::format("signal {:.4f} is outside the calibration table [{:.4f}, {:.4f}]",
                              signal, table_signal[0], table_signal[n - 1]));
    const auto* first = table_signal.data();
    Eigen::Index i = std::upper_bound(first, first + n, signal) - first - 1;
    i = std::clamp<Eigen::Index>(i, 0, n - 2);
    const double t = (signal - table_signal[i]) / (table_signal[i + 1] - table_signal[i]);
    return table_displacement[i] + t * (table_displacement[i + 1] - table_displacement[i]);
  }
  if (!(std::abs(signal) <= max_signal))
    throw Error(
        fmt::format("signal {:.4f} is outside the linear range (|s| <= {:g})", signal, max_signal));
  return gain * signal;
}

Eigen::Vector2d Qpd::spot(double i1, double i2, double i3, double i4) const {
  const double sum = i1 + i2 + i3 + i4;
  if (!std::isfinite(sum) || !(sum > min_sum) || !(sum > 0))
    throw Error(fmt::format("spot lost: sum signal {:g} <= {:g}", sum, min_sum));
  return {displacement(((i1 + i4) - (i2 + i3)) / sum), displacement(((i1 + i2) - (i3 + i4)) / sum)};
}

double gaussian_signal(double x, double w) {
  return std::erf(std::sqrt(2.0) * x / w);
}

void Layout::validate() const {
  if (detectors.empty()) throw Error("layout: no detectors");
  std::set<std::string> seen;
  std::vector<Eigen::Vector3d> pos;
  std::vector<std::string> pos_names;
  bool angle = false;
  for (const auto& d : detectors) {
    if (d.name.empty()) throw Error("layout: a detector has no name");
    if (!seen.insert(d.name).second)
      throw Error(fmt::format("layout: detector name '{}' is used twice", d.name));
    if (d.kind == Kind::Angle) {
      if (!(d.focal_length > 0) || !std::isfinite(d.focal_length))
        throw Error(
            fmt::format("layout: angle detector '{}' needs a positive focal length (mm)", d.name));
      angle = true;
    } else {
      if (!d.position.allFinite())
        throw Error(fmt::format("layout: detector '{}' has a non-finite position", d.name));
      pos.push_back(d.position);
      pos_names.push_back(d.name);
    }
  }
  std::string list;
  for (const auto& n : pos_names) list += (list.empty() ? "" : ", ") + n;
  if (pos.size() >= 2) {
    Eigen::MatrixXd diff(3, static_cast<Eigen::Index>(pos.size() - 1));
    double scale = 0;
    for (std::size_t i = 1; i < pos.size(); ++i) {
      diff.col(static_cast<Eigen::Index>(i - 1)) = pos[i] - pos[0];
      scale = std::max(scale, (pos[i] - pos[0]).norm());
    }
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(diff).singularValues();
    const bool collinear = scale == 0 || sv.size() < 2 || sv[1] <= 1e-9 * sv[0];
    if (collinear && pos.size() >= 3)
      throw Error(fmt::format(
          "layout: the position detectors {} lie on one line; they must span a triangle (like "
          "the three spots of a classic layout) for roll and the two straightness errors to be "
          "separable",
          list));
    if (scale == 0)
      throw Error(fmt::format("layout: the position detectors {} are at the same point", list));
  }
  if (pos.size() < 3 && !angle)
    throw Error(fmt::format(
        "layout: {} position detector(s) ({}) and no angle detector cannot give five errors; use "
        "three non-collinear position detectors, or add an angle detector",
        pos.size(), list.empty() ? "none" : list));
}

Eigen::MatrixXd Layout::design() const {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * static_cast<Eigen::Index>(detectors.size()), 5);
  for (std::size_t i = 0; i < detectors.size(); ++i) {
    const auto& d = detectors[i];
    const auto r = 2 * static_cast<Eigen::Index>(i);
    if (d.kind == Kind::Angle) {
      a(r, 3) = d.focal_length;       // dx = f·εy
      a(r + 1, 2) = -d.focal_length;  // dy = −f·εx
    } else {
      const double x = d.position.x(), y = d.position.y(), z = d.position.z();
      a.row(r) << -1, 0, 0, -z, y;      // dx = −(δx + εy·z − εz·y)
      a.row(r + 1) << 0, -1, z, 0, -x;  // dy = −(δy + εz·x − εx·z)
    }
  }
  return a;
}

LayoutAnalysis analyze_layout(const Layout& layout) {
  layout.validate();
  const Eigen::MatrixXd a = layout.design();
  LayoutAnalysis r;
  r.observable.fill(true);
  // Drop unknowns that do not raise the rank, angles first, until the rest is of full rank.
  const int order[kErrors] = {3, 2, 4, 1, 0};
  for (;;) {
    const auto keep = indices(r.observable);
    const int rk = rank(normalised(columns(a, keep)));
    if (rk == static_cast<int>(keep.size())) break;
    bool dropped = false;
    for (int j : order) {
      if (!r.observable[static_cast<std::size_t>(j)]) continue;
      auto trial = r.observable;
      trial[static_cast<std::size_t>(j)] = false;
      if (rank(normalised(columns(a, indices(trial)))) == rk) {
        r.observable = trial;
        dropped = true;
        break;
      }
    }
    if (!dropped) break;  // cannot happen: some column is always dependent when rank < size
  }
  r.singular_values = singular_values(normalised(a));
  r.condition_number = condition(r.singular_values, kErrors);
  const auto keep = indices(r.observable);
  r.observable_condition_number = condition(singular_values(normalised(columns(a, keep))),
                                            static_cast<Eigen::Index>(keep.size()));
  std::vector<int> lost;
  for (int j = 0; j < kErrors; ++j)
    if (!r.observable[static_cast<std::size_t>(j)]) lost.push_back(j);
  if (!lost.empty()) {
    std::string sv;
    for (Eigen::Index i = 0; i < r.singular_values.size(); ++i)
      sv += fmt::format("{}{:.3g}", i ? ", " : "", r.singular_values[i]);
    r.message =
        fmt::format("unobservable with this layout: {} (singular values {})", names_of(lost), sv);
    bool angle = false;
    double zmin = INFINITY, zmax = -INFINITY;
    for (const auto& d : layout.detectors) {
      if (d.kind == Kind::Angle)
        angle = true;
      else {
        zmin = std::min(zmin, d.position.z());
        zmax = std::max(zmax, d.position.z());
      }
    }
    if (!angle && zmax - zmin <= 1e-9 * std::max(1.0, std::abs(zmax)) &&
        (!r.observable[2] || !r.observable[3]))
      r.message += fmt::format(
          ". All position detectors are at z = {:g} mm and there is no angle detector: pitch and "
          "yaw need detectors at different axial positions or an angle channel. The straightness "
          "values are those of the detectors' cross-section z = {:g} mm",
          zmin, zmin);
  }
  return r;
}

Result solve(const Layout& layout, const Eigen::VectorXd& s, const Eigen::MatrixXd& spots,
             const Options& options) {
  Result r;
  r.layout = analyze_layout(layout);
  const auto m = static_cast<Eigen::Index>(layout.detectors.size());
  if (spots.cols() != 2 * m)
    throw Error(fmt::format("guideway: {} reading columns for {} detectors (need dx and dy each)",
                            spots.cols(), m));
  if (spots.rows() != s.size())
    throw Error(
        fmt::format("guideway: {} rows of readings for {} positions", spots.rows(), s.size()));
  if (!s.allFinite() || !spots.allFinite())
    throw Error("guideway: positions and readings must be finite");
  if (!(options.sigma >= 0)) throw Error("guideway: sigma must be >= 0");
  const auto keep = indices(r.layout.observable);
  if (keep.empty()) throw Error("guideway: the layout observes none of the five errors");
  if (!(r.layout.observable_condition_number <= options.max_condition))
    throw Error(fmt::format(
        "guideway: the layout is too badly conditioned (condition number {:.3g} > {:.3g}); move "
        "the detectors further apart",
        r.layout.observable_condition_number, options.max_condition));

  // Factor once: P = A_S⁺ (k × 2m), then every position is one small matrix-vector product.
  const Eigen::MatrixXd a = columns(layout.design(), keep);
  const auto k = static_cast<Eigen::Index>(keep.size());
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  const Eigen::MatrixXd p = qr.solve(Eigen::MatrixXd::Identity(2 * m, 2 * m));
  // Blocks of positions small enough to stay in cache: one pass over the readings computes the
  // errors, the residuals and their sum of squares.
  const Eigen::Index n = s.size();
  r.s = s;
  for (Eigen::Index c = 0; c < k; ++c)
    r.value[static_cast<std::size_t>(keep[static_cast<std::size_t>(c)])].resize(n);
  r.residual.resize(n);
  double ss_res = 0;
  constexpr Eigen::Index kBlock = 2048;
  Eigen::MatrixXd qb(kBlock, k), rb(kBlock, 2 * m);
  for (Eigen::Index b = 0; b < n; b += kBlock) {
    const Eigen::Index nb = std::min(kBlock, n - b);
    auto q = qb.topRows(nb);
    auto res = rb.topRows(nb);
    q.noalias() = spots.middleRows(b, nb) * p.transpose();
    res = spots.middleRows(b, nb);
    res.noalias() -= q * a.transpose();
    r.residual.segment(b, nb) =
        (res.rowwise().squaredNorm() / static_cast<double>(2 * m)).cwiseSqrt();
    ss_res += res.squaredNorm();
    for (Eigen::Index c = 0; c < k; ++c)
      r.value[static_cast<std::size_t>(keep[static_cast<std::size_t>(c)])].segment(b, nb) =
          q.col(c);
  }
  const Eigen::Index dof = 2 * m - k;
  r.sigma = options.sigma;
  if (r.sigma == 0 && dof > 0 && s.size() > 0) {
    const double estimate = std::sqrt(ss_res / static_cast<double>(n * dof));
    // Residuals at round-off level are no noise estimate.
    if (!trueaxis::detail::is_round_off(estimate, spots.cwiseAbs().maxCoeff())) {
      r.sigma = estimate;
      r.sigma_estimated = true;
    } else {
      r.no_uncertainty = trueaxis::detail::noise_free_reason("the detectors'");
    }
  } else if (r.sigma == 0) {
    r.no_uncertainty =
        "the reading noise is unknown: no --sigma was given and the layout has no redundant "
        "readings to estimate it from";
  }
  const Eigen::MatrixXd cov = p * p.transpose();  // (AᵀA)⁻¹ for unit reading noise
  for (Eigen::Index c = 0; c < k; ++c) {
    const auto j = static_cast<std::size_t>(keep[static_cast<std::size_t>(c)]);
    r.uncertainty[j] = r.sigma * std::sqrt(cov(c, c));
  }
  for (std::size_t j = 0; j < kErrors; ++j) {
    if (r.value[j].size() == 0) continue;
    const Eigen::VectorXd* vp = &r.value[j];
    if (j < 2 && s.size() >= 2) {
      auto& st = j == 0 ? r.horizontal_straightness : r.vertical_straightness;
      st = detrend(s, r.value[j]);
      vp = &st;
    }
    const Eigen::VectorXd& v = *vp;
    if (v.size()) {
      r.pv[j] = v.maxCoeff() - v.minCoeff();
      r.rms[j] = std::sqrt(v.squaredNorm() / static_cast<double>(v.size()));
    }
  }
  return r;
}

std::optional<double> Result::pv_U(std::size_t j) const {
  if (j >= kErrors || value[j].size() == 0 || !(sigma > 0) || !std::isfinite(uncertainty[j]))
    return std::nullopt;
  return trueaxis::detail::peak_to_valley_U(uncertainty[j], value[j].size());
}

std::optional<bool> Result::resolved(std::size_t j) const {
  const std::optional<double> U = pv_U(j);
  if (!U) return std::nullopt;
  return *U < pv[j];
}

Eigen::Matrix3d carriage_axes(int axis) {
  if (axis < 0 || axis > 2) throw Error("guideway: the machine axis must be 0, 1 or 2 (X, Y, Z)");
  Eigen::Matrix3d m;
  switch (axis) {
    case 0:  // travel X: horizontal Y, vertical Z
      m << 0, 0, 1, 1, 0, 0, 0, 1, 0;
      break;
    case 1:  // travel Y: horizontal −X, vertical Z
      m << -1, 0, 0, 0, 0, 1, 0, 1, 0;
      break;
    default:  // travel Z: x = X, y = Y
      m.setIdentity();
  }
  return m;
}

std::array<IsoName, kErrors> iso_names(int axis) {
  const Eigen::Matrix3d m = carriage_axes(axis);
  const char* travel = "XYZ";
  const char* translation = "XYZ";
  const char* rotation = "ABC";
  // Error j moves along (translations) or about (rotations) carriage axis c: δx, δy along x, y;
  // εx, εy, εz about x, y, z. That axis is ± one machine axis.
  const int along[kErrors] = {0, 1, 0, 1, 2};
  std::array<IsoName, kErrors> out;
  for (int j = 0; j < kErrors; ++j) {
    Eigen::Index k = 0;
    m.col(along[j]).cwiseAbs().maxCoeff(&k);
    out[static_cast<std::size_t>(j)] = {
        fmt::format("E{}{}", j < 2 ? translation[k] : rotation[k], travel[axis]),
        m(k, along[j]) > 0 ? 1.0 : -1.0};
  }
  return out;
}

std::string Result::name(std::size_t j) const {
  if (axis < 0) return kErrorNames[j];
  return fmt::format("{} ({})", iso_names(axis)[j].name, kErrorNames[j]);
}

double Result::sign(std::size_t j) const {
  return axis < 0 ? 1.0 : iso_names(axis)[j].sign;
}

std::string Result::summary() const {
  std::string out =
      fmt::format("guideway: {} positions, condition number {:.3g} (observable part)\n", s.size(),
                  layout.observable_condition_number);
  const int width = axis < 0 ? 10 : 18;
  for (std::size_t j = 0; j < kErrors; ++j) {
    const bool angle = j >= 2;
    if (value[j].size() == 0) {
      out += fmt::format("  {:<{}} not observable\n", name(j), width);
      continue;
    }
    const double sc = angle ? 1e6 : 1e3;
    const char* unit = angle ? "urad" : "um";
    if (const std::optional<double> U = pv_U(j)) {
      if (!*resolved(j))
        out += fmt::format("  {:<{}} PV not resolved (U = {} {}, 95 %)\n", name(j), width,
                           trueaxis::detail::two_digits(*U * sc), unit);
      else
        out += fmt::format("  {:<{}} PV {} {}, RMS {} {}, U = {} {} (95 %)\n", name(j), width,
                           trueaxis::detail::rounded_to(pv[j] * sc, *U * sc), unit,
                           trueaxis::detail::rounded_to(rms[j] * sc, *U * sc), unit,
                           trueaxis::detail::two_digits(*U * sc), unit);
    } else {
      out += fmt::format("  {:<{}} PV {:.4g} {}, RMS {:.4g} {}\n", name(j), width, pv[j] * sc, unit,
                         rms[j] * sc, unit);
    }
  }
  if (sigma > 0)
    out +=
        fmt::format("  reading noise sigma {} µm ({})\n", trueaxis::detail::two_digits(sigma * 1e3),
                    sigma_estimated ? "estimated from the residuals" : "given");
  else if (!no_uncertainty.empty())
    out += "  no uncertainty: " + no_uncertainty + "\n";
  if (!layout.message.empty()) out += "  " + layout.message + "\n";
  return out;
}

}  // namespace trueaxis::guideway
