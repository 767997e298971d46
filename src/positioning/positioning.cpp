#include "trueaxis/positioning/positioning.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "trueaxis/error.hpp"

namespace trueaxis::positioning {
// Magnitudes no real positioning test has (see evaluate()): mm of travel, mm of deviation range.
constexpr double kShortestAxis = 5.0;
constexpr double kSmallestDeviationRange = 5e-5;  // 0.05 µm

namespace {

char sign(Direction d) {
  return d == Direction::Up ? '+' : '-';
}

// max / min over the finite values of f(i); NaN when there are none or when any is NaN and
// `all` is true (a parameter defined over every target is undefined if one target's term is).
template <class F>
double span(std::size_t m, F f) {
  double hi = -INFINITY, lo = INFINITY;
  for (std::size_t i = 0; i < m; ++i) {
    const auto [a, b] = f(i);
    if (std::isnan(a) || std::isnan(b)) return kNaN;
    hi = std::max(hi, a);
    lo = std::min(lo, b);
  }
  return m == 0 ? kNaN : hi - lo;
}

template <class F>
double max_of(std::size_t m, F f) {
  double hi = -INFINITY;
  for (std::size_t i = 0; i < m; ++i) {
    const double v = f(i);
    if (std::isnan(v)) return kNaN;
    hi = std::max(hi, v);
  }
  return m == 0 ? kNaN : hi;
}

// max and min that pass NaN through (std::max and std::min do so for one argument order only).
double hi2(double a, double b) {
  return std::isnan(a) || std::isnan(b) ? kNaN : std::max(a, b);
}
double lo2(double a, double b) {
  return std::isnan(a) || std::isnan(b) ? kNaN : std::min(a, b);
}

// Where a missing reading (cycle c, direction d, at `target`) would have been: the place of the
// reading of that run that follows the gap in the direction of travel, "file:line:col: ", or of
// the run's last reading when the gap is at its end; empty without Options::locate.
std::string gap_at(const std::vector<Reading>& readings, const Options& o, double target, int c,
                   int d) {
  if (!o.locate) return "";
  std::size_t after = readings.size(), last = readings.size();
  for (std::size_t k = 0; k < readings.size(); ++k) {
    const Reading& r = readings[k];
    if (r.cycle != c || (r.direction == Direction::Up ? 0 : 1) != d) continue;
    last = k;
    const bool beyond = d == 0 ? r.target > target : r.target < target;
    const bool closer = after == readings.size() || (d == 0 ? r.target < readings[after].target
                                                            : r.target > readings[after].target);
    if (beyond && closer) after = k;
  }
  if (after < readings.size()) return o.locate(after);
  return last < readings.size() ? o.locate(last) : "";
}

std::string um(double mm) {
  return std::isnan(mm) ? std::string("n/d") : fmt::format("{:.2f}", mm * 1e3);
}

}  // namespace

void Options::validate() const {
  if (!(target_tolerance >= 0) || !std::isfinite(target_tolerance))
    throw Error(
        fmt::format("target tolerance must be finite and >= 0 mm (got {})", target_tolerance));
  if (!std::isfinite(expansion_coefficient) || std::abs(expansion_coefficient) > 1e-3)
    throw Error(fmt::format(
        "expansion coefficient must be finite and at most 1e-3 per kelvin in size (got {}); give "
        "it per kelvin, e.g. 11.5e-6 for steel",
        expansion_coefficient));
  if (!std::isfinite(reference_temperature)) throw Error("reference temperature must be finite");
  if (!std::isnan(datum) && !std::isfinite(datum)) throw Error("datum must be finite");
}

Result evaluate(const std::vector<Reading>& readings, const Options& o) {
  o.validate();
  if (readings.empty()) throw Error("no readings to evaluate");
  const std::size_t nr = readings.size();
  std::size_t with_material = 0;
  for (std::size_t k = 0; k < nr; ++k) {
    const Reading& r = readings[k];
    if (!std::isfinite(r.target) || !std::isfinite(r.deviation))
      throw Error(fmt::format("reading {}: target and deviation must be finite", k + 1));
    if (r.cycle < 1)
      throw Error(fmt::format("reading {}: cycle {} (cycles count from 1)", k + 1, r.cycle));
    if (!std::isnan(r.material_temperature)) {
      if (!std::isfinite(r.material_temperature))
        throw Error(fmt::format("reading {}: material temperature must be finite", k + 1));
      ++with_material;
    }
    if (!std::isnan(r.air_temperature) && !std::isfinite(r.air_temperature))
      throw Error(fmt::format("reading {}: air temperature must be finite", k + 1));
  }
  if (with_material != 0 && with_material != nr)
    throw Error(fmt::format(
        "material temperature is given for {} of {} readings; give it for all of them or none",
        with_material, nr));

  Result res;
  // Targets: cluster the sorted positions.
  std::vector<double> sorted(nr);
  for (std::size_t k = 0; k < nr; ++k) sorted[k] = readings[k].target;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> positions;
  for (double p : sorted)
    if (positions.empty() || p - positions.back() > o.target_tolerance) positions.push_back(p);
  const std::size_t m = positions.size();
  auto target_of = [&](double p) {
    auto it = std::upper_bound(positions.begin(), positions.end(), p + o.target_tolerance);
    return static_cast<std::size_t>(it - positions.begin()) - 1;
  };

  // Temperature correction to the reference temperature.
  res.readings = readings;
  const bool correct = with_material == nr && o.correct_temperature;
  const double datum = std::isnan(o.datum) ? positions.front() : o.datum;
  for (std::size_t k = 0; k < nr; ++k) {
    const Reading& r = readings[k];
    double x = r.deviation;
    if (correct) {
      const double c = o.expansion_coefficient *
                       (r.material_temperature - o.reference_temperature) * (r.target - datum);
      x -= c;
      res.max_correction = std::max(res.max_correction, std::abs(c));
    }
    res.readings[k].deviation = x;
    auto widen = [](double& lo, double& hi, double v) {
      if (std::isnan(v)) return;
      lo = std::isnan(lo) ? v : std::min(lo, v);
      hi = std::isnan(hi) ? v : std::max(hi, v);
    };
    widen(res.material_min, res.material_max, r.material_temperature);
    widen(res.air_min, res.air_max, r.air_temperature);
  }
  if (correct) {
    res.temperature_corrected = true;
    res.expansion_coefficient = o.expansion_coefficient;
    res.datum = datum;
    res.reference_temperature = o.reference_temperature;
  }

  // Group: [target][direction] -> readings; duplicates refused.
  std::map<std::tuple<std::size_t, int, int>, std::size_t> seen;
  std::vector<std::array<std::vector<double>, 2>> x(m);
  std::set<int> cycles_dir[2];
  for (std::size_t k = 0; k < nr; ++k) {
    const Reading& r = readings[k];
    const std::size_t i = target_of(r.target);
    const int d = r.direction == Direction::Up ? 0 : 1;
    const auto [it, fresh] = seen.emplace(std::make_tuple(i, r.cycle, d), k);
    if (!fresh) {
      if (!o.locate)
        throw Error(fmt::format("readings {} and {} are both cycle {}, '{}' at target {} mm",
                                it->second + 1, k + 1, r.cycle, sign(r.direction), positions[i]));
      const std::string first = o.locate(it->second);  // "file:line:col: "
      throw Error(fmt::format("{}cycle {} '{}' at target {:g} mm again (first at {})", o.locate(k),
                              r.cycle, sign(r.direction), positions[i],
                              first.substr(0, first.size() - 2)));
    }
    x[i][static_cast<std::size_t>(d)].push_back(res.readings[k].deviation);
    cycles_dir[d].insert(r.cycle);
  }
  std::set<int> all_cycles = cycles_dir[0];
  all_cycles.insert(cycles_dir[1].begin(), cycles_dir[1].end());
  res.cycles = static_cast<int>(all_cycles.size());
  res.has_up = !cycles_dir[0].empty();
  res.has_down = !cycles_dir[1].empty();

  // Completeness: every target in every cycle of each direction present.
  std::size_t incomplete = 0;
  for (int d = 0; d < 2; ++d) {
    if (cycles_dir[d].empty()) continue;
    for (std::size_t i = 0; i < m; ++i) {
      const std::size_t have = x[i][static_cast<std::size_t>(d)].size();
      if (have == cycles_dir[d].size()) continue;
      if (!o.allow_incomplete) {
        for (int c : cycles_dir[d])
          if (!seen.count(std::make_tuple(i, c, d)))
            throw Error(fmt::format(
                "{}no '{}' reading at target {:g} mm in cycle {} (every target needs one reading "
                "per cycle and direction; allow incomplete cycles to evaluate each target with "
                "the readings it has)",
                gap_at(readings, o, positions[i], c, d), d == 0 ? '+' : '-', positions[i], c));
      }
      ++incomplete;
    }
  }
  if (incomplete > 0)
    res.warnings.push_back(fmt::format(
        "incomplete cycles: {} target/direction pairs have fewer readings than cycles; each is "
        "evaluated with the readings it has",
        incomplete));

  // Per target.
  std::size_t single = 0;
  res.targets.resize(m);
  for (std::size_t i = 0; i < m; ++i) {
    Target& t = res.targets[i];
    t.position = positions[i];
    double mean[2] = {kNaN, kNaN}, s[2] = {kNaN, kNaN};
    int count[2] = {0, 0};
    for (std::size_t d = 0; d < 2; ++d) {
      const auto& v = x[i][d];
      count[d] = static_cast<int>(v.size());
      if (v.empty()) continue;
      double sum = 0;
      for (double e : v) sum += e;
      mean[d] = sum / static_cast<double>(v.size());
      if (v.size() >= 2) {
        double ss = 0;
        for (double e : v) ss += (e - mean[d]) * (e - mean[d]);
        s[d] = std::sqrt(ss / static_cast<double>(v.size() - 1));
      } else if ((d == 0 && res.has_up) || (d == 1 && res.has_down)) {
        ++single;
      }
    }
    t.n_up = count[0];
    t.n_down = count[1];
    t.mean_up = mean[0];
    t.mean_down = mean[1];
    t.s_up = s[0];
    t.s_down = s[1];
    t.R_up = 4 * s[0];
    t.R_down = 4 * s[1];
    t.mean = (mean[0] + mean[1]) / 2;
    t.B = mean[0] - mean[1];
    t.R = hi2(2 * s[0] + 2 * s[1] + std::abs(t.B), hi2(t.R_up, t.R_down));
    t.U = std::abs(t.B);
    t.Ps = 6 * (s[0] + s[1]) / 2;
  }
  if (single > 0)
    res.warnings.push_back(fmt::format(
        "{} target/direction pairs have a single reading: their spread, repeatability and "
        "accuracy are not defined",
        single));

  // Axis parameters.
  const auto& T = res.targets;
  IsoParameters& p = res.iso;
  p.E_up = span(m, [&](std::size_t i) { return std::pair{T[i].mean_up, T[i].mean_up}; });
  p.E_down = span(m, [&](std::size_t i) { return std::pair{T[i].mean_down, T[i].mean_down}; });
  p.E = span(m, [&](std::size_t i) {
    return std::pair{hi2(T[i].mean_up, T[i].mean_down), lo2(T[i].mean_up, T[i].mean_down)};
  });
  p.M = span(m, [&](std::size_t i) { return std::pair{T[i].mean, T[i].mean}; });
  p.R_up = max_of(m, [&](std::size_t i) { return T[i].R_up; });
  p.R_down = max_of(m, [&](std::size_t i) { return T[i].R_down; });
  p.R = max_of(m, [&](std::size_t i) { return T[i].R; });
  p.B = max_of(m, [&](std::size_t i) { return std::abs(T[i].B); });
  if (!std::isnan(p.B)) {
    double sum = 0;
    for (const auto& t : T) sum += t.B;
    p.B_mean = sum / static_cast<double>(m);
  }
  p.A_up = span(m, [&](std::size_t i) {
    return std::pair{T[i].mean_up + 2 * T[i].s_up, T[i].mean_up - 2 * T[i].s_up};
  });
  p.A_down = span(m, [&](std::size_t i) {
    return std::pair{T[i].mean_down + 2 * T[i].s_down, T[i].mean_down - 2 * T[i].s_down};
  });
  p.A = span(m, [&](std::size_t i) {
    return std::pair{hi2(T[i].mean_up + 2 * T[i].s_up, T[i].mean_down + 2 * T[i].s_down),
                     lo2(T[i].mean_up - 2 * T[i].s_up, T[i].mean_down - 2 * T[i].s_down)};
  });

  VdiParameters& v = res.vdi;
  v.Pa = p.M;
  v.U = p.B;
  v.Ps = max_of(m, [&](std::size_t i) { return T[i].Ps; });
  v.P = span(m, [&](std::size_t i) {
    const double h = (T[i].U + T[i].Ps) / 2;
    return std::pair{T[i].mean + h, T[i].mean - h};
  });
  if (!std::isnan(v.U)) {
    double su = 0;
    for (const auto& t : T) su += t.U;
    v.U_mean = su / static_cast<double>(m);
  }
  if (!std::isnan(v.Ps)) {
    double sp = 0;
    for (const auto& t : T) sp += t.Ps;
    v.Ps_mean = sp / static_cast<double>(m);
  }

  // Departures from the test conditions of ISO 230-2:2014 (clause 4).
  if (!res.has_up || !res.has_down)
    res.warnings.push_back(fmt::format(
        "only '{}' approaches: the reversal value and every bidirectional parameter are not "
        "defined",
        res.has_up ? '+' : '-'));
  if (res.cycles < 5)
    res.warnings.push_back(fmt::format(
        "{} cycle{}: ISO 230-2 asks for 5 runs in each direction; spreads from fewer are coarse "
        "estimates",
        res.cycles, res.cycles == 1 ? "" : "s"));
  const double travel = positions.back() - positions.front();
  const double needed = std::max(5.0, std::ceil(5.0 * travel / 1000.0));
  if (static_cast<double>(m) < needed)
    res.warnings.push_back(fmt::format(
        "{} targets over {:g} mm: ISO 230-2 asks for at least five per metre and five in all ({:g} "
        "here)",
        m, travel, needed));
  if (res.temperature_corrected && res.material_max - res.material_min > 1.0)
    res.warnings.push_back(fmt::format(
        "the material temperature changed by {:.2f} K during the test: the correction to {:g} C "
        "assumes the whole axis follows its sensor",
        res.material_max - res.material_min, o.reference_temperature));

  // A unit mix-up passes every check above and every tolerance: look at the magnitudes. A
  // machine axis is tested over more than 5 mm, and its deviations vary by more than the
  // resolution of any laser interferometer (about 1 nm) along it.
  if (m >= 2 && travel < kShortestAxis)
    res.implausible = fmt::format(
        "the targets span only {:.3g} mm: no machine axis is tested over less than {:g} mm. Are "
        "they in metres? Name the column 'target [m]' (or write millimetres)",
        travel, kShortestAxis);
  double lo = INFINITY, hi = -INFINITY;
  for (const Reading& r : res.readings) {
    lo = std::min(lo, r.deviation);
    hi = std::max(hi, r.deviation);
  }
  if (res.implausible.empty() && m >= 2 && hi - lo < kSmallestDeviationRange)
    res.implausible = fmt::format(
        "the deviations vary by only {:.2g} µm along {:g} mm of axis, below the resolution of "
        "any laser interferometer: they look like millimetres in a micrometre column. Name the "
        "column 'deviation [mm]' (or write micrometres)",
        (hi - lo) * 1e3, travel);
  if (!res.implausible.empty()) res.warnings.insert(res.warnings.begin(), res.implausible);
  return res;
}

const std::vector<std::string>& parameter_names() {
  static const std::vector<std::string> names{"A", "A_up", "A_down", "E",      "E_up", "E_down",
                                              "M", "R",    "R_up",   "R_down", "B",    "B_mean",
                                              "P", "Pa",   "Ps",     "U"};
  return names;
}

double parameter(const Result& r, const std::string& name) {
  const IsoParameters& p = r.iso;
  const VdiParameters& v = r.vdi;
  const std::pair<const char*, double> all[] = {
      {"A", p.A},       {"A_up", p.A_up},     {"A_down", p.A_down}, {"E", p.E},
      {"E_up", p.E_up}, {"E_down", p.E_down}, {"M", p.M},           {"R", p.R},
      {"R_up", p.R_up}, {"R_down", p.R_down}, {"B", p.B},           {"B_mean", p.B_mean},
      {"P", v.P},       {"Pa", v.Pa},         {"Ps", v.Ps},         {"U", v.U}};
  for (const auto& [n, value] : all)
    if (name == n) return value;
  std::string known;
  for (const auto& n : parameter_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error(fmt::format("unknown parameter '{}' (known: {})", name, known));
}

std::vector<Verdict> check(const Result& r,
                           const std::vector<std::pair<std::string, double>>& tolerances) {
  std::vector<Verdict> out;
  for (const auto& [name, limit] : tolerances) {
    if (!std::isfinite(limit) || limit <= 0)
      throw Error(
          fmt::format("tolerance of {} must be finite and positive (got {:g})", name, limit));
    Verdict v;
    v.name = name;
    v.value = parameter(r, name);
    v.limit = limit;
    v.pass = !std::isnan(v.value) && std::abs(v.value) <= limit && r.implausible.empty();
    if (!r.implausible.empty()) v.not_judged = r.implausible;
    out.push_back(v);
  }
  return out;
}

std::string Result::summary(bool vdi) const {
  std::string s;
  const double lo = targets.front().position, hi = targets.back().position;
  const char* dirs = has_up && has_down ? "both directions" : has_up ? "'+' only" : "'-' only";
  s += fmt::format("{} positioning: {} targets {:g} .. {:g} mm, {} cycle{}, {}\n",
                   vdi ? "VDI/DGQ 3441" : "ISO 230-2:2014", targets.size(), lo, hi, cycles,
                   cycles == 1 ? "" : "s", dirs);
  if (vdi) {
    s += fmt::format("  positional uncertainty P  {} µm\n", um(this->vdi.P));
    s += fmt::format("  positional deviation Pa   {} µm\n", um(this->vdi.Pa));
    s += fmt::format("  positional scatter Ps     {} µm (mean {})\n", um(this->vdi.Ps),
                     um(this->vdi.Ps_mean));
    s += fmt::format("  reversal span U           {} µm (mean {})\n", um(this->vdi.U),
                     um(this->vdi.U_mean));
  } else {
    s += fmt::format("  accuracy A                {} µm (A+ {}, A- {})\n", um(iso.A), um(iso.A_up),
                     um(iso.A_down));
    s += fmt::format("  systematic deviation E    {} µm (E+ {}, E- {})\n", um(iso.E), um(iso.E_up),
                     um(iso.E_down));
    s += fmt::format("  mean bidirectional M      {} µm\n", um(iso.M));
    s += fmt::format("  repeatability R           {} µm (R+ {}, R- {})\n", um(iso.R), um(iso.R_up),
                     um(iso.R_down));
    s += fmt::format("  reversal B                {} µm (mean {})\n", um(iso.B), um(iso.B_mean));
  }
  if (temperature_corrected)
    s += fmt::format(
        "  corrected to {:g} C for a material temperature of {:.2f} .. {:.2f} C, expansion "
        "coefficient {:g}/K, datum {:g} mm (at most {:.2f} µm)\n",
        reference_temperature, material_min, material_max, expansion_coefficient, datum,
        max_correction * 1e3);
  for (const auto& w : warnings) s += "  warning: " + w + "\n";
  return s;
}

}  // namespace trueaxis::positioning

namespace trueaxis::positioning {

void LogOptions::validate() const {
  if (!(dwell_time > 0) || !std::isfinite(dwell_time))
    throw Error(fmt::format("the dwell time must be positive (got {:g} s)", dwell_time));
  if (!(dwell_tolerance > 0) || !std::isfinite(dwell_tolerance))
    throw Error(fmt::format("the dwell tolerance must be positive (got {:g} mm)", dwell_tolerance));
  if (!std::isnan(capture) && (!(capture > 0) || !std::isfinite(capture)))
    throw Error(fmt::format("the capture distance must be positive (got {:g} mm)", capture));
}

LogReadings readings_from_log(const Log& log, const std::vector<double>& targets,
                              const LogOptions& o) {
  o.validate();
  const std::size_t n = log.time.size();
  if (log.reading.size() != n) throw Error("the log needs one reading per time");
  if (targets.empty()) throw Error("no targets to find in the log");
  double spacing = INFINITY;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    if (!std::isfinite(targets[i])) throw Error("targets must be finite");
    if (i > 0) {
      if (!(targets[i] > targets[i - 1])) throw Error("targets must be strictly increasing");
      spacing = std::min(spacing, targets[i] - targets[i - 1]);
    }
  }
  const double capture =
      std::isnan(o.capture) ? std::min(std::isfinite(spacing) ? spacing / 4 : 0.5, 0.5) : o.capture;
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(log.time[k]) || !std::isfinite(log.reading[k]))
      throw Error(fmt::format("log sample {}: time and reading must be finite", k + 1));
    if (k > 0 && !(log.time[k] > log.time[k - 1]))
      throw Error(fmt::format("log sample {}: time {:g} s does not increase", k + 1, log.time[k]));
  }
  LogReadings out;
  std::map<std::pair<std::size_t, int>, int> visits;
  std::size_t k = 0;
  while (k < n) {
    // The longest run from k whose range stays within the tolerance.
    double lo = log.reading[k], hi = lo;
    std::size_t e = k + 1;
    while (e < n) {
      const double v = log.reading[e];
      if (std::max(hi, v) - std::min(lo, v) > o.dwell_tolerance) break;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
      ++e;
    }
    if (log.time[e - 1] - log.time[k] < o.dwell_time) {
      ++k;
      continue;
    }
    ++out.stops;
    // The settled second half of the stop.
    double sum = 0;
    const std::size_t half = k + (e - k) / 2;
    for (std::size_t q = half; q < e; ++q) sum += log.reading[q];
    const double value = sum / static_cast<double>(e - half);
    const double t0 = log.time[k];
    // The motion into the stop.
    std::size_t q = k;
    while (q > 0 && std::abs(log.reading[q - 1] - value) <= 10 * o.dwell_tolerance) --q;
    const auto near = std::lower_bound(targets.begin(), targets.end(), value);
    std::size_t ti = static_cast<std::size_t>(near - targets.begin());
    if (ti == targets.size() || (ti > 0 && value - targets[ti - 1] < targets[ti] - value)) --ti;
    if (std::abs(value - targets[ti]) > capture) {
      out.ignored.push_back(fmt::format("stop at {:.4f} mm from {:.1f} s: no target within {:g} mm",
                                        value, t0, capture));
    } else if (q == 0) {
      out.ignored.push_back(fmt::format(
          "stop at {:.4f} mm from {:.1f} s: the log starts there (no approach to tell the "
          "direction)",
          value, t0));
    } else {
      Reading r;
      r.target = targets[ti];
      r.direction = log.reading[q - 1] < value ? Direction::Up : Direction::Down;
      r.cycle = ++visits[{ti, r.direction == Direction::Up ? 0 : 1}];
      r.deviation = value - targets[ti];
      out.readings.push_back(r);
    }
    k = e;
  }
  return out;
}

}  // namespace trueaxis::positioning
