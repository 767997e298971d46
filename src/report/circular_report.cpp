#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "../common/figures.hpp"
#include "trueaxis/report/circular.hpp"

namespace trueaxis::report {

Section circular_section(const std::string& title, const circular::Result& r,
                         const circular::Trace& t, const CircularBefore& before) {
  constexpr double kDeg = 3.14159265358979323846 / 180;
  Section s;
  s.title = title;
  s.references = {refs::kIso230_4, refs::kGum};
  s.warnings = r.warnings;
  const std::string plane = r.plane.name();
  s.intro_html = fmt::format(
      "<p>A circular test in the {} plane: radius {:g} mm (the ballbar's calibrated length), "
      "feed {:g} mm/min. The angle runs from +{} towards +{}; a deviation is the ballbar's "
      "reading less its length, positive outward. G is the radial band of a path about its "
      "least-squares circle, F its smallest and largest deviation about the nominal circle, H "
      "the largest difference of the two directions at one angle.</p><p>Diagnosis: the trace "
      "is fitted, both directions at once, with each cause's signature; a cause's share is the "
      "peak-to-valley of its own part over the larger G. Conventions: squareness is positive "
      "when the actual +{} and +{} make more than 90° (the 45° diagonal comes out short); the "
      "scale mismatch is {}'s scale error less {}'s; the lag mismatch {}'s following lag less "
      "{}'s; backlash is positive when an axis stops short; reversal spikes are positive "
      "outward, decaying over {:.1f}° of the circle{}; {} reverses {:.2f}° and {} {:.2f}° after "
      "the "
      "command (their following lags' phase; the samples, {:.2f}° apart, resolve no finer).</p>",
      plane, r.radius, r.feed, plane[0], plane[1], plane[0], plane[1], plane[0], plane[1], plane[0],
      plane[1], r.spike_decay / kDeg,
      r.spike_decay_u ? fmt::format(" (u {:.2f}°)", *r.spike_decay_u / kDeg)
                      : fmt::format(" ({})", report::escape(r.spike_decay_note)),
      plane[0], r.reversal_delay[0] / kDeg, plane[1], r.reversal_delay[1] / kDeg,
      r.reversal_delay_resolution / kDeg);
  s.table.push_back({"direction", "G (µm)", "F min (µm)", "F max (µm)", "samples"});
  for (const auto* d : {&r.ccw, &r.cw})
    if (d->present)
      s.table.push_back({d == &r.ccw ? "ccw" : "cw", fmt::format("{:.2f}", d->G * 1e3),
                         fmt::format("{:+.2f}", d->F_min * 1e3),
                         fmt::format("{:+.2f}", d->F_max * 1e3), fmt::format("{}", d->samples)});
  if (r.H) s.table.push_back({"H, both directions", fmt::format("{:.2f}", *r.H * 1e3), "", "", ""});
  const bool has_before = before.result && before.trace;
  if (has_before) {
    const circular::Result& b = *before.result;
    s.table[0].push_back("before: G or H (µm)");
    for (std::size_t row = 1; row < s.table.size(); ++row) {
      const std::string& name = s.table[row][0];
      const circular::DirectionFigures* d = name == "ccw" ? &b.ccw : name == "cw" ? &b.cw : nullptr;
      s.table[row].push_back(d ? (d->present ? fmt::format("{:.2f}", d->G * 1e3) : "not run")
                               : (b.H ? fmt::format("{:.2f}", *b.H * 1e3) : "not defined"));
    }
  }
  std::vector<std::vector<std::string>> diag{{"cause", "value", "u (1σ)", "share of G"}};
  for (const auto& c : r.causes) {
    if (!c.separated) {
      diag.push_back({c.name, "not separated from " + c.confused_with, "", ""});
      continue;
    }
    diag.push_back(
        {c.name,
         (c.u ? trueaxis::detail::rounded_to(c.value, *c.u) : fmt::format("{:.3g}", c.value)) +
             " " + c.unit,
         c.u ? fmt::format("{} {}", trueaxis::detail::two_digits(*c.u), c.unit)
             : std::string("not stated"),
         fmt::format("{:.0f} %", 100 * c.share)});
  }
  diag.push_back({"unexplained (RMS of the residual)",
                  fmt::format("{:.3f} µm", r.unexplained_rms * 1e3), "", ""});
  s.more_tables.push_back({"Diagnosis: the trace explained by its causes", std::move(diag)});
  s.summary =
      fmt::format("G {}; H {}",
                  r.ccw.present && r.cw.present
                      ? fmt::format("{:.2f} µm ccw, {:.2f} µm cw", r.ccw.G * 1e3, r.cw.G * 1e3)
                      : fmt::format("{:.2f} µm", std::max(r.ccw.G, r.cw.G) * 1e3),
                  r.H ? fmt::format("{:.2f} µm", *r.H * 1e3) : std::string("not defined"));

  // The polar plot: each path at R + M·δr about the pivot, the nominal circle, and rings at a
  // round deviation either side.
  double worst = t.deviation.size() ? t.deviation.cwiseAbs().maxCoeff() * 1e3 : 0;  // µm
  if (has_before && before.trace->deviation.size())
    worst = std::max(worst, before.trace->deviation.cwiseAbs().maxCoeff() * 1e3);
  const double mag = nice_magnification(std::max(worst, 1e-3), r.radius, 0.25);
  const double ring = [&] {  // µm: 1, 2 or 5 × 10^k about the largest deviation
    const double p = std::pow(10.0, std::floor(std::log10(std::max(worst, 1e-3))));
    const double x = worst / p;
    return (x > 5 ? 10 : x > 2 ? 5 : x > 1 ? 2 : 1) * p;
  }();
  PlaneView v;
  v.title = fmt::format(
      "polar plot: deviations ×{:g} about the nominal circle; dashed rings at ±{:g} µm", mag, ring);
  v.x_label = fmt::format("{} (mm)", plane[0]);
  v.y_label = fmt::format("{} (mm)", plane[1]);
  auto circle = [&](double radius) {
    Eigen::Matrix2Xd c(2, 361);
    for (int k = 0; k <= 360; ++k)
      c.col(k) = radius * Eigen::Vector2d(std::cos(k * kDeg), std::sin(k * kDeg));
    return c;
  };
  v.curves.push_back({"nominal circle", circle(r.radius), "#757575", false, false, true});
  v.curves.push_back({fmt::format("±{:g} µm", ring), circle(r.radius + mag * ring * 1e-3),
                      "#bdbdbd", true, false, true});
  v.curves.push_back({"", circle(r.radius - mag * ring * 1e-3), "#bdbdbd", true, false, true});
  // Each direction's path, sorted by angle; `old` paths (before a compensation) dashed and paler.
  auto paths = [&](const circular::Trace& tr, bool old) {
    for (const auto dir : {circular::Direction::Ccw, circular::Direction::Cw}) {
      std::vector<Eigen::Index> idx;
      for (Eigen::Index k = 0; k < tr.angle.size(); ++k)
        if (tr.direction[static_cast<std::size_t>(k)] == dir) idx.push_back(k);
      if (idx.empty()) continue;
      std::stable_sort(idx.begin(), idx.end(), [&](Eigen::Index p, Eigen::Index q) {
        return std::remainder(tr.angle[p], 2 * 180 * kDeg) <
               std::remainder(tr.angle[q], 2 * 180 * kDeg);
      });
      Eigen::Matrix2Xd xy(2, static_cast<Eigen::Index>(idx.size()));
      for (std::size_t k = 0; k < idx.size(); ++k) {
        const double th = tr.angle[idx[k]], rho = r.radius + mag * tr.deviation[idx[k]];
        xy.col(static_cast<Eigen::Index>(k)) = rho * Eigen::Vector2d(std::cos(th), std::sin(th));
      }
      const bool ccw = dir == circular::Direction::Ccw;
      const std::string label = std::string(ccw ? "ccw" : "cw") + (old ? ", before" : "");
      const char* colour = old ? (ccw ? "#9ecae1" : "#fcae91") : (ccw ? "#1f77b4" : "#d62728");
      v.curves.push_back(
          {has_before && !old ? label + ", after" : label, xy, colour, old, false, true});
    }
  };
  if (has_before) paths(*before.trace, true);
  paths(t, false);
  s.planes.push_back(std::move(v));

  // Per direction: the trace against the angle with the fitted model, and the residual.
  for (const auto dir : {circular::Direction::Ccw, circular::Direction::Cw}) {
    std::vector<Eigen::Index> idx;
    for (Eigen::Index k = 0; k < t.angle.size(); ++k)
      if (t.direction[static_cast<std::size_t>(k)] == dir) idx.push_back(k);
    if (idx.empty()) continue;
    auto wrapped = [&](Eigen::Index k) {
      const double a = std::fmod(t.angle[k] / kDeg, 360.0);
      return a < 0 ? a + 360 : a;
    };
    std::stable_sort(idx.begin(), idx.end(),
                     [&](Eigen::Index p, Eigen::Index q) { return wrapped(p) < wrapped(q); });
    const auto n = static_cast<Eigen::Index>(idx.size());
    Plot p;
    const char* name = dir == circular::Direction::Ccw ? "ccw" : "cw";
    p.title =
        fmt::format("{}: the trace against the angle, the fitted causes and what remains", name);
    p.x_label = "angle (°)";
    p.y_label = "radial deviation (µm)";
    p.x.resize(n);
    Eigen::VectorXd y(n), m(n), res(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index k = idx[static_cast<std::size_t>(i)];
      p.x[i] = wrapped(k);
      y[i] = t.deviation[k] * 1e3;
      m[i] = r.model.size() == t.angle.size() ? r.model[k] * 1e3 : NAN;
      res[i] = y[i] - m[i];
    }
    p.series.push_back(
        {"measured", y, {}, dir == circular::Direction::Ccw ? "#1f77b4" : "#d62728", false});
    p.series.push_back({"fitted causes", m, {}, "#444444", true});
    p.series.push_back({"residual", res, {}, "#2ca02c", false});
    s.plots.push_back(std::move(p));
  }
  return s;
}

void add_compensation(Section& s, const circular::Compensation& c,
                      const std::vector<std::vector<std::string>>& files) {
  const char* axes = "XYZ";
  std::vector<std::vector<std::string>> t{
      {"compensation", "to enter", "active in the test", "the test found (±u)", "note"}};
  auto row = [&](const std::string& name, const circular::CompensationValue& v, double scale,
                 const char* unit) {
    t.push_back({name, fmt::format("{:+.2f} {}", v.value * scale, unit),
                 fmt::format("{:+.2f} {}", v.active * scale, unit),
                 std::isfinite(v.diagnosed) && v.u
                     ? fmt::format("{} ± {} {}",
                                   trueaxis::detail::rounded_to(v.diagnosed * scale, *v.u * scale),
                                   trueaxis::detail::two_digits(*v.u * scale), unit)
                     : std::string("not resolved"),
                 v.changed ? "changed" : "unchanged: " + v.reason});
  };
  for (int i = 0; i < 2; ++i)
    row(fmt::format("backlash of {}", axes[i == 0 ? c.plane.a : c.plane.b]),
        c.backlash[static_cast<std::size_t>(i)], 1e3, "µm");
  row(fmt::format("squareness: {} corrected by slope × {}", axes[c.plane.a], axes[c.plane.b]),
      c.squareness, 1e6, "µm/m");
  s.more_tables.push_back({"What to give the controller", std::move(t)});
  if (files.size() > 1)
    s.more_tables.push_back({"Compensation files (each read back and checked)", files});
}

}  // namespace trueaxis::report
