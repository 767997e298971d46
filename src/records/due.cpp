// When each machine is next due (records.hpp): the last visit plus the longest interval, brought
// forward by any figure whose trend reaches its limit sooner.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <tuple>

#include "trueaxis/error.hpp"
#include "trueaxis/records/records.hpp"

namespace trueaxis::records {

Limit Limit::parse(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw Error(fmt::format("limit '{}': write FIGURE=VALUE or FIGURE@AXIS=VALUE (A@X=25)", text));
  Limit l;
  const std::string key = text.substr(0, eq), value = text.substr(eq + 1);
  const auto at = key.find('@');
  l.figure = key.substr(0, at);
  if (at != std::string::npos) {
    l.axis = key.substr(at + 1);
    for (char& c : l.axis) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  std::size_t used = 0;
  try {
    l.value = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (l.figure.empty() || used == 0 || used != value.size() || !std::isfinite(l.value))
    throw Error(fmt::format("limit '{}': the value after '=' must be a number", text));
  return l;
}

void DueOptions::validate() const {
  if (interval_months < 1 || interval_months > 120)
    throw Error("due: the interval must be 1 … 120 months");
  if (!today.empty()) (void)day_number(today);
}

std::string add_months(const std::string& date, int months) {
  (void)day_number(date);  // refuses what is not a date
  int y = std::stoi(date.substr(0, 4)), m = std::stoi(date.substr(5, 2));
  const int d = std::stoi(date.substr(8, 2));
  const int index = y * 12 + (m - 1) + months;
  y = index / 12;
  m = index % 12 + 1;
  static constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  const int last = kDays[m - 1] + (m == 2 && leap);
  return fmt::format("{:04d}-{:02d}-{:02d}", y, m, std::min(d, last));
}

namespace {

// The history's latest point, fitted or not: on one day the as-left value, which an adjustment
// left after the as-found one.
const TrendPoint* latest(const Trend& t) {
  const TrendPoint* best = nullptr;
  const auto order = [](const TrendPoint& p) {
    return std::tuple(day_number(p.date),
                      p.state == State::AsFound ? 0
                      : p.state == State::None  ? 1
                                                : 2,
                      p.record);
  };
  for (const auto* list : {&t.points, &t.not_fitted})
    for (const auto& p : *list)
      if (best == nullptr || order(*best) < order(p)) best = &p;
  return best;
}

}  // namespace

std::vector<Due> due_dates(const Database& db, const DueOptions& options) {
  options.validate();
  const std::string today = options.today.empty() ? today_utc() : options.today;
  std::vector<Due> out;
  for (const auto& m : db.machines()) {
    if (!options.machine.empty() && m.id != options.machine) continue;
    if (m.records == 0) continue;
    Due d;
    d.machine = m.id;
    d.last_visit = m.last.substr(0, 10);
    d.due = add_months(d.last_visit, options.interval_months);
    d.because = fmt::format("{} months after the last visit", options.interval_months);
    const auto figures = db.figures(m.id);
    for (const auto& limit : options.limits) {
      for (const auto& [name, axis] : figures) {
        if (!limit.applies_to(name, axis)) continue;
        TrendOptions to;
        to.tolerance = limit.value;
        const Trend t = db.trend(m.id, name, axis, to);
        const std::string label = axis.empty() ? name : name + "@" + axis;
        if (!t.due) {
          // The machine as it was last left already past the limit is due now, trend or not.
          if (const TrendPoint* last = latest(t); last != nullptr && last->value > limit.value) {
            if (day_number(d.last_visit) <= day_number(d.due)) {
              d.due = d.last_visit;
              d.u_days.reset();
              d.because = fmt::format(
                  "{} was {:.3g} {} {}, over its limit {:g}", label, last->value, t.unit,
                  last->state == State::AsLeft ? "as left at the last visit" : "at the last visit",
                  limit.value);
            }
          } else {
            d.notes.push_back(fmt::format("{}: {}", label, t.not_resolved));
          }
          continue;
        }
        if (day_number(*t.due) < day_number(d.due)) {
          d.due = *t.due;
          d.u_days = t.u_due_days;
          d.because = fmt::format("{} reaches {:g} {} (drift {:.3g} ± {:.2g} {}/year)", label,
                                  limit.value, t.unit, *t.drift_per_year, *t.u_drift, t.unit);
        }
      }
    }
    d.overdue = day_number(d.due) < day_number(today);
    out.push_back(std::move(d));
  }
  std::stable_sort(out.begin(), out.end(), [](const Due& a, const Due& b) {
    return day_number(a.due) < day_number(b.due);
  });
  return out;
}

std::string to_json(const std::vector<Due>& due) {
  using ojson = nlohmann::ordered_json;
  ojson j;
  j["kind"] = "due";
  j["machines"] = ojson::array();
  for (const auto& d : due)
    j["machines"].push_back({{"machine", d.machine},
                             {"last_visit", d.last_visit},
                             {"due", d.due},
                             {"u_days", d.u_days ? ojson(*d.u_days) : ojson(nullptr)},
                             {"because", d.because},
                             {"overdue", d.overdue},
                             {"notes", d.notes}});
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace trueaxis::records
