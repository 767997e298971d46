// A figure's history and drift as a report section (report/records.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "trueaxis/report/records.hpp"

namespace trueaxis::report {
namespace {

std::string with_u(double v, const std::optional<double>& u, const std::string& unit) {
  return u ? fmt::format("{:.3g} ± {:.2g} {} (k = 2)", v, 2 * *u, unit)
           : fmt::format("{:.3g} {} (no uncertainty)", v, unit);
}

}  // namespace

Section trend_section(const records::Trend& t, const std::string& machine,
                      std::optional<double> tolerance) {
  Section s;
  const std::string what = t.figure + (t.axis.empty() ? "" : " on " + t.axis);
  s.title = fmt::format("{}: history and drift", what);
  s.source = "machine " + machine;
  s.references = {refs::kGum};
  s.summary = t.summary();
  if (!t.not_resolved.empty()) s.warnings.push_back(t.not_resolved);
  s.intro_html = fmt::format(
      "<p>Each point is one calibration of machine {} on its date: as found (before any "
      "adjustment) and as left (after it) are marked apart. The line is the drift fitted by "
      "weighted least squares (weights 1/u² when every point states its u) to {}, its band ±2 "
      "standard uncertainties of the line (the points' u or, when larger, their scatter about "
      "the line){}.</p>",
      escape(machine),
      t.fitted_on == "all" ? std::string("every point")
                           : "the " + t.fitted_on +
                                 " points (the machine drifts between adjustments; the other "
                                 "points are where an adjustment put it)",
      tolerance ? "; the dashed line is the limit" : "");
  const std::string unit = t.unit.empty() ? "" : t.unit;
  s.table.push_back({"", "value"});
  if (t.drift_per_year)
    s.table.push_back({"drift per year", with_u(*t.drift_per_year, t.u_drift, unit + "/year")});
  else
    s.table.push_back({"drift per year", "not resolved"});
  if (t.value_now)
    s.table.push_back({"the line at the last date (" + t.points.back().date + ")",
                       with_u(*t.value_now, t.u_value_now, unit)});
  if (tolerance) s.table.push_back({"limit", fmt::format("{:g} {}", *tolerance, unit)});
  if (t.due)
    s.table.push_back(
        {"the trend reaches the limit",
         fmt::format("{} (± {:.0f} days, k = 2)", *t.due, 2 * t.u_due_days.value_or(0))});
  else if (tolerance)
    s.table.push_back({"the trend reaches the limit", "not resolved"});
  // Every point of the history, fitted or not, by date.
  std::vector<std::pair<records::TrendPoint, bool>> all;
  for (const auto& p : t.points) all.push_back({p, true});
  for (const auto& p : t.not_fitted) all.push_back({p, false});
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
    return records::day_number(a.first.date) < records::day_number(b.first.date);
  });
  std::vector<std::vector<std::string>> history{
      {"date", "state", fmt::format("{} ({})", t.figure, unit), "u", "fitted", "record"}};
  for (const auto& [p, fitted] : all)
    history.push_back({p.date, p.state == records::State::None ? "not stated" : to_string(p.state),
                       fmt::format("{:.4g}", p.value),
                       p.u ? fmt::format("{:.2g}", *p.u) : "not stated", fitted ? "yes" : "no",
                       fmt::format("{}", p.record)});
  s.tables_after.push_back({"The history", std::move(history)});
  if (all.empty()) return s;

  // x: the points' days, then the line's samples out to the due date (or a year on).
  std::set<long long> days;
  for (const auto& [p, fitted] : all) days.insert(records::day_number(p.date));
  const long long first = *days.begin(), last = *days.rbegin();
  long long end = last + 365;
  if (t.due) end = std::max(end, records::day_number(*t.due) + 60);
  end = std::min(end, last + 20 * 365);  // a far-off date would squash the history
  const bool line = t.drift_per_year.has_value();
  if (line)
    for (int k = 0; k <= 40; ++k) days.insert(first + (end - first) * k / 40);
  std::vector<long long> x(days.begin(), days.end());
  const auto n = static_cast<Eigen::Index>(x.size());
  Plot p;
  p.title = fmt::format("{} of machine {}", what, machine);
  p.x_label = "date";
  p.y_label = fmt::format("{} ({})", t.figure, unit);
  p.x_dates = true;
  p.span_gaps = true;
  p.x.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) p.x[i] = static_cast<double>(x[static_cast<std::size_t>(i)]);
  struct Kind {
    records::State state;
    const char* label;
    const char* color;
  };
  for (const Kind k : {Kind{records::State::AsFound, "as found", "#d62728"},
                       Kind{records::State::AsLeft, "as left", "#2ca02c"},
                       Kind{records::State::None, "state not stated", "#555555"}}) {
    Series m;
    m.label = k.label;
    m.color = k.color;
    m.points = true;
    m.y = Eigen::VectorXd::Constant(n, NAN);
    bool any = false;
    for (const auto& [pt, fitted] : all) {
      if (pt.state != k.state) continue;
      const auto i = std::lower_bound(x.begin(), x.end(), records::day_number(pt.date)) - x.begin();
      // Two records of one day and state: the later one is drawn (both are in the table).
      m.y[i] = pt.value;
      any = true;
    }
    if (any) p.series.push_back(std::move(m));
  }
  if (line) {
    Series l;
    l.label = "fitted drift";
    l.color = "#1f77b4";
    l.y.resize(n);
    l.band.resize(n);
    bool banded = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto [v, u] = t.line_at(x[static_cast<std::size_t>(i)]);
      l.y[i] = v;
      l.band[i] = u ? *u : NAN;
      banded = banded && u.has_value();
    }
    if (!banded) l.band.resize(0);
    l.band_meaning = "±2 standard uncertainties of the fitted line (about 95 %)";
    p.series.push_back(std::move(l));
  }
  if (tolerance) {
    Series lim;
    lim.label = fmt::format("limit {:g} {}", *tolerance, unit);
    lim.color = "#000000";
    lim.dashed = true;
    lim.y = Eigen::VectorXd::Constant(n, *tolerance);
    p.series.push_back(std::move(lim));
  }
  s.plots.push_back(std::move(p));
  return s;
}

}  // namespace trueaxis::report
