// Report sections for error surfaces and error spaces.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "../common/figures.hpp"
#include "trueaxis/geometry/triangulation.hpp"
#include "trueaxis/report/surface.hpp"

namespace trueaxis::report {
namespace {

std::string joined(const std::vector<std::string>& v, const char* empty = "nothing") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s.empty() ? empty : s;
}

std::string um_3f(double mm) {
  return fmt::format("{:.3f}", mm * 1e3);
}

// A heat map over the x-y plane (mm).
HeatMap xy_map(std::string title, std::string value_label, int width) {
  HeatMap h;
  h.title = std::move(title);
  h.x_label = "x (mm)";
  h.y_label = "y (mm)";
  h.value_label = std::move(value_label);
  h.width = width;
  return h;
}

// The height field as a contour map: the stations (a station on several lines once, at the mean
// of its heights) triangulated, the heights linear over each triangle, drawn as cells (when the
// method gives no lattice of its own) and as contour lines at a round step.
void add_contours(HeatMap& h, const surface::Result& r) {
  std::vector<Eigen::Vector2d> xy;
  std::vector<double> sum;
  std::vector<int> count;
  for (const auto& p : r.points) {
    std::size_t k = 0;
    while (k < xy.size() && (xy[k] - p.xy).norm() > 1e-6) ++k;
    if (k == xy.size()) {
      xy.push_back(p.xy);
      sum.push_back(0);
      count.push_back(0);
    }
    sum[k] += p.height * 1e3;
    ++count[k];
  }
  const auto n = static_cast<Eigen::Index>(xy.size());
  Eigen::Matrix2Xd pts(2, n);
  Eigen::VectorXd z(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    pts.col(k) = xy[static_cast<std::size_t>(k)];
    z[k] = sum[static_cast<std::size_t>(k)] / count[static_cast<std::size_t>(k)];
  }
  const auto tris = geometry::delaunay(pts);
  if (tris.empty() || !(z.maxCoeff() > z.minCoeff())) return;
  if (!r.grid) {
    // Cells about 1/45 of the longer side, square.
    const Eigen::Vector2d lo = pts.rowwise().minCoeff(), hi = pts.rowwise().maxCoeff();
    const double step = (hi - lo).maxCoeff() / 45;
    const auto nx = std::max<Eigen::Index>(2, std::lround((hi.x() - lo.x()) / step) + 1);
    const auto ny = std::max<Eigen::Index>(2, std::lround((hi.y() - lo.y()) / step) + 1);
    h.grid_x = Eigen::VectorXd::LinSpaced(nx, lo.x(), hi.x());
    h.grid_y = Eigen::VectorXd::LinSpaced(ny, lo.y(), hi.y());
    Eigen::Matrix2Xd q(2, nx * ny);
    for (Eigen::Index j = 0; j < ny; ++j)
      for (Eigen::Index i = 0; i < nx; ++i) q.col(j * nx + i) << h.grid_x[i], h.grid_y[j];
    const Eigen::VectorXd v = geometry::interpolate_linear(pts, z, tris, q);
    h.grid_value.resize(ny, nx);
    for (Eigen::Index j = 0; j < ny; ++j)
      for (Eigen::Index i = 0; i < nx; ++i) h.grid_value(j, i) = v[j * nx + i];
  }
  // About ten contours at 1, 2 or 5 × 10^k µm.
  const double span = z.maxCoeff() - z.minCoeff();
  const double raw = span / 10, p10 = std::pow(10.0, std::floor(std::log10(raw)));
  const double step = (raw / p10 > 5 ? 10 : raw / p10 > 2 ? 5 : raw / p10 > 1 ? 2 : 1) * p10;
  for (double level = std::ceil(z.minCoeff() / step) * step; level < z.maxCoeff(); level += step) {
    for (const auto& [a, b] : geometry::contour_segments(pts, z, tris, level)) {
      Eigen::Matrix2Xd seg(2, 2);
      seg << a.x(), b.x(), a.y(), b.y();
      h.contours.push_back(std::move(seg));
    }
  }
  if (!r.grid) h.band_step = step;
  h.title =
      r.grid ? fmt::format("heights (cells: the lattice of stations), contours every {:g} µm", step)
             : fmt::format(
                   "heights: measured at the stations (dots; lines in grey), linear "
                   "between them; contours every {:g} µm",
                   step);
}

}  // namespace

Section surface_section(const std::string& title, const surface::Result& r,
                        const std::string& intro_html) {
  Section s;
  s.title = title;
  s.references = {refs::kMoody, refs::kIso12780};
  s.intro_html = intro_html +
                 fmt::format("<p>Heights in µm, {}. Not determined by the lines: {}; {}.</p>",
                             escape(r.reference), escape(joined(r.unobservable)), escape(r.gauge));
  s.table = {
      {"quantity", "value"},
      {"method", r.method},
      {"lines / stations", fmt::format("{} / {}", r.lines.size(), r.points.size())},
      {"flatness, least squares (µm)",
       r.U ? (*r.resolved() ? trueaxis::detail::rounded_to(r.flatness_ls * 1e3, *r.U * 1e3)
                            : std::string("not resolved"))
           : um_3f(r.flatness_ls)},
      {"flatness, minimum zone (µm)",
       r.U ? (*r.resolved() ? trueaxis::detail::rounded_to(r.flatness_min_zone * 1e3, *r.U * 1e3)
                            : std::string("not resolved"))
           : um_3f(r.flatness_min_zone)},
      {"uncertainty of the flatness",
       r.U ? fmt::format("U = {} µm (95 %): {}", trueaxis::detail::two_digits(*r.U * 1e3),
                         r.uncertainty_basis())
           : std::string("not stated: ") + r.no_uncertainty()}};
  if (!r.crossings.empty()) {
    s.table.push_back({"crossings", fmt::format("{}", r.crossings.size())});
    s.table.push_back({"closure RMS / max (µm)",
                       fmt::format("{} / {}", um_3f(r.closure_rms), um_3f(r.closure_max))});
  }
  if (r.method.rfind("moody", 0) == 0) {
    // The numeric Union Jack, as Moody's worksheet shows it: every line's heights, station by
    // station (µm).
    std::vector<std::vector<std::string>> t;
    std::size_t longest = 0;
    std::vector<std::vector<double>> per_line(r.lines.size());
    for (const auto& p : r.points) {
      auto& v = per_line[static_cast<std::size_t>(p.line)];
      if (v.size() <= static_cast<std::size_t>(p.station))
        v.resize(static_cast<std::size_t>(p.station) + 1, NAN);
      v[static_cast<std::size_t>(p.station)] = p.height * 1e3;
      longest = std::max(longest, v.size());
    }
    t.push_back({"line"});
    for (std::size_t k = 0; k < longest; ++k) t[0].push_back(fmt::format("station {}", k));
    for (std::size_t l = 0; l < r.lines.size(); ++l) {
      t.push_back({r.lines[l]});
      for (std::size_t k = 0; k < longest; ++k)
        t.back().push_back(k < per_line[l].size() && std::isfinite(per_line[l][k])
                               ? fmt::format("{:.2f}", per_line[l][k])
                               : "");
    }
    s.more_tables.emplace_back("Union Jack: heights along every line (µm)", std::move(t));
  }
  {
    // The 3-D view: every measured line at its height, in station order.
    SurfaceView view;
    view.title = "the surface in 3-D: every measured line at its height";
    view.value_label = "height (µm)";
    std::vector<std::vector<std::pair<int, Eigen::Vector3d>>> along(r.lines.size());
    for (const auto& p : r.points)
      along[static_cast<std::size_t>(p.line)].push_back(
          {p.station, Eigen::Vector3d(p.xy.x(), p.xy.y(), p.height * 1e3)});
    for (auto& l : along) {
      std::sort(l.begin(), l.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      if (l.size() < 2) continue;
      Eigen::Matrix3Xd m(3, static_cast<Eigen::Index>(l.size()));
      for (std::size_t k = 0; k < l.size(); ++k) m.col(static_cast<Eigen::Index>(k)) = l[k].second;
      view.lines.push_back(std::move(m));
    }
    if (!view.lines.empty()) s.views.push_back(std::move(view));
  }
  HeatMap h = xy_map("heights at every station (lines in grey)", "height (µm)", 620);
  const auto n = static_cast<Eigen::Index>(r.points.size());
  h.px.resize(n);
  h.py.resize(n);
  h.pvalue.resize(n);
  h.lines.resize(r.lines.size());
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto& p = r.points[static_cast<std::size_t>(k)];
    h.px[k] = p.xy.x();
    h.py[k] = p.xy.y();
    h.pvalue[k] = p.height * 1e3;
    h.lines[static_cast<std::size_t>(p.line)].push_back(k);
  }
  h.symmetric = h.pvalue.size() && h.pvalue.minCoeff() < 0;  // e.g. Moody's: lowest point 0
  if (r.grid) {
    h.title = "heights (cells: the lattice of stations)";
    h.grid_x = r.grid->x;
    h.grid_y = r.grid->y;
    h.grid_value = r.grid->height * 1e3;
  }
  add_contours(h, r);
  s.heat_maps.push_back(std::move(h));
  if (!r.crossings.empty() && r.closure_max > 0) {
    HeatMap c = xy_map("closure at every crossing (height on one line − on the other)",
                       "closure (µm)", 520);
    const auto m = static_cast<Eigen::Index>(r.crossings.size());
    c.px.resize(m);
    c.py.resize(m);
    c.pvalue.resize(m);
    // Crossings at one point (Moody's centre: four lines) are drawn on a small ring around it,
    // so that no marker hides another.
    double extent = 0;
    for (const auto& x : r.crossings) extent = std::max(extent, x.xy.cwiseAbs().maxCoeff());
    const double ring = 0.025 * std::max(extent, 1.0);
    bool spread = false;
    for (Eigen::Index k = 0; k < m; ++k) {
      const auto& x = r.crossings[static_cast<std::size_t>(k)];
      std::vector<Eigen::Index> same;
      for (Eigen::Index q = 0; q < m; ++q)
        if ((r.crossings[static_cast<std::size_t>(q)].xy - x.xy).norm() <= 1e-6 * ring)
          same.push_back(q);
      Eigen::Vector2d at = x.xy;
      if (same.size() > 1) {
        const auto pos = std::find(same.begin(), same.end(), k) - same.begin();
        const double a = 2 * M_PI * static_cast<double>(pos) / static_cast<double>(same.size());
        at += ring * Eigen::Vector2d(std::cos(a), std::sin(a));
        spread = true;
      }
      c.px[k] = at.x();
      c.py[k] = at.y();
      c.pvalue[k] = x.residual * 1e3;
    }
    if (spread) c.title += "; crossings at one point are drawn on a small ring around it";
    // Few crossings, each number matters (a closure of 0 would otherwise be a white dot).
    c.label_points = m <= 40;
    s.heat_maps.push_back(std::move(c));
  }
  return s;
}

Section space_section(const std::string& title, const surface::SpaceResult& sp,
                      const surface::Verification* v) {
  const map::ErrorMap& m = sp.map;
  const Eigen::Index nx = m.size(0), ny = m.size(1), nz = m.size(2);
  Section s;
  s.title = title;
  s.references = {refs::kIso230, refs::kIso230_2, refs::kThreePoint, refs::kGum};
  s.warnings = surface::space_warnings(sp, v);
  s.intro_html = fmt::format(
      "<p>Error vectors e = actual − nominal (µm) on a {} × {} × {} grid, from {} straightness "
      "runs and {} laser runs. Not determined by the campaign: {}; {}.</p>"
      "<p>An error space holds translations of the probe point only. Roll, pitch and yaw act "
      "on it through the probe offset and are contained in these vectors, but a map measured "
      "with one probe offset cannot separate them from straightness, so no angular curves are "
      "drawn. The parametric model fitted to ball-gauge placements ('trueaxis ballgauge "
      "--parametric model.json') reports them with ±2u bands.</p>",
      nx, ny, nz, sp.straightness_runs, sp.laser_runs, escape(joined(sp.unobservable)),
      escape(sp.gauge));
  s.table = {{"quantity", "value (µm)"},
             {"error space RMS / max |e|",
              fmt::format("{} / {}", um_3f(std::sqrt(m.error.colwise().squaredNorm().mean())),
                          um_3f(m.error.colwise().norm().maxCoeff()))},
             {"map − truth at the nodes, RMS / max",
              fmt::format("{} / {}", um_3f(sp.truth_rms), um_3f(sp.truth_max))}};
  if (m.uncertainty.cols())
    s.table.push_back({"standard uncertainty, RMS over nodes",
                       um_3f(std::sqrt(m.uncertainty.colwise().squaredNorm().mean()))});
  if (v) {
    s.table.push_back(
        {fmt::format("positioning error at {} random points, before: RMS / max", v->points),
         fmt::format("{} / {}", um_3f(v->before_rms), um_3f(v->before_max))});
    s.table.push_back({"after compensation: RMS / max",
                       fmt::format("{} / {}", um_3f(v->after_rms), um_3f(v->after_max))});
    if (v->uncertainty_known)
      s.table.push_back({"expected after: sqrt(interpolation² + uncertainty²)",
                         fmt::format("{} = {} ⊕ {}", um_3f(v->predicted_rms),
                                     um_3f(v->interpolation_rms), um_3f(v->uncertainty_rms))});
    else
      s.table.push_back(
          {"expected after: at least the interpolation error (uncertainty not "
           "computed)",
           fmt::format("≥ {}", um_3f(v->interpolation_rms))});
    s.table.push_back(
        {"improvement (RMS before / after)", fmt::format("×{:.1f}", v->improvement())});
  }

  // Per axis, the error vector along the grid line through the centre of the volume against
  // travel: the positioning error (the component along the axis) and the two straightness
  // components, with ±2u bands where the uncertainty was computed.
  {
    const char* names = "xyz";
    const Eigen::Index mid[3] = {nx / 2, ny / 2, nz / 2};
    for (int a = 0; a < 3; ++a) {
      Plot p;
      p.title = fmt::format(
          "along {} through the centre ({} = {:g}, {} = {:g} mm): positioning e{} and "
          "straightness e{}, e{}",
          names[a], names[(a + 1) % 3],
          m.axes[static_cast<std::size_t>((a + 1) % 3)][mid[(a + 1) % 3]], names[(a + 2) % 3],
          m.axes[static_cast<std::size_t>((a + 2) % 3)][mid[(a + 2) % 3]], names[a],
          names[(a + 1) % 3], names[(a + 2) % 3]);
      p.x_label = fmt::format("{} (mm)", names[a]);
      p.y_label = "error (µm)";
      p.x = m.axes[static_cast<std::size_t>(a)];
      const Eigen::Index n = m.size(a);
      for (int c : {a, (a + 1) % 3, (a + 2) % 3}) {
        Eigen::VectorXd y(n), band;
        if (m.uncertainty.cols()) band.resize(n);
        for (Eigen::Index i = 0; i < n; ++i) {
          Eigen::Index ijk[3] = {mid[0], mid[1], mid[2]};
          ijk[a] = i;
          const Eigen::Index node = m.index(ijk[0], ijk[1], ijk[2]);
          y[i] = m.error(c, node) * 1e3;
          if (band.size()) band[i] = m.uncertainty(c, node) * 1e3;
        }
        p.series.push_back({fmt::format("e{}", names[c]), y, band, component_colour(c), false});
      }
      s.plots.push_back(std::move(p));
    }
  }

  // Distorted grids of three planes through the volume.
  auto plane = [&](int a, int b, Eigen::Index at, const char* name) {
    s.grids.push_back(distorted_plane(m, a, b, at, name));
  };
  plane(0, 1, nz - 1, "XY plane");
  plane(0, 2, ny / 2, "XZ plane");
  plane(1, 2, nx / 2, "YZ plane");

  // The ez surfaces of up to six z levels, on one colour scale.
  const double lim = m.error.row(2).cwiseAbs().maxCoeff() * 1e3;
  const Eigen::Index shown = std::min<Eigen::Index>(nz, 6);
  for (Eigen::Index q = 0; q < shown; ++q) {
    const Eigen::Index k = shown > 1 ? q * (nz - 1) / (shown - 1) : 0;
    HeatMap h = xy_map(fmt::format("ez surface at z = {:g} mm", m.axes[2][k]), "ez (µm)", 340);
    h.grid_x = m.axes[0];
    h.grid_y = m.axes[1];
    h.grid_value.resize(ny, nx);
    for (Eigen::Index j = 0; j < ny; ++j)
      for (Eigen::Index i = 0; i < nx; ++i) h.grid_value(j, i) = m.error(2, m.index(i, j, k)) * 1e3;
    h.vmin = -lim;
    h.vmax = lim;
    s.heat_maps.push_back(std::move(h));
  }
  if (m.uncertainty.cols()) {
    HeatMap h = xy_map(fmt::format("standard uncertainty |u| at z = {:g} mm", m.axes[2][nz - 1]),
                       "|u| (µm)", 340);
    h.symmetric = false;
    h.grid_x = m.axes[0];
    h.grid_y = m.axes[1];
    h.grid_value.resize(ny, nx);
    for (Eigen::Index j = 0; j < ny; ++j)
      for (Eigen::Index i = 0; i < nx; ++i)
        h.grid_value(j, i) = m.uncertainty.col(m.index(i, j, nz - 1)).norm() * 1e3;
    s.heat_maps.push_back(std::move(h));
  }

  if (v && v->before.cols() > 0) {
    Plot p;
    p.title = "positioning error |e| at the random points, sorted: before and after compensation";
    p.x_label = "fraction of points (%)";
    p.y_label = "|e| (µm)";
    const Eigen::Index n = v->before.cols();
    p.x = Eigen::VectorXd::LinSpaced(n, 100.0 / static_cast<double>(n), 100.0);
    auto sorted = [](const Eigen::Matrix3Xd& r) {
      Eigen::VectorXd y = r.colwise().norm().transpose() * 1e3;
      std::sort(y.data(), y.data() + y.size());
      return y;
    };
    p.series.push_back({"before", sorted(v->before), {}, "#d62728", false});
    p.series.push_back({"after", sorted(v->after), {}, "#1f77b4", false});
    p.series.push_back(
        {v->uncertainty_known ? "expected RMS after" : "expected RMS after (interpolation only)",
         Eigen::VectorXd::Constant(n, v->predicted_rms * 1e3),
         {},
         "#2ca02c",
         true});
    p.log_y = true;
    s.plots.push_back(std::move(p));
  }
  return s;
}

}  // namespace trueaxis::report
