#include "trueaxis/io/circular/circular.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>

#include "../fast_text.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/units.hpp"

namespace trueaxis::io {
namespace {

using ojson = nlohmann::ordered_json;
constexpr double kDegree = 3.14159265358979323846 / 180;

// Fields of one line: [begin, end) offsets, trimmed.
std::vector<std::pair<std::size_t, std::size_t>> trace_fields(std::string_view l) {
  std::vector<std::pair<std::size_t, std::size_t>> f;
  std::size_t b = 0;
  while (true) {
    const std::size_t e = l.find(',', b);
    const std::size_t stop = e == std::string_view::npos ? l.size() : e;
    std::size_t x = b, y = stop;
    while (x < y && detail::is_blank(l[x])) ++x;
    while (y > x && detail::is_blank(l[y - 1])) --y;
    f.emplace_back(x, y);
    if (e == std::string_view::npos) break;
    b = e + 1;
  }
  return f;
}

// A time series' samples as runs and angles: a new run starts where the time goes back or jumps
// by more than kGap median sample intervals; run i is order[i], starting at the start angle at its
// first sample and moving at ω = feed / R in its direction.
void series_to_angles(const std::vector<double>& time, const std::vector<std::size_t>& lines,
                      const std::string& path, const TimeSeriesOptions& o, std::size_t time_col,
                      circular::Trace& t, std::vector<double>& angle) {
  o.validate();
  constexpr double kGap = 5;
  const std::size_t n = time.size();
  std::vector<double> dt;
  for (std::size_t k = 1; k < n; ++k)
    if (time[k] > time[k - 1]) dt.push_back(time[k] - time[k - 1]);
  if (dt.empty()) throw Error(fmt::format("{}: a time series needs times that increase", path));
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  const double step = dt[dt.size() / 2];
  const double omega = o.feed / 60 / o.radius;  // rad/s
  std::size_t run = 0, first = 0;
  auto where = [&](std::size_t k) {
    return fmt::format("{}:{}:{}: ", path, lines[k], time_col + 1);
  };
  for (std::size_t k = 0; k < n; ++k) {
    if (k > 0 && (time[k] <= time[k - 1] || time[k] - time[k - 1] > kGap * step)) {
      ++run;
      first = k;
      if (run >= o.order.size())
        throw Error(fmt::format(
            "{}run {} starts here (the time {} {:g} s after {:g} s), but the direction order "
            "names {} run{}",
            where(k), run + 1, time[k] <= time[k - 1] ? "goes back to" : "jumps to", time[k],
            time[k - 1], o.order.size(), o.order.size() == 1 ? "" : "s"));
    }
    const circular::Direction d = o.order[run];
    const double s = d == circular::Direction::Ccw ? 1.0 : -1.0;
    const double a = o.start_angle + s * omega * (time[k] - time[first]);
    if (std::abs(a - o.start_angle) > 4 * 3.14159265358979323846 + 1e-9)
      throw Error(fmt::format(
          "{}run {} has gone {:.0f}° round the circle at {:g} mm/min on a radius of {:g} mm: "
          "more than two turns, so the feed, the radius or the run boundaries are not this "
          "test's",
          where(k), run + 1, std::abs(a - o.start_angle) / kDegree, o.feed, o.radius));
    t.direction.push_back(d);
    angle.push_back(a);
  }
  if (run + 1 != o.order.size())
    throw Error(fmt::format(
        "{}: {} run{} found (runs are told apart where the time goes back or jumps), but the "
        "direction order names {}",
        path, run + 1, run == 0 ? "" : "s", o.order.size()));
}

}  // namespace

void TimeSeriesOptions::validate() const {
  if (!(feed > 0) || !std::isfinite(feed))
    throw Error("a time series needs the feed (mm/min, > 0) to turn times into angles");
  if (!(radius > 0) || !std::isfinite(radius))
    throw Error("a time series needs the radius (mm, > 0) to turn times into angles");
  if (!std::isfinite(start_angle)) throw Error("the start angle must be finite");
  if (order.empty() || order.size() > 2)
    throw Error("the direction order names one or two runs (ccw,cw; cw,ccw; ccw; cw)");
}

std::vector<circular::Direction> TimeSeriesOptions::order_of(const std::string& text) {
  const std::string t = detail::lower(text);
  using circular::Direction;
  if (t == "ccw,cw") return {Direction::Ccw, Direction::Cw};
  if (t == "cw,ccw") return {Direction::Cw, Direction::Ccw};
  if (t == "ccw") return {Direction::Ccw};
  if (t == "cw") return {Direction::Cw};
  throw Error(fmt::format("direction order '{}': use ccw,cw; cw,ccw; ccw or cw", text));
}

circular::Trace parse_trace(std::string text, const std::string& path,
                            const TimeSeriesOptions* series) {
  detail::normalize_text(text);
  if (std::optional<std::string> plain = detail::plain_csv(text, path)) text = std::move(*plain);
  circular::Trace t;
  std::vector<double> angle, deviation, time;
  std::vector<std::size_t> lines;
  int col[4] = {-1, -1, -1, -1};  // direction, angle, deviation, time
  double scale[4] = {1, 1, 1, 1};
  std::size_t ncol = 0;
  bool header = false, is_series = false;
  detail::for_each_line(text, [&](std::size_t line, std::string_view l) {
    std::size_t first = 0;
    while (first < l.size() && detail::is_blank(l[first])) ++first;
    if (first == l.size() || l[first] == '#') return;
    const auto f = trace_fields(l);
    auto fail = [&](std::size_t col0, const std::string& what) {
      detail::fail_at(path, line, col0, what);
    };
    if (!header) {
      header = true;
      ncol = f.size();
      const char* quantity[4] = {"direction", "angle", "deviation", "t"};
      const Unit unit[4] = {Unit::Count, Unit::Degree, Unit::Micrometre, Unit::Second};
      for (std::size_t c = 0; c < f.size(); ++c) {
        const std::string_view name = l.substr(f[c].first, f[c].second - f[c].first);
        int which = -1;
        for (int k = 0; k < 4 && which < 0; ++k) {
          ColumnMatch m;
          try {
            m = column_matches(name, quantity[k]);
          } catch (const Error& e) {
            fail(f[c].first, e.what());
          }
          if (!m.holds) continue;
          which = k;
          if (m.unit) {
            if (const std::string why =
                    unit_refusal(detail::quote_cut(name), *m.unit, quantity[k], unit[k]);
                !why.empty())
              fail(f[c].first, why);
            scale[k] = unit_factor(*m.unit, unit[k]);
          }
        }
        if (which < 0)
          fail(f[c].first,
               fmt::format("unknown column '{}' (direction, angle_deg, deviation_um; or t_s, "
                           "deviation_um for a time series)",
                           detail::quote_cut(name)));
        if (col[which] >= 0)
          fail(f[c].first, fmt::format("column '{}' holds the {} again", detail::quote_cut(name),
                                       quantity[which]));
        col[which] = static_cast<int>(c);
      }
      // A time series: times and deviations only, turned into angles below.
      is_series = col[0] < 0 && col[1] < 0 && col[3] >= 0 && col[2] >= 0;
      if (is_series && !series)
        fail(f[static_cast<std::size_t>(col[3])].first,
             "a time series (t_s, deviation_um): give the feed and the radius to turn the times "
             "into angles");
      if (is_series) {
        try {
          series->validate();
        } catch (const Error& e) {
          fail(f[static_cast<std::size_t>(col[3])].first, e.what());
        }
        return;
      }
      for (int k = 0; k < 3; ++k)
        if (col[k] < 0)
          fail(0, fmt::format("the header has no '{}' column (direction, angle_deg and "
                              "deviation_um are needed, or t_s and deviation_um)",
                              k == 0   ? "direction"
                              : k == 1 ? "angle_deg"
                                       : "deviation_um"));
      return;
    }
    if (f.size() != ncol)
      fail(f.size() < ncol ? l.size() : f[ncol].first - 1,
           fmt::format("{} fields, the header has {} columns", f.size(), ncol));
    auto number = [&](int k) {
      const auto [b, e] = f[static_cast<std::size_t>(col[k])];
      const char* s = l.data() + b;
      const char* se = l.data() + e;
      if (b < e && *s == '+') ++s;
      double v = 0;
      const auto res = std::from_chars(s, se, v);
      if (b == e || res.ec != std::errc() || res.ptr != se || !std::isfinite(v))
        fail(b, fmt::format("'{}' is not a number", detail::quote_cut(l.substr(b, e - b))));
      return v * scale[k];
    };
    if (is_series) {
      time.push_back(number(3));
      lines.push_back(line);
    } else {
      const auto [b, e] = f[static_cast<std::size_t>(col[0])];
      const std::string d = detail::lower(l.substr(b, e - b));
      if (d == "ccw")
        t.direction.push_back(circular::Direction::Ccw);
      else if (d == "cw")
        t.direction.push_back(circular::Direction::Cw);
      else
        fail(b, fmt::format("direction '{}': use ccw (angle increasing) or cw",
                            detail::quote_cut(l.substr(b, e - b))));
      angle.push_back(number(1) * kDegree);
    }
    const double dev = number(2);
    if (std::abs(dev) > detail::kMaxDeviation)
      fail(f[static_cast<std::size_t>(col[2])].first,
           fmt::format("{:g} µm is not a ballbar's deviation", dev));
    deviation.push_back(dev * 1e-3);
    t.where.push_back(
        fmt::format("{}:{}:{}: ", path, line, f[static_cast<std::size_t>(col[2])].first + 1));
  });
  if (!header) throw Error(fmt::format("{}: empty: no header and no samples", path));
  if (is_series)
    series_to_angles(time, lines, path, *series, static_cast<std::size_t>(col[3]), t, angle);
  t.angle = Eigen::Map<Eigen::VectorXd>(angle.data(), static_cast<Eigen::Index>(angle.size()));
  t.deviation =
      Eigen::Map<Eigen::VectorXd>(deviation.data(), static_cast<Eigen::Index>(deviation.size()));
  return t;
}

circular::Trace read_trace(const std::string& path, const TimeSeriesOptions* series) {
  return parse_trace(detail::read_text(path), path, series);
}

void write_trace(const std::string& path, const circular::Trace& t) {
  std::string s = "direction,angle_deg,deviation_um\n";
  char buf[32];
  for (Eigen::Index k = 0; k < t.angle.size(); ++k) {
    s += t.direction[static_cast<std::size_t>(k)] == circular::Direction::Ccw ? "ccw," : "cw,";
    s.append(buf, detail::write_number(buf, t.angle[k] / kDegree));
    s += ',';
    s.append(buf, detail::write_number(buf, t.deviation[k] * 1e3));
    s += '\n';
  }
  detail::OutFile out(path);
  out.write(s);
  out.close();
}

void write_circular_result(const std::string& path, const circular::Result& r,
                           const circular::Trace* trace) {
  ojson j;
  j["kind"] = "circular";
  j["standard"] = "ISO 230-4:2005";
  j["plane"] = r.plane.name();
  j["radius_mm"] = r.radius;
  j["feed_mm_per_min"] = r.feed;
  ojson g = ojson::object(), f = ojson::object(), lsc = ojson::object(), samples = ojson::object();
  for (const auto* d : {&r.ccw, &r.cw}) {
    if (!d->present) continue;
    const char* name = d == &r.ccw ? "ccw" : "cw";
    g[name] = d->G * 1e3;
    f[name] = {{"min", d->F_min * 1e3}, {"max", d->F_max * 1e3}};
    lsc[name] = {d->centre.x() * 1e3, d->centre.y() * 1e3};
    samples[name] = d->samples;
  }
  j["G_um"] = g;
  j["F_um"] = f;
  j["H_um"] = r.H ? ojson(*r.H * 1e3) : ojson(nullptr);
  j["ls_centre_um"] = lsc;
  j["samples"] = samples;
  // The causes, grouped by their keys' parts: "backlash.X" → diagnosis.backlash_um.X.
  ojson diag = ojson::object();
  for (const auto& c : r.causes) {
    ojson v{{"value", c.separated && std::isfinite(c.value) ? ojson(c.value) : ojson(nullptr)},
            {"u", c.separated && c.u ? ojson(*c.u) : ojson(nullptr)},
            {"share", c.share},
            {"name", c.name}};
    if (!c.separated) {
      v["separated"] = false;
      v["not_separated_from"] = c.confused_with;
    }
    const std::string unit = c.unit == "µm" ? "_um" : c.unit == "µm/m" ? "_um_per_m" : "_ms";
    std::vector<std::string> parts;
    std::size_t b = 0;
    while (true) {
      const std::size_t e = c.key.find('.', b);
      parts.push_back(c.key.substr(b, e == std::string::npos ? std::string::npos : e - b));
      if (e == std::string::npos) break;
      b = e + 1;
    }
    ojson* at = &diag[parts[0] + unit];
    for (std::size_t k = 1; k < parts.size(); ++k) at = &(*at)[parts[k]];
    *at = v;
  }
  diag["spike_decay_deg"] = r.spike_decay / kDegree;
  diag["spike_decay_u_deg"] = r.spike_decay_u ? ojson(*r.spike_decay_u / kDegree) : ojson(nullptr);
  if (!r.spike_decay_u) diag["spike_decay_note"] = r.spike_decay_note;
  diag["reversal_delay_resolution_deg"] = r.reversal_delay_resolution / kDegree;
  diag["reversal_delay_deg"] = {{std::string(1, "XYZ"[r.plane.a]), r.reversal_delay[0] / kDegree},
                                {std::string(1, "XYZ"[r.plane.b]), r.reversal_delay[1] / kDegree}};
  diag["unexplained_rms_um"] = r.unexplained_rms * 1e3;
  diag["sigma_um"] = r.sigma > 0 ? ojson(r.sigma * 1e3) : ojson(nullptr);
  j["diagnosis"] = diag;
  j["conventions"] =
      "angle from the plane's first axis towards its second; deviation = reading - calibrated "
      "length, positive outward; squareness > 0 when the actual axes make more than 90 deg; "
      "scale mismatch = first axis' scale error - second's; lag mismatch = first axis' "
      "following lag - second's; backlash > 0 when an axis stops short; reversal spikes > 0 "
      "outward";
  j["warnings"] = r.warnings;
  if (trace && r.model.size() == trace->angle.size()) {
    std::string dir;
    for (const auto d : trace->direction) dir += d == circular::Direction::Ccw ? '+' : '-';
    std::vector<double> a(trace->angle.data(), trace->angle.data() + trace->angle.size());
    for (double& x : a) x /= kDegree;
    std::vector<double> dv(static_cast<std::size_t>(trace->angle.size())), md(dv.size());
    for (std::size_t k = 0; k < dv.size(); ++k) {
      dv[k] = trace->deviation[static_cast<Eigen::Index>(k)] * 1e3;
      md[k] = r.model[static_cast<Eigen::Index>(k)] * 1e3;
    }
    j["trace"] = {{"direction", dir}, {"angle_deg", a}, {"deviation_um", dv}, {"model_um", md}};
  }
  write_json(path, j);
}

std::array<sim::ServoAxis, 3> read_servo(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  using P = nlohmann::json::json_pointer;
  std::array<sim::ServoAxis, 3> out;
  f.object(P());
  for (const auto& [key, value] : f.root().items()) {
    (void)value;
    if (key != "X" && key != "Y" && key != "Z") f.fail(P("/" + key), "an axis is X, Y or Z");
  }
  const char* names[3] = {"X", "Y", "Z"};
  for (int k = 0; k < 3; ++k) {
    const P at = P() / names[k];
    if (!f.has(at)) continue;
    f.object(at);
    auto& s = out[static_cast<std::size_t>(k)];
    auto get = [&](const char* name, double scale, double& into, bool positive) {
      if (!f.has(at / name)) return;
      const double v = f.number(at / name);
      if (positive ? !(v > 0) : !(v >= 0))
        f.fail(at / name, positive ? "must be > 0" : "must be >= 0");
      into = v * scale;
    };
    get("gain_per_s", 1, s.gain, false);
    get("backlash_um", 1e-3, s.backlash, false);
    get("spike_um", 1e-3, s.spike, false);
    get("spike_decay_deg", kDegree, s.spike_decay, true);
    get("cyclic_um", 1e-3, s.cyclic, false);
    get("pitch_mm", 1, s.pitch, true);
  }
  return out;
}

void write_circular_truth(const std::string& path, const sim::CircularTruth& t,
                          const circular::Plane& plane) {
  const std::string A(1, "XYZ"[plane.a]), B(1, "XYZ"[plane.b]);
  ojson j;
  j["kind"] = "circular truth";
  j["centre_offset_um"] = {{A, t.centre_offset.x() * 1e3}, {B, t.centre_offset.y() * 1e3}};
  j["squareness_um_per_m"] = t.squareness * 1e6;
  j["scale_mismatch_um_per_m"] = t.scale_mismatch * 1e6;
  j["lag_mismatch_ms"] = t.lag_mismatch * 1e3;
  j["backlash_um"] = {{A, t.backlash[0] * 1e3}, {B, t.backlash[1] * 1e3}};
  j["reversal_spike_um"] = {{A, t.spike[0] * 1e3}, {B, t.spike[1] * 1e3}};
  write_json(path, j);
}

CircularFile read_circular_result(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  using P = JsonFile::pointer;
  CircularFile out;
  circular::Result& r = out.result;
  try {
    r.plane = circular::Plane::parse(f.string(P("/plane")));
  } catch (const Error& e) {
    f.fail(P("/plane"), e.what());
  }
  r.radius = f.number(P("/radius_mm"));
  r.feed = f.number(P("/feed_mm_per_min"));
  for (const char* name : {"ccw", "cw"}) {
    if (!f.has(P("/G_um") / name)) continue;
    auto& d = std::string(name) == "ccw" ? r.ccw : r.cw;
    d.present = true;
    d.G = f.number(P("/G_um") / name) * 1e-3;
    d.F_min = f.number(P("/F_um") / name / "min") * 1e-3;
    d.F_max = f.number(P("/F_um") / name / "max") * 1e-3;
    if (f.has(P("/ls_centre_um") / name)) {
      const Eigen::VectorXd c = f.numbers(P("/ls_centre_um") / name, 1e-3);
      if (c.size() != 2) f.fail(P("/ls_centre_um") / name, "a centre is [a, b] (µm)");
      d.centre = c;
    }
    if (f.has(P("/samples") / name)) d.samples = static_cast<long>(f.number(P("/samples") / name));
  }
  if (f.has(P("/H_um")) && !f.root().at(P("/H_um")).is_null()) r.H = f.number(P("/H_um")) * 1e-3;
  // The causes: every object in the diagnosis holding a "value", its key the path to it with the
  // unit's suffix taken off the first part.
  const P diag("/diagnosis");
  f.object(diag);
  std::function<void(const P&, const std::string&, const std::string&)> walk =
      [&](const P& at, const std::string& key, const std::string& unit) {
        const auto& node = f.root().at(at);
        if (!node.is_object()) return;
        if (node.contains("value")) {
          circular::Cause c;
          c.key = key;
          c.unit = unit;
          c.name = f.has(at / "name") ? f.string(at / "name") : key;
          if (node.at("value").is_null()) {
            c.value = NAN;
            c.separated = false;
            if (f.has(at / "not_separated_from"))
              c.confused_with = f.string(at / "not_separated_from");
          } else {
            c.value = f.number(at / "value");
          }
          if (f.has(at / "u") && !node.at("u").is_null()) c.u = f.number(at / "u");
          if (f.has(at / "share")) c.share = f.number(at / "share");
          r.causes.push_back(c);
          return;
        }
        for (const auto& [k, v] : node.items()) {
          (void)v;
          walk(at / k, key + "." + k, unit);
        }
      };
  for (const auto& [k, v] : f.root().at(diag).items()) {
    if (!v.is_object()) continue;
    std::string base = k, unit = "µm";
    for (const auto& [suffix, u] :
         {std::pair<const char*, const char*>{"_um_per_m", "µm/m"}, {"_um", "µm"}, {"_ms", "ms"}})
      if (base.size() > std::strlen(suffix) &&
          base.compare(base.size() - std::strlen(suffix), std::string::npos, suffix) == 0) {
        base.resize(base.size() - std::strlen(suffix));
        unit = u;
        break;
      }
    walk(diag / k, base, unit);
  }
  if (f.has(diag / "spike_decay_deg")) r.spike_decay = f.number(diag / "spike_decay_deg") * kDegree;
  if (f.has(diag / "spike_decay_u_deg") && !f.root().at(diag / "spike_decay_u_deg").is_null())
    r.spike_decay_u = f.number(diag / "spike_decay_u_deg") * kDegree;
  if (f.has(diag / "spike_decay_note")) r.spike_decay_note = f.string(diag / "spike_decay_note");
  if (f.has(diag / "reversal_delay_resolution_deg"))
    r.reversal_delay_resolution = f.number(diag / "reversal_delay_resolution_deg") * kDegree;
  if (f.has(diag / "reversal_delay_deg")) {  // per axis; one number (files of 2026-11) for both
    const auto at = diag / "reversal_delay_deg";
    if (f.root().at(at).is_number()) {
      r.reversal_delay[0] = r.reversal_delay[1] = f.number(at) * kDegree;
    } else {
      r.reversal_delay[0] = f.number(at / std::string(1, "XYZ"[r.plane.a])) * kDegree;
      r.reversal_delay[1] = f.number(at / std::string(1, "XYZ"[r.plane.b])) * kDegree;
    }
  }
  r.unexplained_rms = f.number(diag / "unexplained_rms_um") * 1e-3;
  if (f.has(diag / "sigma_um") && !f.root().at(diag / "sigma_um").is_null())
    r.sigma = f.number(diag / "sigma_um") * 1e-3;
  if (f.has(P("/warnings")))
    for (const auto& w : f.array(P("/warnings")))
      if (w.is_string()) r.warnings.push_back(w.get<std::string>());
  if (f.has(P("/trace"))) {
    const P t("/trace");
    const std::string dir = f.string(t / "direction");
    out.trace.angle = f.numbers(t / "angle_deg", kDegree);
    out.trace.deviation = f.numbers(t / "deviation_um", 1e-3);
    r.model = f.numbers(t / "model_um", 1e-3);
    const auto n = out.trace.angle.size();
    if (static_cast<Eigen::Index>(dir.size()) != n || out.trace.deviation.size() != n ||
        r.model.size() != n)
      f.fail(t, "direction, angle_deg, deviation_um and model_um must have one entry per sample");
    for (char c : dir) {
      if (c != '+' && c != '-') f.fail(t / "direction", "one '+' (ccw) or '-' (cw) per sample");
      out.trace.direction.push_back(c == '+' ? circular::Direction::Ccw : circular::Direction::Cw);
    }
    r.residual = out.trace.deviation - r.model;
  }
  return out;
}

}  // namespace trueaxis::io
