// Straightness separation (multi-probe error separation): the driver. It checks the data, runs
// the method (two- or three-point recurrence, or the least-squares solve), applies the reference,
// propagates the uncertainties and reports; solution.hpp lists the file of each part.
#include "trueaxis/separation/separation.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "../common/figures.hpp"
#include "../geometry/profile_min_zone.hpp"
#include "solution.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/straightness.hpp"

namespace trueaxis::separation {
namespace {

constexpr double kStepTolerance = 1e-6;  // relative tolerance for equal steps / whole multiples

}  // namespace

const char* to_string(Method m) {
  switch (m) {
    case Method::TwoPoint:
      return "two-point";
    case Method::ThreePoint:
      return "three-point";
    case Method::Lsq:
      return "lsq";
  }
  return "?";
}

const char* to_string(Reference r) {
  switch (r) {
    case Reference::LeastSquares:
      return "ls";
    case Reference::Seed:
      return "patent";
    case Reference::MinZone:
      return "min-zone";
  }
  return "?";
}

Method method_from_string(const std::string& s) {
  if (s == "two-point") return Method::TwoPoint;
  if (s == "three-point") return Method::ThreePoint;
  if (s == "lsq") return Method::Lsq;
  throw Error(fmt::format("unknown method '{}' (expected two-point, three-point or lsq)", s));
}

Reference reference_from_string(const std::string& s) {
  if (s == "ls") return Reference::LeastSquares;
  if (s == "patent" || s == "seed") return Reference::Seed;  // "seed": earlier files
  if (s == "min-zone") return Reference::MinZone;
  throw Error(fmt::format("unknown reference '{}' (expected ls, patent or min-zone)", s));
}

double ProbeData::step() const {
  if (x.size() < 2) throw Error("need at least two stations");
  return (x[x.size() - 1] - x[0]) / static_cast<double>(x.size() - 1);
}

namespace {

// ProbeData::validate in three parts, so that separate() can check the values (one pass over all
// the data) on another core while the method runs; the errors are the same, in the same order.
void check_shapes(const ProbeData& d) {
  const Eigen::Index n = d.x.size();
  const auto& readings = d.readings;
  const auto& offsets = d.offsets;
  const auto& angle = d.angle;
  if (n < 3) throw Error(fmt::format("too few stations: {} (need at least 3)", n));
  if (readings.rows() != n)
    throw Error(fmt::format("readings have {} rows but there are {} stations", readings.rows(), n));
  if (readings.cols() < 2) throw Error("need at least two probes");
  if (static_cast<Eigen::Index>(offsets.size()) != readings.cols())
    throw Error(
        fmt::format("{} probe offsets for {} probe columns", offsets.size(), readings.cols()));
  if (angle.size() != 0 && angle.size() != n)
    throw Error(fmt::format("angle channel has {} values for {} stations", angle.size(), n));
}

// Checks the values and returns the range of all probe readings (mm), found in the same pass.
double check_values(const ProbeData& data) {
  const Eigen::Index n = data.x.size();
  const auto& x = data.x;
  const auto& readings = data.readings;
  const auto& angle = data.angle;
  // One vectorised pass per array decides; only a failure looks for the first offender. v·0 is
  // NaN for a NaN or an infinity, else 0; the reductions keep vector accumulators, so each pass
  // runs at memory speed.
  bool all_finite = (Eigen::Map<const Eigen::ArrayXd>(angle.data(), angle.size()) * 0.0).sum() == 0;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (Eigen::Index j = 0; j < readings.cols() && all_finite; ++j) {
    const double* v = readings.col(j).data();
    double nonfinite = 0;
#pragma omp simd reduction(min : lo) reduction(max : hi) reduction(+ : nonfinite)
    for (Eigen::Index k = 0; k < n; ++k) {
      nonfinite += v[k] * 0.0;
      lo = v[k] < lo ? v[k] : lo;
      hi = v[k] > hi ? v[k] : hi;
    }
    all_finite = nonfinite == 0;
  }
  if (!all_finite) throw Error("non-finite value (NaN or Inf) in the data");
  // x's own check rides on the pass over its steps (which are used only once x is finite).
  const double* xp = x.data();
  const double h = n >= 2 ? data.step() : 0.0;  // (not finite with x: reported below)
  const double tolerance = kStepTolerance * h + 1e-12;
  double smallest = h, worst = 0, x_finite = n ? xp[0] * 0.0 : 0.0;
#pragma omp simd reduction(min : smallest) reduction(max : worst) reduction(+ : x_finite)
  for (Eigen::Index k = 1; k < n; ++k) {
    const double d = xp[k] - xp[k - 1];
    x_finite += xp[k] * 0.0;
    smallest = std::min(smallest, d);
    worst = std::max(worst, std::abs(d - h));
  }
  if (!(x_finite == 0)) throw Error("non-finite value (NaN or Inf) in the data");
  if (n < 2) data.step();  // throws its error
  if (!(h > 0)) throw Error("station positions must increase");
  const bool uneven = !(smallest > 0) || worst > tolerance;
  for (Eigen::Index k = 1; k < n && uneven; ++k) {
    const double d = x[k] - x[k - 1];
    if (!(d > 0))
      throw Error(fmt::format("station {} does not increase (x = {} after {})", k, x[k], x[k - 1]));
    if (std::abs(d - h) > tolerance)
      throw Error(fmt::format("uneven step at station {}: {} mm instead of {} mm", k, d, h));
  }
  return n > 0 && readings.cols() > 0 ? hi - lo : 0.0;
}

void check_offsets(const ProbeData& d) {
  const auto& offsets = d.offsets;
  const double h = d.step();
  if (offsets[0] != 0) throw Error("the first probe offset must be 0 (offsets are from probe A)");
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    const double r = offsets[i] / h;
    if (!std::isfinite(r) ||
        std::abs(r - std::round(r)) > kStepTolerance * std::max(1.0, std::abs(r)))
      throw Error(fmt::format("probe offset {} mm is not a whole multiple of the step {} mm",
                              offsets[i], h));
    for (std::size_t j = 0; j < i; ++j)
      if (std::round(offsets[j] / h) == std::round(r))
        throw Error(
            fmt::format("probes {} and {} have the same offset {} mm", j + 1, i + 1, offsets[i]));
  }
}

}  // namespace

void ProbeData::validate() const {
  check_shapes(*this);
  check_values(*this);
  check_offsets(*this);
}

void Options::validate() const {
  if (sigma && !(*sigma > 0 && std::isfinite(*sigma))) throw Error("sigma must be positive");
  if (!(angle_sigma > 0 && std::isfinite(angle_sigma))) throw Error("angle sigma must be positive");
  if (!(nominal_sigma > 0)) throw Error("nominal sigma must be positive");
  if (!(filter_cutoff >= 0 && std::isfinite(filter_cutoff)))
    throw Error("filter cut-off must be >= 0");
  if (zero_difference && !std::isfinite(*zero_difference))
    throw Error("zero difference must be finite");
  if (reference == Reference::Seed && method != Method::ThreePoint)
    throw Error("reference 'patent' is defined for the three-point method only");
}

namespace {

using detail::apply_reference;
using detail::direct_uncertainties;
using detail::kTwoCorePoints;
using detail::lsq_uncertainties;
using detail::LsqState;
using detail::LsWidths;
using detail::policy_for;
using detail::Raw;
using detail::recurrence_arrays;
using detail::recurrence_uncertainties;
using detail::regions_of;
using detail::solve_lsq;
using detail::solve_lsq_direct;
using detail::three_point;
using detail::two_point;

// `ls`: the least-squares straightness when already known (not NaN). x is one of separate()'s
// grids, strictly increasing by construction from the checked stations.
Straightness straightness_of(const Eigen::VectorXd& x, const Eigen::VectorXd& v, double ls) {
  Straightness s;
  s.ls = std::isnan(ls) ? geometry::ls_straightness(x, v) : ls;
  s.min_zone = geometry::detail::min_zone_of_increasing(x, v).width;
  return s;
}

}  // namespace

Result detail::separate(const ProbeData& data, const Options& opt, LsqSolver solver) {
  // A recurrence's arrays are known in size from the start: their pages are committed on another
  // core while the data are checked and the recurrence runs.
  Raw raw;
  std::optional<detail::Prefault> prefault;
  if (opt.method != Method::Lsq) {
    raw = recurrence_arrays(opt.method, data.x.size());
    prefault.emplace(regions_of(raw));
  }
  check_shapes(data);
  const long n = data.x.size();
  // The values (finite, evenly stepped: one pass over all the data) are checked on another core
  // while the offsets, the layout and the method go on. Their error, if any, is the one reported,
  // as if they had been checked first, and nothing computed from the data is used before.
  std::future<double> values =
      std::async(n >= kTwoCorePoints ? std::launch::async : std::launch::deferred,
                 [&data] { return check_values(data); });
  bool values_known = false;
  double readings_span = 0;
  auto values_first = [&] {  // rethrows the values' error, once
    if (values_known) return;
    values_known = true;
    readings_span = values.get();
  };
  Result res;
  res.method = opt.method;
  res.reference = opt.reference;
  const double h = data.step();
  const bool angle = data.angle.size() == n;
  std::vector<long> p;
  // The least-squares solve gives the Lsq answer and its covariance. The recurrences (A, B)
  // propagate each reading exactly through their own equations. Without redundancy (A, B) the
  // noise level cannot be estimated, so their uncertainty needs a given sigma.
  const bool unc_possible =
      opt.compute_uncertainty && opt.filter_cutoff == 0 && opt.reference != Reference::Seed;
  LsqState st;
  try {
    check_offsets(data);
    // Offsets of an absurd number of steps can only come from a broken x (which the values check
    // reports): nothing is sized by them before that check has answered.
    constexpr double kAbsurdSteps = 2147483647.0;
    for (double s : data.offsets)
      if (!(std::abs(s / h) <= kAbsurdSteps)) values_first();
    opt.validate();
    for (double s : data.offsets) p.push_back(std::lround(s / h));
    // The layout must be observable (beyond line and, by convention, parabola) for every method.
    const LayoutAnalysis la = analyze_layout(p, angle, opt.zero_difference.has_value(), n);
    if (!la.observable) throw Error(la.message);
    res.unobservable = la.unobservable;
    switch (opt.method) {
      case Method::TwoPoint:
        two_point(data, raw);
        break;
      case Method::ThreePoint:
        three_point(data, opt.zero_difference, raw);
        break;
      case Method::Lsq:
        if (solver == detail::LsqSolver::Automatic && detail::direct_layout(p, angle)) {
          // Its uncertainties need the grids only, and a noise level that only a given sigma can
          // set (no redundancy): they are propagated on another core while the solve runs.
          if (unc_possible) {
            const bool with_pitch = opt.sigma.has_value();
            const double noise_var = with_pitch ? *opt.sigma * *opt.sigma : 1.0;
            st.propagation = std::async(
                n >= kTwoCorePoints ? std::launch::async : std::launch::deferred,
                [&st, &data, h, with_pitch, noise_var, par = !opt.zero_difference] {
                  direct_uncertainties(data.x, par, with_pitch, h, noise_var, st.uw, st.ug, st.ut);
                });
          }
          raw = solve_lsq_direct(data, opt);
        } else {
          raw = solve_lsq(data, opt, st);
        }
        break;
    }
  } catch (...) {
    values_first();  // the values' error first
    throw;
  }
  values_first();
  raw.xg_increasing = true;  // every method's guide grid is the stations, now checked
  const bool want_unc = unc_possible && (opt.method == Method::Lsq || opt.sigma.has_value());
  res.dof = st.engine ? st.dof : 0;

  LsWidths widths;  // NaN unless the reference found them
  if (opt.reference == Reference::Seed) {
    res.gauge =
        "patent (JPH0464003B2): X_0 = Y_0 = 0, alpha = X_1 and beta = 2Y_1 - Y_2 minimise sum of "
        "X_K^2 (K >= 2); "
        "pitch relative to the first station";
    if (opt.zero_difference) res.gauge += "; beta from the known zero difference";
  } else {
    widths = apply_reference(raw, opt.reference);
    res.gauge = opt.reference == Reference::MinZone
                    ? "workpiece and guide relative to the middle lines of their minimum zones"
                    : "workpiece and guide are residuals from their own least-squares lines";
    if (raw.theta.size()) res.gauge += "; pitch about its mean";
    if (raw.parabola_free)
      res.gauge += "; parabola: the guide is taken to have no quadratic (least-squares) component";
    else if (opt.zero_difference)
      res.gauge += "; parabola fixed by the known zero difference";
    else if (angle)
      res.gauge += "; parabola fixed by the angle channel";
  }

  Eigen::VectorXd uw, ug, ut;
  if (unc_possible) {
    double s2 = 0;
    if (want_unc && opt.sigma) {
      s2 = (*opt.sigma) * (*opt.sigma);
      res.sigma = opt.sigma;
    } else if (want_unc && st.dof > 0) {
      // Every row (probe, or angle scaled by its weight) carries the probe noise, so the
      // residual variance estimates the probe variance directly.
      s2 = st.ssr / static_cast<double>(st.dof);
      // Residuals at round-off level are no noise estimate.
      const double size = data.readings.size() ? data.readings.cwiseAbs().maxCoeff() : 0.0;
      if (!trueaxis::detail::is_round_off(std::sqrt(s2), size)) {
        res.sigma = std::sqrt(s2);
        res.sigma_estimated = true;
      } else {
        res.no_uncertainty = trueaxis::detail::noise_free_reason("the probes'");
      }
    }
    if (!res.sigma && res.no_uncertainty.empty())
      res.no_uncertainty =
          opt.method == Method::Lsq
              ? "the probes' noise is unknown: no --sigma was given and the layout has no "
                "redundant readings to estimate it from (add a probe or an angle channel, or "
                "give --sigma)"
              : fmt::format(
                    "the probes' noise is unknown: no --sigma was given, and the {} "
                    "method cannot estimate it (give --sigma, or use --method lsq with "
                    "redundant probes)",
                    to_string(opt.method));
    // Standard uncertainties; without a noise level, those for unit noise.
    const double noise_var = res.sigma ? s2 : 1.0;
    if (st.propagation.valid()) {  // the direct solve's, launched with it
      st.propagation.get();
      uw = std::move(st.uw);
      ug = std::move(st.ug);
      ut = std::move(st.ut);
    } else if (opt.method == Method::Lsq)
      lsq_uncertainties(st, raw, res.sigma.has_value(), noise_var, uw, ug, ut);
    else
      recurrence_uncertainties(data, opt.method, raw, res.sigma.has_value(), noise_var, uw, ug, ut);
    if (!res.sigma) {
      // No noise level: state no uncertainty, only how strongly the layout amplifies noise.
      res.noise_gain = std::max(uw.maxCoeff(), ug.maxCoeff());
      uw.resize(0);
      ug.resize(0);
      ut.resize(0);
    }
  }
  if (st.engine && st.dof > 0) res.residual_rms = std::sqrt(st.ssr / static_cast<double>(st.rows));

  if (!unc_possible)
    res.no_uncertainty =
        !opt.compute_uncertainty ? "uncertainties were not asked for"
        : opt.filter_cutoff > 0
            ? "the profiles were filtered (ISO 16610-21), and uncertainties are not carried "
              "through the filter"
            : "the reference of JPH0464003B2 (--reference patent) depends on the readings "
              "themselves; use the least-squares or minimum-zone reference for uncertainties";
  if (opt.filter_cutoff > 0) {
    raw.w = geometry::gaussian_filter(raw.w, h, opt.filter_cutoff);
    raw.g = geometry::gaussian_filter(raw.g, h, opt.filter_cutoff);
    widths = {};  // the filtered profiles' own
  }
  {
    // The two minimum zones are independent: the guide's on another core for long profiles.
    auto guide =
        std::async(policy_for(raw), [&] { return straightness_of(raw.xg, raw.g, widths.g); });
    res.workpiece_straightness = straightness_of(raw.xw, raw.w, widths.w);
    res.guide_straightness = guide.get();
  }
  if (uw.size() && uw.allFinite())
    res.workpiece_straightness.U = trueaxis::detail::peak_to_valley_U(uw.maxCoeff(), uw.size());
  if (ug.size() && ug.allFinite())
    res.guide_straightness.U = trueaxis::detail::peak_to_valley_U(ug.maxCoeff(), ug.size());
  res.workpiece = {std::move(raw.xw), std::move(raw.w), std::move(uw)};
  res.guide = {std::move(raw.xg), std::move(raw.g), std::move(ug)};
  if (raw.theta.size()) res.pitch = Profile{std::move(raw.xt), std::move(raw.theta), std::move(ut)};
  res.offsets = data.offsets;
  res.offsets_assumed = data.offsets_assumed;
  res.readings_span = readings_span;
  res.traverse = data.x[n - 1] - data.x[0];
  return res;
}

Result separate(const ProbeData& data, const Options& opt) {
  return detail::separate(data, opt, detail::LsqSolver::Automatic);
}

std::vector<std::string> Result::warnings() const {
  std::vector<std::string> w;
  const auto check = [&](const char* what, const Straightness& st) {
    if (st.resolved().value_or(true)) return;
    std::string advice = "use more probes, an angle channel (--angle) or a known zero difference";
    if (method != Method::Lsq) advice += ", or --method lsq with redundant probes";
    w.push_back(fmt::format(
        "the {} straightness is not resolved: its expanded uncertainty (95 %) is {} µm, as large "
        "as the {} µm the profile spans, so this probe layout cannot tell it from noise. To "
        "resolve it, {}",
        what, trueaxis::detail::two_digits(*st.U * 1e3),
        trueaxis::detail::two_digits(st.min_zone * 1e3), advice));
  };
  check("workpiece", workpiece_straightness);
  check("guide", guide_straightness);
  if (!no_uncertainty.empty()) {
    std::string s = "no uncertainty is stated: " + no_uncertainty;
    if (noise_gain && std::isfinite(*noise_gain) && *noise_gain > 0) {
      const double st = std::min(workpiece_straightness.ls, guide_straightness.ls);
      s += fmt::format(
          ". This layout multiplies probe noise by up to {} along the profiles, so probe noise "
          "above {} µm (standard deviation) would hide a straightness of {} µm",
          trueaxis::detail::two_digits(*noise_gain),
          trueaxis::detail::two_digits(st / (2 * *noise_gain) * 1e3),
          trueaxis::detail::two_digits(st * 1e3));
    }
    w.push_back(s);
  }
  // Probes over a traverse of millimetres read micrometres; readings that all lie within 50 nm
  // are either a nanometre-flat surface on a nanometre-straight guide, or millimetres written
  // where micrometres were expected (every figure then 1000 times too small).
  constexpr double kUnitCheckSpan = 5e-5, kUnitCheckTraverse = 5;  // mm
  if (readings_span > 0 && readings_span < kUnitCheckSpan && traverse >= kUnitCheckTraverse)
    w.push_back(fmt::format(
        "all probe readings lie within {:.3g} nm over {:.4g} mm of traverse: if they are "
        "millimetres, every figure above is 1000 times too small; name the probe columns with "
        "their unit (a [mm], b [mm], ...)",
        readings_span * 1e6, traverse));
  if (offsets_assumed) {
    std::string list;
    for (double o : offsets) list += fmt::format("{}{:g}", list.empty() ? "" : ", ", o);
    w.push_back(fmt::format(
        "the probe offsets were not stated, so they were taken as {} mm (equal to the stations' "
        "step); if the probes stand otherwise every figure above is wrong: give --offsets, or "
        "name the probe columns with their offsets (a@0, b@10, ...)",
        list));
  }
  return w;
}

std::string Result::summary() const {
  std::string s = fmt::format("method {}, reference {}\n", to_string(method), to_string(reference));
  const auto line = [&](const char* what, const Straightness& st, long n, const char* points) {
    const std::string label = fmt::format("  {} straightness:", what);
    if (st.U && !*st.resolved())
      return fmt::format("{:<26}not resolved (U = {} µm, 95 %), {} {}\n", label,
                         trueaxis::detail::two_digits(*st.U * 1e3), n, points);
    if (st.U)
      return fmt::format("{:<26}{} µm (LS), {} µm (min-zone), U = {} µm (95 %), {} {}\n", label,
                         trueaxis::detail::rounded_to(st.ls * 1e3, *st.U * 1e3),
                         trueaxis::detail::rounded_to(st.min_zone * 1e3, *st.U * 1e3),
                         trueaxis::detail::two_digits(*st.U * 1e3), n, points);
    return fmt::format("{:<26}{:.4g} µm (LS), {:.4g} µm (min-zone), no uncertainty stated, {} {}\n",
                       label, st.ls * 1e3, st.min_zone * 1e3, n, points);
  };
  s += line("workpiece", workpiece_straightness, static_cast<long>(workpiece.x.size()), "points");
  s += line("guide", guide_straightness, static_cast<long>(guide.x.size()), "stations");
  if (pitch && pitch->value.size())
    s += fmt::format("  pitch range:            {:.4g} µrad\n",
                     (pitch->value.maxCoeff() - pitch->value.minCoeff()) * 1e6);
  if (workpiece.uncertainty.size())
    s += fmt::format(
        "  max standard uncertainty: workpiece {} µm, guide {} µm (probe noise sigma {} um{})\n",
        trueaxis::detail::two_digits(workpiece.uncertainty.maxCoeff() * 1e3),
        trueaxis::detail::two_digits(guide.uncertainty.maxCoeff() * 1e3),
        sigma ? trueaxis::detail::two_digits(*sigma * 1e3) : std::string("not known"),
        sigma_estimated
            ? fmt::format(", estimated from the residuals with {} degrees of freedom", dof)
            : "");
  else
    s += fmt::format("  no uncertainty: {}\n", no_uncertainty);
  std::string u;
  for (const auto& m : unobservable) u += (u.empty() ? "" : ", ") + m;
  s += fmt::format("  unobservable: {}\n  gauge: {}\n", u, gauge);
  return s;
}

}  // namespace trueaxis::separation