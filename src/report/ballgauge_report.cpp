#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numeric>

#include "trueaxis/report/ballgauge.hpp"

namespace trueaxis::report {
namespace {

std::string um_2f(double mm) {
  return fmt::format("{:.2f}", mm * 1e3);
}

std::string alignment(ballgauge::Alignment a) {
  // The words of measurements.json, explained.
  return a == ballgauge::Alignment::ThreeTwoOne    ? "321 (3-2-1 on balls 0, 1, 2)"
         : a == ballgauge::Alignment::LeastSquares ? "ls (least squares over its balls)"
                                                   : "stitch (to the map's shared balls)";
}

}  // namespace

namespace {

// The identified error functions against travel, per axis: positioning and straightness (µm),
// roll, pitch and yaw (µrad), each with its ±2u band from the parameter covariance (the
// Chebyshev basis of the function at u against the covariance of its coefficients). Functions
// the data cannot see are left out and named.
void parametric_curves(const ballgauge::ParametricResult& pr, Section& s) {
  const int q = pr.degree + 1;
  const char* axes = "XYZ";
  for (int k = 0; k < 3; ++k) {
    const auto& range = pr.model.range[static_cast<std::size_t>(k)];
    constexpr int kPoints = 101;
    const Eigen::VectorXd u = Eigen::VectorXd::LinSpaced(kPoints, range[0], range[1]);
    for (int group = 0; group < 2; ++group) {
      Plot p;
      p.title = fmt::format("{} axis, identified {} against travel (±2u)", axes[k],
                            group == 0 ? "positioning and straightness" : "roll, pitch and yaw");
      p.x_label = fmt::format("{} (mm)", static_cast<char>(std::tolower(axes[k])));
      p.y_label = group == 0 ? "error (µm)" : "error (µrad)";
      p.x = u;
      std::string missing;
      for (int j = group * 3; j < group * 3 + 3; ++j) {
        const std::string name = sim::error_name(k, static_cast<sim::Component>(j));
        if (std::find(pr.unobservable.begin(), pr.unobservable.end(), name) !=
            pr.unobservable.end()) {
          missing += (missing.empty() ? "" : ", ") + name;
          continue;
        }
        const double sc = j < 3 ? 1e3 : 1e6;
        const auto& f = pr.model.errors[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)];
        const Eigen::Index base = (k * 6 + j) * q;
        Eigen::VectorXd y(kPoints), band(kPoints);
        for (int i = 0; i < kPoints; ++i) {
          y[i] = f(u[i]) * sc;
          const double t = (u[i] - pr.centre[k]) / pr.half_span[k];
          Eigen::VectorXd T(q);
          T[0] = 1;
          if (q > 1) T[1] = t;
          for (int d = 2; d < q; ++d) T[d] = 2 * t * T[d - 1] - T[d - 2];
          const bool have = pr.covariance.rows() >= base + q;
          band[i] =
              have ? std::sqrt(std::max(
                         0.0, (T.transpose() * pr.covariance.block(base, base, q, q) * T)(0, 0))) *
                         sc
                   : 0.0;
        }
        p.series.push_back({name, y, band, "", false});
      }
      if (!missing.empty()) p.title += " (not determined by the data: " + missing + ")";
      if (!p.series.empty()) s.plots.push_back(std::move(p));
    }
  }
}

}  // namespace

Section ballgauge_section(const std::string& title, const ballgauge::Result& r,
                          const ballgauge::ParametricResult* pr) {
  Section s;
  s.title = title;
  s.references = {refs::kOya, refs::kIso230, refs::kGum};
  double emax = 0, umax = 0;
  bool stated = true;
  for (const auto& p : r.points) {
    emax = std::max(emax, p.error.norm());
    if (p.uncertainty.allFinite())
      umax = std::max(umax, p.uncertainty.maxCoeff());
    else
      stated = false;
  }
  s.intro_html = fmt::format(
      "<p>Error vectors Δ = measured − true ball centre at {} mapped points from {} "
      "placements; largest |Δ| {} µm, {}. {}</p>",
      r.points.size(), r.placements.size(), um_2f(emax),
      stated ? fmt::format("largest standard uncertainty {} µm (it grows with every stitch)",
                           um_2f(umax))
             : std::string("uncertainty not stated (ball centres were given without theirs)"),
      r.frames > 1
          ? fmt::format("The {} aligned placements each map in their own frame: their errors "
                        "differ by rigid motions no ball ties down, so they form no common map.",
                        r.frames)
      : r.grid && r.grid->plane >= 0
          ? "The map holds the plate's plane: measured points on it are corrected by X = x − "
            "Δ(x), bilinear in the plane."
          : "Measured points are corrected by X = x − Δ(x), trilinear.");
  s.table = {{"placement", "alignment", "balls", "shared", "registration RMS (µm)",
              "sphere diameter error max (µm)"}};
  for (const auto& p : r.placements)
    s.table.push_back({p.name, alignment(p.alignment), std::to_string(p.balls),
                       std::to_string(p.shared), um_2f(p.registration_rms),
                       p.given_centres < p.balls ? um_2f(p.diameter_error_max) : "centres given"});
  if (pr) {
    // The parametric model and the squareness it gives have their own tables and headers.
    s.more_tables.push_back(
        {"Parametric model: the 21 rigid-body error functions fitted to every placement",
         {{"degree", "balls", "rank / unknowns", "residual RMS (µm)", "σ of a centre (µm)"},
          {std::to_string(pr->degree), std::to_string(pr->balls),
           fmt::format("{} / {}", pr->rank, pr->unknowns), um_2f(pr->residual_rms),
           um_2f(pr->sigma)}}});
    // Squareness as ISO 230-1 defines it (the angles between the axes' reference lines at the
    // tool point), with U = 2u from the parameter covariance.
    const char* names[3] = {"EC0Y", "EB0Z", "EA0Z"};
    const double values[3] = {pr->iso.lines.c0y, pr->iso.lines.b0z, pr->iso.lines.a0z};
    const double u[3] = {pr->iso.u_c0y, pr->iso.u_b0z, pr->iso.u_a0z};
    std::vector<std::vector<std::string>> sq = {{"error", "value (µrad)", "U (µrad, k = 2)"}};
    for (int i = 0; i < 3; ++i)
      sq.push_back(
          {names[i], fmt::format("{:.2f}", values[i] * 1e6), fmt::format("{:.2f}", 2e6 * u[i])});
    s.more_tables.push_back({"Squareness of the axes (ISO 230-1)", std::move(sq)});
  }
  if (pr) parametric_curves(*pr, s);
  if (r.grid) {
    const map::ErrorMap& m = *r.grid;
    double step = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 2; ++a)
      for (Eigen::Index i = 0; i + 1 < m.size(a); ++i)
        step = std::min(step, m.axes[static_cast<std::size_t>(a)][i + 1] -
                                  m.axes[static_cast<std::size_t>(a)][i]);
    const double inplane = m.error.topRows(2).colwise().norm().maxCoeff() * 1e3;
    const double mag = nice_magnification(std::max(inplane, 1e-6), step);
    // Every level on one colour scale, so that a colour means the same ez on each.
    const double ez = m.error.row(2).cwiseAbs().maxCoeff() * 1e3;
    for (Eigen::Index k = m.size(2) - 1; k >= 0; --k) {
      s.grids.push_back(distorted_plane(m, 0, 1, k, "error vectors", mag));
      s.grids.back().vmin = -ez;
      s.grids.back().vmax = ez;
    }
  }
  return s;
}

Section lengths_section(const std::string& title,
                        const std::vector<ballgauge::LengthVerification>& results,
                        const ballgauge::Mpe* mpe) {
  Section s;
  s.title = title;
  s.references = {refs::kIso10360_2, refs::kOya, refs::kGum};
  if (results.empty()) return s;
  const auto& first = results.front();
  s.intro_html = fmt::format(
      "<p>{} calibrated lengths in {} set-ups (a gauge length at one place; repeats have the "
      "same nominal and end points). "
      "Length error = measured − nominal, before and after correction, against the nominal "
      "length (as in Oya et al. 1988, figure 10). Expected after correction: the repeatability of "
      "the "
      "measurement and the correction's own uncertainty, added in quadrature.</p>",
      first.rows.size(), first.positions);
  s.table = {
      {"", "min (µm)", "max (µm)", "range (µm)", "mean (µm)", "RMS (µm)", "expected RMS (µm)"}};
  auto row = [&](const std::string& name, const ballgauge::LengthStats& st,
                 const std::string& expected) {
    s.table.push_back({name, um_2f(st.min), um_2f(st.max), um_2f(st.range()), um_2f(st.mean),
                       um_2f(st.rms), expected});
  };
  row("before correction", first.before, "");
  for (const auto& v : results)
    row("after, " + v.correction, v.after,
        std::isnan(v.predicted_after)
            ? "no repeats"
            : fmt::format("{} (repeatability {} ⊕ u {})", um_2f(v.predicted_after),
                          um_2f(v.repeatability), um_2f(v.correction_u_rms)));
  if (mpe) {
    // The E0 verdicts: a table of their own, under headers that fit them.
    std::vector<std::vector<std::string>> e0 = {
        {"E0", "verdict", "lengths beyond the MPE", "worst (% of the MPE)"}};
    auto verdict = [&](const std::string& name, const std::vector<ballgauge::LengthRow>& rows,
                       bool after) {
      const auto c = ballgauge::check_mpe(rows, *mpe, after);
      e0.push_back({name, c.pass() ? "PASS" : "FAIL", fmt::format("{} of {}", c.failed, c.lengths),
                    fmt::format("{:.0f}", 100 * c.worst_ratio)});
    };
    verdict("before correction", first.rows, false);
    for (const auto& v : results) verdict("after, " + v.correction, v.rows, true);
    s.more_tables.push_back(
        {fmt::format("E0 against the MPE {} µm (ISO 10360-2, L in mm)", mpe->text), std::move(e0)});
  }
  // Scatter: rows sorted by nominal length (uPlot wants x ascending; equal x are fine).
  std::vector<std::size_t> order(first.rows.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return first.rows[a].nominal < first.rows[b].nominal;
  });
  Plot p;
  p.title = "Length error against nominal length";
  p.x_label = "nominal length (mm)";
  p.y_label = "length error (µm)";
  // Before, and after each correction, at the same nominal lengths: each set is drawn a little
  // to the side of the nominal (in the order of the legend) so that no marker hides another.
  const auto n = static_cast<Eigen::Index>(order.size());
  const auto sets = static_cast<Eigen::Index>(results.size()) + 1;
  const double lo = n ? first.rows[order.front()].nominal : 0;
  const double hi = n ? first.rows[order.back()].nominal : 0;
  const double dodge = sets > 1 ? 0.008 * std::max(hi - lo, 1.0) : 0.0;
  p.x.resize(n * sets);
  std::vector<Series> series;
  series.push_back(
      {"before correction", Eigen::VectorXd::Constant(n * sets, NAN), {}, "#d62728", false, true});
  const char* colours[] = {"#1f77b4", "#2ca02c", "#9467bd"};
  for (std::size_t c = 0; c < results.size(); ++c)
    series.push_back({"after, " + results[c].correction,
                      Eigen::VectorXd::Constant(n * sets, NAN),
                      {},
                      colours[c % 3],
                      false,
                      true});
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index k = 0; k < sets; ++k) {
      const std::size_t row = order[static_cast<std::size_t>(i)];
      const Eigen::Index at = i * sets + k;
      p.x[at] = first.rows[row].nominal +
                dodge * (static_cast<double>(k) - 0.5 * static_cast<double>(sets - 1));
      series[static_cast<std::size_t>(k)].y[at] =
          (k == 0 ? first.rows[row].before
                  : results[static_cast<std::size_t>(k - 1)].rows[row].after) *
          1e3;
    }
  // Offsets are far smaller than the spacing of gauge lengths, but uPlot wants x ascending.
  std::vector<Eigen::Index> by_x(static_cast<std::size_t>(p.x.size()));
  std::iota(by_x.begin(), by_x.end(), Eigen::Index{0});
  std::stable_sort(by_x.begin(), by_x.end(),
                   [&](Eigen::Index a, Eigen::Index b) { return p.x[a] < p.x[b]; });
  const Eigen::VectorXd x = p.x;
  for (std::size_t k = 0; k < by_x.size(); ++k) p.x[static_cast<Eigen::Index>(k)] = x[by_x[k]];
  for (auto& se : series) {
    const Eigen::VectorXd y = se.y;
    for (std::size_t k = 0; k < by_x.size(); ++k) se.y[static_cast<Eigen::Index>(k)] = y[by_x[k]];
    p.series.push_back(std::move(se));
  }
  if (dodge > 0)
    p.title += fmt::format(" (each set drawn {:.2g} mm apart, beside its nominal length)", dodge);
  if (mpe) {  // the envelope ±MPE(L)
    Series up{"+MPE", Eigen::VectorXd(p.x.size()), {}, "#444444", true, false};
    Series down{"−MPE", Eigen::VectorXd(p.x.size()), {}, "#444444", true, false};
    for (Eigen::Index i = 0; i < p.x.size(); ++i) {
      up.y[i] = mpe->at(p.x[i]);
      down.y[i] = -up.y[i];
    }
    p.series.push_back(up);
    p.series.push_back(down);
    p.title += fmt::format(", with the E0 envelope ±({}) µm", mpe->text);
  }
  s.plots.push_back(std::move(p));
  return s;
}

}  // namespace trueaxis::report
