#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "../common/figures.hpp"
#include "trueaxis/report/circular.hpp"

namespace trueaxis::report {

Section circular_section(const std::string& title, const circular::Result& r,
                         const circular::Trace& t) {
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
      "outward, decaying over {:.1f}° of the circle.</p>",
      plane, r.radius, r.feed, plane[0], plane[1], plane[0], plane[1], plane[0], plane[1], plane[0],
      plane[1], r.spike_decay / kDeg);
  s.table.push_back({"direction", "G (µm)", "F min (µm)", "F max (µm)", "samples"});
  for (const auto* d : {&r.ccw, &r.cw})
    if (d->present)
      s.table.push_back({d == &r.ccw ? "ccw" : "cw", fmt::format("{:.2f}", d->G * 1e3),
                         fmt::format("{:+.2f}", d->F_min * 1e3),
                         fmt::format("{:+.2f}", d->F_max * 1e3), fmt::format("{}", d->samples)});
  if (r.H) s.table.push_back({"H, both directions", fmt::format("{:.2f}", *r.H * 1e3), "", "", ""});
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
  const double worst = t.deviation.size() ? t.deviation.cwiseAbs().maxCoeff() * 1e3 : 0;  // µm
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
  for (const auto dir : {circular::Direction::Ccw, circular::Direction::Cw}) {
    std::vector<Eigen::Index> idx;
    for (Eigen::Index k = 0; k < t.angle.size(); ++k)
      if (t.direction[static_cast<std::size_t>(k)] == dir) idx.push_back(k);
    if (idx.empty()) continue;
    std::stable_sort(idx.begin(), idx.end(), [&](Eigen::Index p, Eigen::Index q) {
      return std::remainder(t.angle[p], 2 * 180 * kDeg) <
             std::remainder(t.angle[q], 2 * 180 * kDeg);
    });
    Eigen::Matrix2Xd xy(2, static_cast<Eigen::Index>(idx.size()));
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const double th = t.angle[idx[k]], rho = r.radius + mag * t.deviation[idx[k]];
      xy.col(static_cast<Eigen::Index>(k)) = rho * Eigen::Vector2d(std::cos(th), std::sin(th));
    }
    const bool ccw = dir == circular::Direction::Ccw;
    v.curves.push_back({ccw ? "ccw" : "cw", xy, ccw ? "#1f77b4" : "#d62728", false, false, true});
  }
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

}  // namespace trueaxis::report
