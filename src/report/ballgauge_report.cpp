#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numeric>

#include "trueaxis/geometry/straightness.hpp"
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
        p.series.push_back({name, y, band, component_colour(j), false});
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

namespace {

// ISO 10360-2's view of the test: the lines the set-ups lie along (its "positions"), each with its
// worst length error before and after each correction, and every error drawn by position (a
// position whose errors grow with length shows the direction the machine errs along).
void add_positions(Section& s, const std::vector<ballgauge::LengthVerification>& results) {
  const auto& first = results.front();
  const auto lines = static_cast<int>(first.line_directions.size());
  if (lines == 0) return;
  for (const auto& v : results)
    for (const auto& r : v.rows)
      if (r.line < 0 || r.line >= lines) return;
  std::vector<std::vector<std::string>> t{
      {"position", "direction", "set-ups", "lengths", "max |E| before (µm)"}};
  for (const auto& v : results) t[0].push_back("max |E| after, " + v.correction + " (µm)");
  for (int l = 0; l < lines; ++l) {
    std::vector<int> setups;
    int n = 0;
    for (const auto& r : first.rows)
      if (r.line == l) {
        ++n;
        if (std::find(setups.begin(), setups.end(), r.position) == setups.end())
          setups.push_back(r.position);
      }
    auto worst = [&](const std::vector<ballgauge::LengthRow>& rows, bool after) {
      double w = 0;
      for (const auto& r : rows)
        if (r.line == l) w = std::max(w, std::abs(after ? r.after : r.before));
      return um_2f(w);
    };
    std::vector<std::string> row{
        fmt::format("{}", l + 1),
        ballgauge::direction_name(first.line_directions[static_cast<std::size_t>(l)]),
        fmt::format("{}", setups.size()), fmt::format("{}", n), worst(first.rows, false)};
    for (const auto& v : results) row.push_back(worst(v.rows, true));
    t.push_back(std::move(row));
  }
  s.more_tables.push_back({fmt::format("Positions (ISO 10360-2): the {} lines the set-ups lie "
                                       "along",
                                       lines),
                           std::move(t)});
  // Every length error at its position: a position's lengths from left to right, shortest first,
  // across the position's width; before and after each correction side by side.
  const auto sets = static_cast<Eigen::Index>(results.size()) + 1;
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& r : first.rows) {
    lo = std::min(lo, r.nominal);
    hi = std::max(hi, r.nominal);
  }
  const auto n = static_cast<Eigen::Index>(first.rows.size());
  std::vector<std::pair<double, Eigen::Index>> at;  // (x, row) of every marker, then sorted
  at.reserve(static_cast<std::size_t>(n * sets));
  for (Eigen::Index k = 0; k < sets; ++k)
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto& r = first.rows[static_cast<std::size_t>(i)];
      const double along = hi > lo ? (r.nominal - lo) / (hi - lo) : 0.5;  // 0..1
      at.emplace_back(r.line + 1 - 0.3 + 0.6 * along +
                          0.04 * (static_cast<double>(k) - 0.5 * static_cast<double>(sets - 1)),
                      k * n + i);
    }
  std::stable_sort(at.begin(), at.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  Plot p;
  p.title = fmt::format(
      "Length error by ISO 10360-2 position: at each position its lengths left to right, "
      "{:g} to {:g} mm",
      lo, hi);
  p.x_label = "position";
  p.whole_x = true;
  p.y_label = "length error (µm)";
  p.x.resize(static_cast<Eigen::Index>(at.size()));
  std::vector<Series> series;
  series.push_back({"before correction",
                    Eigen::VectorXd::Constant(p.x.size(), NAN),
                    {},
                    "#d62728",
                    false,
                    true});
  const char* colours[] = {"#1f77b4", "#2ca02c", "#9467bd"};
  for (std::size_t c = 0; c < results.size(); ++c)
    series.push_back({"after, " + results[c].correction,
                      Eigen::VectorXd::Constant(p.x.size(), NAN),
                      {},
                      colours[c % 3],
                      false,
                      true});
  for (std::size_t j = 0; j < at.size(); ++j) {
    const auto J = static_cast<Eigen::Index>(j);
    const Eigen::Index k = at[j].second / n, i = at[j].second % n;
    p.x[J] = at[j].first;
    const auto& rows = k == 0 ? first.rows : results[static_cast<std::size_t>(k - 1)].rows;
    const auto& r = rows[static_cast<std::size_t>(i)];
    series[static_cast<std::size_t>(k)].y[J] = (k == 0 ? r.before : r.after) * 1e3;
  }
  for (auto& se : series) p.series.push_back(std::move(se));
  s.plots.push_back(std::move(p));
}

}  // namespace

Section lengths_section(const std::string& title,
                        const std::vector<ballgauge::LengthVerification>& results,
                        const ballgauge::Mpe* mpe) {
  Section s;
  s.title = title;
  s.references = {refs::kIso10360_2, refs::kOya, refs::kGum};
  if (results.empty()) return s;
  const auto& first = results.front();
  s.intro_html = fmt::format(
      "<p>{} calibrated lengths in {} set-ups{} (a set-up is a gauge length at one place; "
      "repeats have the same nominal and end points). "
      "Length error = measured − nominal, before and after correction, against the nominal "
      "length (as in Oya et al. 1988, figure 10). Expected after correction: the repeatability of "
      "the "
      "measurement and the correction's own uncertainty, added in quadrature.</p>",
      first.rows.size(), first.positions,
      first.line_directions.empty()
          ? std::string()
          : fmt::format(" along {} lines, ISO 10360-2's positions", first.line_directions.size()));
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
  add_positions(s, results);
  return s;
}

FunctionDifferences add_error_functions(Section& s, const ballgauge::ParametricResult& model,
                                        const sim::Machine& known, const std::string& known_name) {
  FunctionDifferences worst;
  constexpr int kSamples = 61;
  const char* axes = "XYZ";
  std::vector<std::vector<std::string>> t{
      {"error", "largest |identified − " + known_name + "|", "its span (" + known_name + ")"}};
  // Both machines with the stylus the model was identified for: the tip is what the data see.
  sim::Machine identified = model.model, truth = known;
  truth.offset = identified.offset;
  // The axis that carries the stylus: with one stylus its rotations move the tip by a constant
  // lever, exactly as its own straightness does, so the data see only their sum.
  const int tool_axis = identified.order()[2];
  const bool one_stylus = model.styli.size() <= 1;
  for (int k = 0; k < 3; ++k) {
    const auto K = static_cast<std::size_t>(k);
    const double lo = identified.range[K][0], hi = identified.range[K][1];
    const Eigen::VectorXd u = Eigen::VectorXd::LinSpaced(kSamples, lo, hi);
    const double mid = (lo + hi) / 2;
    // The axis' line through the middle of the identified span.
    Eigen::Matrix3Xd line(3, kSamples);
    for (Eigen::Index i = 0; i < kSamples; ++i) {
      line.col(i) = model.centre;
      line(k, i) = u[i];
    }
    const Eigen::Matrix3Xd tip_a = identified.errors_at(line), tip_b = truth.errors_at(line);
    for (int group = 0; group < 2; ++group) {
      const double sc = group == 0 ? 1e3 : 1e6;
      const char* unit = group == 0 ? "µm" : "µrad";
      Plot p;
      p.title = group == 0
                    ? fmt::format(
                          "{} axis: error of the stylus tip as {} moves (the others "
                          "mid-span), identified (solid) and {} (dashed); across "
                          "components less their slope",
                          axes[k], axes[k], known_name)
                    : fmt::format("{} axis: rotation errors, identified (solid) and {} (dashed)",
                                  axes[k], known_name);
      p.x_label = fmt::format("{} (mm)", axes[k]);
      p.y_label = fmt::format("error ({})", unit);
      p.x = u;
      for (int c = 0; c < 3; ++c) {
        const int comp = 3 * group + c;
        const auto C = static_cast<std::size_t>(comp);
        // Less the value mid-span; the components across the axis also less their slope.
        auto relative = [&](Eigen::VectorXd v, double at_mid) {
          v.array() -= at_mid;
          if (group == 0 && c != k)
            v -= geometry::fit_line(u, v).slope * (u.array() - mid).matrix();
          return Eigen::VectorXd(v * sc);
        };
        auto sample = [&](const sim::ErrorFunction& f) {
          Eigen::VectorXd v(kSamples);
          for (Eigen::Index i = 0; i < kSamples; ++i) v[i] = f.empty() ? 0.0 : f(u[i]);
          return relative(v, f.empty() ? 0.0 : f(mid));
        };
        Eigen::VectorXd a, b;
        if (group == 0) {
          const Eigen::VectorXd ra = tip_a.row(c).transpose(), rb = tip_b.row(c).transpose();
          a = relative(ra, ra[kSamples / 2]);
          b = relative(rb, rb[kSamples / 2]);
        } else {
          a = sample(identified.errors[K][C]);
          b = sample(known.errors[K][C]);
        }
        const std::string name = sim::error_name(k, static_cast<sim::Component>(comp));
        // A rotation the data do not see (no effect on this stylus tip), or cannot tell from a
        // straightness, is not compared: its identified value is only the solver's choice.
        const bool unseen = std::find(model.unobservable.begin(), model.unobservable.end(), name) !=
                            model.unobservable.end();
        const bool confounded = group == 1 && !unseen && k == tool_axis && one_stylus;
        if (group == 1 && (unseen || confounded)) {
          p.series.push_back({name + " " + known_name, b, {}, component_colour(comp), true});
          t.push_back({name,
                       unseen ? "not determined by these data"
                              : "not separated from the straightness (one stylus): the tip's "
                                "error above holds both",
                       fmt::format("{:.3g} {}", b.maxCoeff() - b.minCoeff(), unit)});
          continue;
        }
        const std::string shown = group == 0 ? name + " at the tip" : name;
        p.series.push_back({shown, a, {}, component_colour(comp), false});
        p.series.push_back({shown + " " + known_name, b, {}, component_colour(comp), true});
        const double d = (a - b).cwiseAbs().maxCoeff();
        (group == 0 ? worst.translation : worst.rotation) =
            std::max(group == 0 ? worst.translation : worst.rotation, d / sc);
        t.push_back({shown, fmt::format("{:.3g} {}", d, unit),
                     fmt::format("{:.3g} {}", b.maxCoeff() - b.minCoeff(), unit)});
      }
      s.plots.push_back(std::move(p));
    }
  }
  // The squareness errors, as ISO 230-1 defines them (angles between the reference lines over
  // the identified span).
  sim::Machine same_span = known;
  same_span.range = model.model.range;
  const auto ref = sim::reference_lines(same_span, model.centre);
  const std::array<std::pair<const char*, std::pair<double, double>>, 3> sq{
      {{"EC0Y", {model.iso.lines.c0y, ref.c0y}},
       {"EB0Z", {model.iso.lines.b0z, ref.b0z}},
       {"EA0Z", {model.iso.lines.a0z, ref.a0z}}}};
  for (const auto& [name, v] : sq) {
    worst.squareness = std::max(worst.squareness, std::abs(v.first - v.second));
    t.push_back({name, fmt::format("{:.3g} µrad", std::abs(v.first - v.second) * 1e6),
                 fmt::format("{:.3g} µrad", v.second * 1e6)});
  }
  t[0][2] = "its span or value (" + known_name + ")";
  s.more_tables.push_back(
      {fmt::format("The identified errors against the {} ones (as drawn)", known_name),
       std::move(t)});
  return worst;
}

}  // namespace trueaxis::report
