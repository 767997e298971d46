#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "trueaxis/report/positioning.hpp"

namespace trueaxis::report {
namespace {

std::string um_text(double mm, int digits = 2) {
  return std::isnan(mm) ? std::string("not defined") : fmt::format("{:.{}f} µm", mm * 1e3, digits);
}

}  // namespace

Section positioning_section(const std::string& title, const positioning::Result& r,
                            positioning::Standard standard,
                            const std::vector<positioning::Verdict>& verdicts) {
  const bool vdi = standard == positioning::Standard::Vdi3441;
  Section s;
  s.title = title;
  s.references = {vdi ? refs::kVdi3441 : refs::kIso230_2};
  if (r.temperature_corrected) s.references.push_back(refs::kIso1);
  s.warnings = r.warnings;
  const std::size_t m = r.targets.size();
  std::string temp;
  if (r.temperature_corrected)
    temp = fmt::format(
        " Deviations corrected to {:g} °C for the axis' expansion: material temperature {:.2f} … "
        "{:.2f} °C, expansion coefficient {:.3g} ppm/K about the datum at {:g} mm (largest "
        "correction {:.2f} µm).",
        r.reference_temperature, r.material_min, r.material_max, r.expansion_coefficient * 1e6,
        r.datum, r.max_correction * 1e3);
  else if (!std::isnan(r.material_min))
    temp = fmt::format(" Material temperature {:.2f} … {:.2f} °C; deviations not corrected.",
                       r.material_min, r.material_max);
  if (!std::isnan(r.air_min))
    temp += fmt::format(" Air temperature {:.2f} … {:.2f} °C.", r.air_min, r.air_max);
  s.intro_html = fmt::format(
      "<p>{} of a linear axis: {} targets from {:g} to {:g} mm, {} cycle{}, {}. Deviation = "
      "actual − target; ↑ approaches move in the positive direction, ↓ in the negative "
      "one.{}</p>",
      vdi ? "VDI/DGQ 3441 positional accuracy" : "ISO 230-2:2014 positioning accuracy", m,
      m ? r.targets.front().position : 0.0, m ? r.targets.back().position : 0.0, r.cycles,
      r.cycles == 1 ? "" : "s",
      r.has_up && r.has_down ? "both directions"
      : r.has_up             ? "↑ approaches only"
                             : "↓ approaches only",
      escape(temp));

  // Parameters with their tolerances.
  auto verdict_of = [&](const std::string& name) -> const positioning::Verdict* {
    for (const auto& v : verdicts)
      if (v.name == name) return &v;
    return nullptr;
  };
  s.table.push_back({"parameter", "symbol", "value", "tolerance", "result"});
  auto row = [&](const char* what, const char* symbol, const std::string& name) {
    const double value = positioning::parameter(r, name);
    const auto* v = verdict_of(name);
    s.table.push_back({what, symbol, um_text(value),
                       v ? fmt::format("{:g} µm", v->limit * 1e3) : "",
                       v ? (v->pass                  ? "pass"
                            : !v->not_judged.empty() ? "not judged (see the warning)"
                            : std::isnan(v->value)   ? "FAIL (not defined)"
                                                     : "FAIL")
                         : ""});
  };
  if (vdi) {
    row("positional uncertainty", "P", "P");
    row("positional deviation", "Pa", "Pa");
    row("positional scatter (largest)", "Ps", "Ps");
    s.table.push_back({"positional scatter (mean)", "Ps mean", um_text(r.vdi.Ps_mean), "", ""});
    row("reversal span (largest)", "U", "U");
    s.table.push_back({"reversal span (mean)", "U mean", um_text(r.vdi.U_mean), "", ""});
  } else {
    row("accuracy, bidirectional", "A", "A");
    row("accuracy, ↑", "A↑", "A_up");
    row("accuracy, ↓", "A↓", "A_down");
    row("systematic positional deviation, bidirectional", "E", "E");
    row("systematic positional deviation, ↑", "E↑", "E_up");
    row("systematic positional deviation, ↓", "E↓", "E_down");
    row("range of mean bidirectional positional deviation", "M", "M");
    row("repeatability, bidirectional (largest)", "R", "R");
    row("repeatability, ↑ (4s, largest)", "R↑", "R_up");
    row("repeatability, ↓ (4s, largest)", "R↓", "R_down");
    row("reversal value (largest |B_i|)", "B", "B");
    row("mean reversal value", "B̄", "B_mean");
  }

  // Per target.
  std::vector<std::vector<std::string>> per;
  if (vdi)
    per.push_back({"target (mm)", "x̄↑ (µm)", "s↑ (µm)", "x̄↓ (µm)", "s↓ (µm)", "U (µm)", "Ps (µm)"});
  else
    per.push_back({"target (mm)", "x̄↑ (µm)", "s↑ (µm)", "x̄↓ (µm)", "s↓ (µm)", "B (µm)", "R (µm)"});
  auto cell = [](double mm) {
    return std::isnan(mm) ? std::string("—") : fmt::format("{:.3f}", mm * 1e3);
  };
  for (const auto& t : r.targets)
    per.push_back({fmt::format("{:g}", t.position), cell(t.mean_up), cell(t.s_up),
                   cell(t.mean_down), cell(t.s_down), cell(vdi ? t.U : t.B),
                   cell(vdi ? t.Ps : t.R)});
  s.more_tables.push_back({"per target", per});

  // The standard's plot.
  Eigen::VectorXd x(static_cast<Eigen::Index>(m)), up(x.size()), down(x.size()), mean(x.size()),
      bu(x.size()), bd(x.size()), bm(x.size());
  for (std::size_t i = 0; i < m; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    const auto& t = r.targets[i];
    x[k] = t.position;
    up[k] = t.mean_up * 1e3;
    down[k] = t.mean_down * 1e3;
    mean[k] = t.mean * 1e3;
    // Bands are drawn at ±2 × the given half-width: s for ISO 230-2's ±2s, (U + Ps)/4 for VDI.
    bu[k] = t.s_up * 1e3;
    bd[k] = t.s_down * 1e3;
    bm[k] = (t.U + t.Ps) / 4 * 1e3;
  }
  Plot p;
  p.x_label = "target position (mm)";
  p.y_label = "positional deviation (µm)";
  p.x = x;
  if (vdi) {
    p.title = fmt::format("mean position x̄ with ±(U + Ps)/2 — P = {}, Pa = {}, Ps = {}, U = {}",
                          um_text(r.vdi.P), um_text(r.vdi.Pa), um_text(r.vdi.Ps), um_text(r.vdi.U));
    p.series.push_back({"x̄ ± (U + Ps)/2", mean, bm, "#444444", false, false,
                        "x̄ ± (U + Ps)/2 (VDI/DGQ 3441's spread about the mean position)"});
    if (r.has_up) p.series.push_back({"x̄↑", up, {}, "#1f77b4", true});
    if (r.has_down) p.series.push_back({"x̄↓", down, {}, "#d62728", true});
  } else {
    p.title = fmt::format("mean deviations with ±2s — A = {}, E = {}, M = {}, R = {}, B = {}",
                          um_text(r.iso.A), um_text(r.iso.E), um_text(r.iso.M), um_text(r.iso.R),
                          um_text(r.iso.B));
    const char* two_s =
        "x̄ ± 2s (ISO 230-2: twice the standard deviation of the readings at a target)";
    if (r.has_up) p.series.push_back({"x̄↑ ± 2s↑", up, bu, "#1f77b4", false, false, two_s});
    if (r.has_down) p.series.push_back({"x̄↓ ± 2s↓", down, bd, "#d62728", false, false, two_s});
    if (r.has_up && r.has_down)
      p.series.push_back({"x̄ (bidirectional mean)", mean, {}, "#444444", true});
  }
  s.plots.push_back(std::move(p));

  // Every reading, by direction.
  if (!r.readings.empty()) {
    std::vector<std::size_t> order(r.readings.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return r.readings[a].target < r.readings[b].target;
    });
    const auto n = static_cast<Eigen::Index>(order.size());
    Eigen::VectorXd rx(n), ru = Eigen::VectorXd::Constant(n, NAN), rd = ru;
    for (Eigen::Index k = 0; k < n; ++k) {
      const auto& q = r.readings[order[static_cast<std::size_t>(k)]];
      rx[k] = q.target;
      (q.direction == positioning::Direction::Up ? ru : rd)[k] = q.deviation * 1e3;
    }
    Plot q;
    q.title = r.temperature_corrected ? "every reading (corrected to the reference temperature)"
                                      : "every reading";
    q.x_label = "target position (mm)";
    q.y_label = "positional deviation (µm)";
    q.x = rx;
    if (r.has_up) q.series.push_back({"↑ readings", ru, {}, "#1f77b4", false, true});
    if (r.has_down) q.series.push_back({"↓ readings", rd, {}, "#d62728", false, true});
    s.plots.push_back(std::move(q));
  }
  return s;
}

void add_before_after(Section& s, const positioning::Result& before,
                      const positioning::Result& after) {
  // One x for both runs: the union of their targets; a run has no value (a gap) at the other's.
  std::vector<double> xs;
  for (const auto* r : {&before, &after})
    for (const auto& t : r->targets) xs.push_back(t.position);
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
  const auto n = static_cast<Eigen::Index>(xs.size());
  Plot p;
  p.title =
      fmt::format("before and after compensation — A {} → {}, E {} → {}, B̄ {} → {}",
                  um_text(before.iso.A), um_text(after.iso.A), um_text(before.iso.E),
                  um_text(after.iso.E), um_text(before.iso.B_mean), um_text(after.iso.B_mean));
  p.x_label = "target position (mm)";
  p.y_label = "positional deviation (µm)";
  p.x = Eigen::Map<const Eigen::VectorXd>(xs.data(), n);
  p.span_gaps = true;
  const char* two_s =
      "x̄ ± 2s (ISO 230-2: twice the standard deviation of the readings at a target)";
  auto add = [&](const positioning::Result& r, const char* when, bool dashed) {
    Eigen::VectorXd up = Eigen::VectorXd::Constant(n, NAN), down = up, su = up, sd = up;
    for (const auto& t : r.targets) {
      const auto k = static_cast<Eigen::Index>(std::lower_bound(xs.begin(), xs.end(), t.position) -
                                               xs.begin());
      up[k] = t.mean_up * 1e3;
      down[k] = t.mean_down * 1e3;
      su[k] = t.s_up * 1e3;
      sd[k] = t.s_down * 1e3;
    }
    // The same colour per direction in both runs; the run is told by the line (dashed before).
    if (r.has_up)
      p.series.push_back(
          {fmt::format("x̄↑ ± 2s↑ {}", when), up, su, "#1f77b4", dashed, false, two_s});
    if (r.has_down)
      p.series.push_back(
          {fmt::format("x̄↓ ± 2s↓ {}", when), down, sd, "#d62728", dashed, false, two_s});
  };
  add(before, "before", true);
  add(after, "after", false);
  s.plots.push_back(std::move(p));
  s.intro_html += fmt::format(
      "<p>Compared with the axis before compensation ({} targets, {} cycles): accuracy A {} → "
      "{}, systematic deviation E {} → {}, mean reversal B̄ {} → {}, repeatability R {} → {}. "
      "The plot \"before and after compensation\" draws both.</p>",
      before.targets.size(), before.cycles, um_text(before.iso.A), um_text(after.iso.A),
      um_text(before.iso.E), um_text(after.iso.E), um_text(before.iso.B_mean),
      um_text(after.iso.B_mean), um_text(before.iso.R), um_text(after.iso.R));
}

}  // namespace trueaxis::report
