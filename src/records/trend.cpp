// A figure's drift over a machine's history and the date it reaches its tolerance
// (records.hpp): a straight line by weighted least squares, its uncertainty by the GUM's law of
// propagation (JCGM 100:2008, 5.1.2), the points' scatter taken in through the Birge ratio.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "trueaxis/error.hpp"
#include "trueaxis/records/records.hpp"

namespace trueaxis::records {
namespace {

constexpr double kDaysPerYear = 365.2425;  // the Gregorian calendar's mean year

}  // namespace

// H. Hinnant's days_from_civil (public domain algorithm, "chrono-Compatible Low-Level Date
// Algorithms"): exact for every proleptic Gregorian date.
long long day_number(const std::string& date) {
  int y = 0, m = 0, d = 0;
  if (date.size() < 10 || std::sscanf(date.c_str(), "%4d-%2d-%2d", &y, &m, &d) != 3 || m < 1 ||
      m > 12 || d < 1 || d > 31)
    throw Error(fmt::format("'{}' is not an ISO 8601 date (YYYY-MM-DD)", date));
  y -= m <= 2;
  const long long era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = static_cast<unsigned>((153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1);
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<long long>(doe) - 719468;
}

std::string date_of_day(long long z) {
  z += 719468;
  const long long era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const long long y = static_cast<long long>(yoe) + era * 400;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  const unsigned d = doy - (153 * mp + 2) / 5 + 1;
  const unsigned m = mp < 10 ? mp + 3 : mp - 9;
  return fmt::format("{:04d}-{:02d}-{:02d}", y + (m <= 2), m, d);
}

TrendOptions::Use TrendOptions::use_of(const std::string& name) {
  if (name == "auto") return Use::Auto;
  if (name == "as-found") return Use::AsFound;
  if (name == "as-left") return Use::AsLeft;
  if (name == "all") return Use::All;
  throw Error(fmt::format(
      "points '{}': the points fitted are 'auto', 'as-found', 'as-left' or 'all'", name));
}

void TrendOptions::validate() const {
  if (tolerance && !std::isfinite(*tolerance)) throw Error("trend: the tolerance must be a number");
}

Trend fit_trend(std::vector<TrendPoint> points, const TrendOptions& options) {
  options.validate();
  Trend t;
  std::stable_sort(points.begin(), points.end(), [](const TrendPoint& a, const TrendPoint& b) {
    return day_number(a.date) < day_number(b.date);
  });
  t.points = points;
  const auto n = points.size();
  if (n < 2) {
    t.not_resolved =
        fmt::format("{} point{}: a drift needs at least two dates", n, n == 1 ? "" : "s");
    return t;
  }
  const long long d0 = day_number(points.front().date), d1 = day_number(points.back().date);
  if (d1 == d0) {
    t.not_resolved = "every point has the same date: no drift can be seen";
    return t;
  }
  const bool weighted =
      std::all_of(points.begin(), points.end(), [](const auto& p) { return p.u && *p.u > 0; });
  // value = a + b·(t − t_last), t in years: the intercept is the value at the last date. Two
  // parameters: the normal equations N·(a, b) = r solved in closed form.
  double S = 0, Sx = 0, Sxx = 0, Sy = 0, Sxy = 0;
  std::vector<double> tx(points.size()), w(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    tx[i] = static_cast<double>(day_number(p.date) - d1) / kDaysPerYear;
    w[i] = weighted ? 1 / (*p.u * *p.u) : 1.0;
    S += w[i];
    Sx += w[i] * tx[i];
    Sxx += w[i] * tx[i] * tx[i];
    Sy += w[i] * p.value;
    Sxy += w[i] * tx[i] * p.value;
  }
  const double det = S * Sxx - Sx * Sx;  // > 0: two dates at least
  const double x[2] = {(Sxx * Sy - Sx * Sxy) / det, (S * Sxy - Sx * Sy) / det};
  // cov = N⁻¹ = [Sxx, −Sx; −Sx, S] / det.
  double cov[2][2] = {{Sxx / det, -Sx / det}, {-Sx / det, S / det}};
  const auto dof = static_cast<long long>(points.size()) - 2;
  double chi2 = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double r = points[i].value - x[0] - x[1] * tx[i];
    chi2 += w[i] * r * r;
  }
  auto scale = [&](double f) {
    for (auto& row : cov)
      for (double& c : row) c *= f;
  };
  if (weighted) {
    // The points' own u, or their scatter when it is the larger (Birge ratio χ²/dof > 1).
    if (dof > 0 && chi2 / static_cast<double>(dof) > 1) scale(chi2 / static_cast<double>(dof));
  } else {
    if (dof < 1) {
      t.drift_per_year = x[1];
      t.value_now = x[0];
      t.not_resolved =
          "two points without stated uncertainties: the drift's uncertainty cannot be estimated "
          "(a third date, or the figures' u, is needed)";
      return t;
    }
    scale(chi2 / static_cast<double>(dof));
  }
  t.drift_per_year = x[1];
  t.u_drift = std::sqrt(cov[1][1]);
  t.value_now = x[0];
  t.u_value_now = std::sqrt(cov[0][0]);
  t.cov_now_drift = cov[0][1];
  if (!options.tolerance) return t;
  const double T = *options.tolerance, b = x[1];
  if (!(std::abs(b) >= 2 * *t.u_drift) || b == 0) {
    t.not_resolved = fmt::format(
        "the drift, {:.3g} ± {:.2g} {}per year, does not stand out of its uncertainty: no due date "
        "can be given from the trend",
        b, *t.u_drift, options.unit.empty() ? "" : options.unit + " ");
    return t;
  }
  if (b < 0) {
    t.not_resolved = "the figure is falling: the trend does not reach its upper limit";
    return t;
  }
  // From the last date; negative when the line crossed the limit before it.
  const double years = (T - x[0]) / b;
  // t* = (T − a)/b: ∂t*/∂a = −1/b, ∂t*/∂b = −(T − a)/b².
  const double J[2] = {-1 / b, -(T - x[0]) / (b * b)};
  const double u_years =
      std::sqrt(J[0] * J[0] * cov[0][0] + 2 * J[0] * J[1] * cov[0][1] + J[1] * J[1] * cov[1][1]);
  t.due = date_of_day(d1 + std::llround(years * kDaysPerYear));
  t.u_due_days = u_years * kDaysPerYear;
  return t;
}

std::pair<double, std::optional<double>> Trend::line_at(long long day) const {
  if (!drift_per_year || !value_now || points.empty())
    throw Error("trend: the line is not resolved");
  const double years = static_cast<double>(day - day_number(points.back().date)) / kDaysPerYear;
  const double value = *value_now + *drift_per_year * years;
  if (!u_drift || !u_value_now || !cov_now_drift) return {value, std::nullopt};
  const double var = *u_value_now * *u_value_now + years * years * *u_drift * *u_drift +
                     2 * years * *cov_now_drift;
  return {value, std::sqrt(std::max(var, 0.0))};
}

std::string Trend::summary() const {
  std::string s = fmt::format("{}{}: {} points{}", figure, axis.empty() ? "" : " " + axis,
                              points.size(), fitted_on == "all" ? "" : " " + fitted_on);
  if (drift_per_year)
    s += fmt::format(", drift {:.3g}{} {}/year", *drift_per_year,
                     u_drift ? fmt::format(" ± {:.2g}", *u_drift) : std::string(), unit);
  if (due)
    s += fmt::format(
        ", {} the tolerance on {} (u {:.0f} days)",
        value_now && *value_now > 0 && day_number(*due) <= day_number(points.back().date)
            ? "reached"
            : "reaches",
        *due, *u_due_days);
  if (!not_resolved.empty()) s += "; " + not_resolved;
  return s;
}

std::string to_json(const Trend& t, const std::string& machine) {
  using ojson = nlohmann::ordered_json;
  auto opt = [](const std::optional<double>& v) { return v ? ojson(*v) : ojson(nullptr); };
  ojson j;
  j["kind"] = "trend";
  j["machine"] = machine;
  j["figure"] = t.figure;
  j["axis"] = t.axis.empty() ? ojson(nullptr) : ojson(t.axis);
  j["unit"] = t.unit;
  auto point = [&](const TrendPoint& p) {
    return ojson{{"date", p.date},
                 {"value", p.value},
                 {"u", opt(p.u)},
                 {"state", p.state == State::None ? ojson(nullptr) : ojson(to_string(p.state))},
                 {"record", p.record}};
  };
  j["fitted_on"] = t.fitted_on;
  j["points"] = ojson::array();
  for (const auto& p : t.points) j["points"].push_back(point(p));
  j["not_fitted"] = ojson::array();
  for (const auto& p : t.not_fitted) j["not_fitted"].push_back(point(p));
  j["drift_per_year"] = {{"value", opt(t.drift_per_year)}, {"u", opt(t.u_drift)}};
  j["due"] = {{"date", t.due ? ojson(*t.due) : ojson(nullptr)}, {"u_days", opt(t.u_due_days)}};
  if (!t.not_resolved.empty()) j["not_resolved"] = t.not_resolved;
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace trueaxis::records
