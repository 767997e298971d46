// Static SVG figures of the report: heat maps and distorted grids. Drawn at true aspect ratio in
// data units (mm), y up; every coloured element carries a <title> with its numbers (hover).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "trueaxis/error.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::report {
namespace {

using Rgb = std::array<double, 3>;

// ColorBrewer RdBu (reversed: blue low, red high) and viridis, linearly interpolated.
constexpr Rgb kDiverging[] = {{33, 102, 172},  {103, 169, 207}, {209, 229, 240}, {247, 247, 247},
                              {253, 219, 199}, {239, 138, 98},  {178, 24, 43}};
constexpr Rgb kSequential[] = {
    {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};

template <std::size_t N>
std::string ramp(const Rgb (&stops)[N], double t) {
  t = std::clamp(std::isfinite(t) ? t : 0.5, 0.0, 1.0) * static_cast<double>(N - 1);
  const std::size_t i = std::min(static_cast<std::size_t>(t), N - 2);
  const double f = t - static_cast<double>(i);
  auto c = [&](int k) {
    const auto ku = static_cast<std::size_t>(k);
    return static_cast<int>(std::lround(stops[i][ku] + f * (stops[i + 1][ku] - stops[i][ku])));
  };
  return fmt::format("#{:02x}{:02x}{:02x}", c(0), c(1), c(2));
}

// A colour scale: symmetric about zero (diverging) or min..max (sequential).
struct Scale {
  double lo = 0, hi = 1;
  bool diverging = true;
  Scale(double vmin, double vmax, bool symmetric) : diverging(symmetric) {
    if (!std::isfinite(vmin) || !std::isfinite(vmax)) vmin = vmax = 0;
    if (symmetric) {
      const double a = std::max(std::abs(vmin), std::abs(vmax));
      lo = -a;
      hi = a;
    } else {
      lo = vmin;
      hi = vmax;
    }
    if (!(hi > lo)) {
      lo -= 1;
      hi += 1;
    }
  }
  std::string operator()(double v) const {
    const double t = (v - lo) / (hi - lo);
    return diverging ? ramp(kDiverging, t) : ramp(kSequential, t);
  }
};

// "Nice" tick values covering [lo, hi].
std::vector<double> ticks(double lo, double hi, int target = 5) {
  std::vector<double> out;
  const double span = hi - lo;
  if (!(span > 0)) return {lo};
  const double raw = span / target, p = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / p, step = (r < 1.5 ? 1 : r < 3.5 ? 2 : r < 7.5 ? 5 : 10) * p;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * span; t += step)
    out.push_back(std::abs(t) < 1e-12 * span ? 0.0 : t);
  return out;
}

// Plot area in pixels for data extent [x0, x1] × [y0, y1], equal scale on both axes.
struct Frame {
  double x0, x1, y0, y1;
  double left = 62, top = 10, pw = 0, ph = 0, bar = 0;
  Frame(double ax0, double ax1, double ay0, double ay1, int width, double bar_space)
      : x0(ax0), x1(ax1), y0(ay0), y1(ay1), bar(bar_space) {
    if (!(x1 > x0)) x1 = x0 + 1;
    if (!(y1 > y0)) y1 = y0 + 1;
    pw = std::max(120.0, width - left - bar - 10);
    ph = pw * (y1 - y0) / (x1 - x0);
    if (ph > 420) {
      ph = 420;
      pw = ph * (x1 - x0) / (y1 - y0);
    }
    ph = std::max(ph, 60.0);
  }
  double X(double x) const { return left + (x - x0) / (x1 - x0) * pw; }
  double Y(double y) const { return top + (y1 - y) / (y1 - y0) * ph; }
  double width() const { return left + pw + bar + 10; }
  double height() const { return top + ph + 42; }
};

std::string open_svg(const Frame& f, const std::string& label) {
  return fmt::format(
      "<svg class=\"ta-fig\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" "
      "height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" role=\"img\" aria-label=\"{}\" "
      "font-family=\"system-ui,sans-serif\" font-size=\"11\">",
      f.width(), f.height(), f.width(), f.height(), escape(label));
}

std::string axes(const Frame& f, const std::string& xl, const std::string& yl) {
  std::string s = fmt::format(
      "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" "
      "stroke=\"#999\"/>",
      f.left, f.top, f.pw, f.ph);
  for (double t : ticks(f.x0, f.x1))
    s += fmt::format(
        "<line x1=\"{0:.1f}\" x2=\"{0:.1f}\" y1=\"{1:.1f}\" y2=\"{2:.1f}\" stroke=\"#999\"/>"
        "<text x=\"{0:.1f}\" y=\"{3:.1f}\" text-anchor=\"middle\">{4:g}</text>",
        f.X(t), f.top + f.ph, f.top + f.ph + 4, f.top + f.ph + 15, t);
  for (double t : ticks(f.y0, f.y1, std::max(2, static_cast<int>(f.ph / 60))))
    s += fmt::format(
        "<line x1=\"{0:.1f}\" x2=\"{1:.1f}\" y1=\"{2:.1f}\" y2=\"{2:.1f}\" stroke=\"#999\"/>"
        "<text x=\"{3:.1f}\" y=\"{4:.1f}\" text-anchor=\"end\">{5:g}</text>",
        f.left - 4, f.left, f.Y(t), f.left - 6, f.Y(t) + 4, t);
  s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>",
                   f.left + f.pw / 2, f.top + f.ph + 32, escape(xl));
  s += fmt::format(
      "<text transform=\"translate(14 {:.1f}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
      f.top + f.ph / 2, escape(yl));
  return s;
}

// A scale's end value in three significant digits, without an exponent a reader must decode
// ("2210", "-0.0123"); exponents only beyond 10⁶ or below 10⁻⁴.
std::string tick_text(double v) {
  const double a = std::abs(v);
  if (a == 0) return "0";
  if (a >= 1e6 || a < 1e-4) return fmt::format("{:.3g}", v);
  const int decimals = std::max(0, 2 - static_cast<int>(std::floor(std::log10(a))));
  return fmt::format("{:.{}f}", v, decimals);
}

// A vertical colour bar right of the plot area: 40 bands, end labels, zero if inside.
std::string colour_bar(const Frame& f, const Scale& sc, const std::string& label) {
  const double x = f.left + f.pw + 16, w = 12, n = 40;
  std::string s;
  for (int i = 0; i < n; ++i) {
    const double v = sc.hi - (sc.hi - sc.lo) * (i + 0.5) / n;
    s += fmt::format("<rect x=\"{:.1f}\" y=\"{:.2f}\" width=\"{}\" height=\"{:.2f}\" fill=\"{}\"/>",
                     x, f.top + f.ph * i / n, w, f.ph / n + 0.3, sc(v));
  }
  auto tick = [&](double v) {
    const double y = f.top + (sc.hi - v) / (sc.hi - sc.lo) * f.ph;
    return fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\">{}</text>", x + w + 3, y + 4, tick_text(v));
  };
  s += tick(sc.hi) + tick(sc.lo);
  if (sc.lo < 0 && sc.hi > 0) s += tick(0.0);
  s += fmt::format(
      "<text transform=\"translate({:.1f} {:.1f}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
      x + w + 52, f.top + f.ph / 2, escape(label));
  return s;
}

// Cell bounds of node i: half-way to the neighbours, the outer nodes' own coordinates at the edge.
// The vertices of a polyline (screen pixels) that a drawing at that resolution needs: those that
// move it by `tolerance` px or more (Douglas & Peucker 1973, "Algorithms for the reduction of the
// number of points required to represent a digitized line or its caricature", The Canadian
// Cartographer 10(2)), the ends always.
std::vector<Eigen::Index> screen_vertices(const Eigen::Matrix2Xd& px, double tolerance) {
  const Eigen::Index n = px.cols();
  std::vector<char> keep(static_cast<std::size_t>(n), 0);
  keep.front() = keep.back() = 1;
  std::vector<std::pair<Eigen::Index, Eigen::Index>> todo{{0, n - 1}};
  while (!todo.empty()) {
    const auto [a, b] = todo.back();
    todo.pop_back();
    if (b - a < 2) continue;
    const Eigen::Vector2d d = px.col(b) - px.col(a);
    const double len = d.norm();
    double worst = -1;
    Eigen::Index at = a;
    for (Eigen::Index k = a + 1; k < b; ++k) {
      const Eigen::Vector2d e = px.col(k) - px.col(a);
      const double dist = len > 0 ? std::abs(d.x() * e.y() - d.y() * e.x()) / len : e.norm();
      if (dist > worst) {
        worst = dist;
        at = k;
      }
    }
    if (worst < tolerance) continue;
    keep[static_cast<std::size_t>(at)] = 1;
    todo.emplace_back(a, at);
    todo.emplace_back(at, b);
  }
  std::vector<Eigen::Index> out;
  for (Eigen::Index k = 0; k < n; ++k)
    if (keep[static_cast<std::size_t>(k)]) out.push_back(k);
  return out;
}

// The points of a heat map that a drawing at screen resolution shows: per cell of `cell_px`
// pixels, the one whose value lies farthest from `mid` (the colour scale's centre), so that a
// dense run of dots keeps its extremes; in their original order.
std::vector<Eigen::Index> screen_points(const Eigen::VectorXd& X, const Eigen::VectorXd& Y,
                                        const Eigen::VectorXd& value, double mid, double cell_px) {
  std::map<std::pair<long, long>, Eigen::Index> best;
  for (Eigen::Index k = 0; k < X.size(); ++k) {
    const std::pair<long, long> key{std::lround(X[k] / cell_px), std::lround(Y[k] / cell_px)};
    const auto [it, fresh] = best.emplace(key, k);
    if (!fresh && std::abs(value[k] - mid) > std::abs(value[it->second] - mid)) it->second = k;
  }
  std::vector<Eigen::Index> out;
  out.reserve(best.size());
  for (const auto& kv : best) out.push_back(kv.second);
  std::sort(out.begin(), out.end());
  return out;
}

std::pair<double, double> cell(const Eigen::VectorXd& x, Eigen::Index i) {
  const Eigen::Index n = x.size();
  return {i > 0 ? 0.5 * (x[i - 1] + x[i]) : x[0], i + 1 < n ? 0.5 * (x[i] + x[i + 1]) : x[n - 1]};
}

}  // namespace

double nice_magnification(double max_error_um, double step_mm, double fraction) {
  if (!(max_error_um > 0) || !(step_mm > 0)) return 1;
  const double m = fraction * step_mm / (max_error_um * 1e-3);
  const double p = std::pow(10.0, std::floor(std::log10(m)));
  const double r = m / p;
  return (r >= 5 ? 5 : r >= 2 ? 2 : 1) * p;
}

std::string svg(const HeatMap& h) {
  const bool grid = h.grid_value.size() > 0;
  if (grid && (h.grid_value.rows() != h.grid_y.size() || h.grid_value.cols() != h.grid_x.size()))
    throw Error(fmt::format("heat map '{}': grid values must be len(y) x len(x)", h.title));
  if (h.px.size() != h.py.size() || h.px.size() != h.pvalue.size())
    throw Error(fmt::format("heat map '{}': point arrays differ in length", h.title));
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  double vmin = INFINITY, vmax = -INFINITY;
  auto take = [&](double x, double y, double v) {
    x0 = std::min(x0, x);
    x1 = std::max(x1, x);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
    if (std::isfinite(v)) {
      vmin = std::min(vmin, v);
      vmax = std::max(vmax, v);
    }
  };
  if (grid)
    for (Eigen::Index j = 0; j < h.grid_y.size(); ++j)
      for (Eigen::Index i = 0; i < h.grid_x.size(); ++i)
        take(h.grid_x[i], h.grid_y[j], h.grid_value(j, i));
  for (Eigen::Index k = 0; k < h.px.size(); ++k) take(h.px[k], h.py[k], h.pvalue[k]);
  if (!std::isfinite(x0)) throw Error(fmt::format("heat map '{}': no data", h.title));
  // Dots at the border need room: pad by 3 % of the larger extent.
  const double pad = h.px.size() ? 0.03 * std::max(x1 - x0, y1 - y0) : 0.0;
  const Frame f(x0 - pad, x1 + pad, y0 - pad, y1 + pad, h.width, 110);
  const Scale sc(std::isfinite(h.vmin) ? h.vmin : vmin, std::isfinite(h.vmax) ? h.vmax : vmax,
                 h.symmetric);
  std::string s = open_svg(f, h.title);
  if (grid && h.band_step > 0) {
    // Filled bands: each row's runs of cells in one band drawn as one rectangle, the rectangles
    // of one band as one path.
    std::map<long, std::string> paths;
    const auto band = [&](double v) {
      return std::isfinite(v) ? static_cast<long>(std::floor(v / h.band_step))
                              : std::numeric_limits<long>::min();
    };
    for (Eigen::Index j = 0; j < h.grid_y.size(); ++j) {
      const auto [ya, yb] = cell(h.grid_y, j);
      for (Eigen::Index i = 0; i < h.grid_x.size();) {
        const long b = band(h.grid_value(j, i));
        Eigen::Index e = i + 1;
        while (e < h.grid_x.size() && band(h.grid_value(j, e)) == b) ++e;
        const double xa = cell(h.grid_x, i).first, xb = cell(h.grid_x, e - 1).second;
        if (b != std::numeric_limits<long>::min())
          paths[b] += fmt::format("M{:.1f} {:.1f}h{:.1f}v{:.1f}h{:.1f}z", f.X(xa), f.Y(yb),
                                  f.X(xb) - f.X(xa) + 0.3, f.Y(ya) - f.Y(yb) + 0.3,
                                  -(f.X(xb) - f.X(xa) + 0.3));
        i = e;
      }
    }
    for (const auto& [b, d] : paths)
      s += fmt::format("<path fill=\"{}\" d=\"{}\"/>",
                       sc(std::clamp((static_cast<double>(b) + 0.5) * h.band_step, sc.lo, sc.hi)),
                       d);
  } else if (grid)
    for (Eigen::Index j = 0; j < h.grid_y.size(); ++j)
      for (Eigen::Index i = 0; i < h.grid_x.size(); ++i) {
        const auto [xa, xb] = cell(h.grid_x, i);
        const auto [ya, yb] = cell(h.grid_y, j);
        const double v = h.grid_value(j, i);
        s += fmt::format(
            "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" fill=\"{}\">"
            "<title>{:g}, {:g}: {:.4g}</title></rect>",
            f.X(xa), f.Y(yb), f.X(xb) - f.X(xa) + 0.3, f.Y(ya) - f.Y(yb) + 0.3,
            std::isfinite(v) ? sc(v) : "#ddd", h.grid_x[i], h.grid_y[j], v);
      }
  if (!h.contours.empty()) {
    std::string d;
    for (const auto& c : h.contours)
      for (Eigen::Index k = 0; k < c.cols(); ++k)
        d += fmt::format("{}{:.1f},{:.1f}", k ? "L" : "M", f.X(c(0, k)), f.Y(c(1, k)));
    s += "<path fill=\"none\" stroke=\"#222\" stroke-opacity=\"0.55\" stroke-width=\"0.8\" d=\"" +
         d + "\"/>";
  }
  // At screen resolution: each line through the vertices that bend it by 0.2 px or more, one
  // dot (9 px wide) per 3 px cell.
  for (const auto& line : h.lines) {
    std::vector<Eigen::Index> valid;
    for (Eigen::Index k : line)
      if (k >= 0 && k < h.px.size()) valid.push_back(k);
    if (valid.empty()) continue;
    Eigen::Matrix2Xd px(2, static_cast<Eigen::Index>(valid.size()));
    for (std::size_t i = 0; i < valid.size(); ++i)
      px.col(static_cast<Eigen::Index>(i)) << f.X(h.px[valid[i]]), f.Y(h.py[valid[i]]);
    std::string pts;
    for (const Eigen::Index i : screen_vertices(px, 0.2))
      pts += fmt::format("{:.1f},{:.1f} ", px(0, i), px(1, i));
    s += "<polyline fill=\"none\" stroke=\"#888\" stroke-width=\"1\" points=\"" + pts + "\"/>";
  }
  Eigen::VectorXd sx(h.px.size()), sy(h.px.size());
  for (Eigen::Index k = 0; k < h.px.size(); ++k) {
    sx[k] = f.X(h.px[k]);
    sy[k] = f.Y(h.py[k]);
  }
  s += "<g stroke=\"#333\" stroke-width=\"0.6\">";
  for (const Eigen::Index k : screen_points(sx, sy, h.pvalue, 0.5 * (sc.lo + sc.hi), 3.0))
    s += fmt::format(
        "<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"4.5\" fill=\"{}\"><title>{:g}, {:g}: {:.4g}"
        "</title></circle>",
        sx[k], sy[k], sc(h.pvalue[k]), h.px[k], h.py[k], h.pvalue[k]);
  s += "</g>";
  if (h.label_points) {
    s += "<g font-size=\"10\" fill=\"#222\">";
    for (Eigen::Index k = 0; k < h.px.size(); ++k)
      s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\">{:.3g}</text>", sx[k] + 6, sy[k] - 5,
                       std::abs(h.pvalue[k]) < 5e-4 ? 0.0 : h.pvalue[k]);
    s += "</g>";
  }
  s += axes(f, h.x_label, h.y_label) + colour_bar(f, sc, h.value_label) + "</svg>";
  return s;
}

std::string svg(const SurfaceView& v) {
  if (v.lines.empty()) throw Error(fmt::format("surface view '{}': no lines", v.title));
  double hmin = INFINITY, hmax = -INFINITY, x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY,
         y1 = -INFINITY;
  for (const auto& l : v.lines) {
    if (l.cols() < 2) throw Error(fmt::format("surface view '{}': a line of < 2 points", v.title));
    if (!l.allFinite()) throw Error(fmt::format("surface view '{}': non-finite value", v.title));
    x0 = std::min(x0, l.row(0).minCoeff());
    x1 = std::max(x1, l.row(0).maxCoeff());
    y0 = std::min(y0, l.row(1).minCoeff());
    y1 = std::max(y1, l.row(1).maxCoeff());
    hmin = std::min(hmin, l.row(2).minCoeff());
    hmax = std::max(hmax, l.row(2).maxCoeff());
  }
  // Isometric projection (x to the lower right, y to the upper right, height up), heights in µm
  // magnified into mm so that their span takes ~15 % of the plate's diagonal.
  const double size = std::hypot(x1 - x0, y1 - y0), span = std::max(hmax - hmin, 1e-9);
  const double mag = v.magnification > 0 ? v.magnification : nice_magnification(span, size, 0.15);
  const double c30 = std::cos(M_PI / 6), s30 = 0.5;
  auto U = [&](double x, double y) { return (x - x0) * c30 + (y - y0) * c30; };
  auto V = [&](double x, double y, double h) {
    return -(x - x0) * s30 + (y - y0) * s30 + (h - hmin) * 1e-3 * mag;
  };
  double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
  for (const auto& l : v.lines)
    for (Eigen::Index k = 0; k < l.cols(); ++k)
      for (double h : {hmin, l(2, k)}) {
        u0 = std::min(u0, U(l(0, k), l(1, k)));
        u1 = std::max(u1, U(l(0, k), l(1, k)));
        v0 = std::min(v0, V(l(0, k), l(1, k), h));
        v1 = std::max(v1, V(l(0, k), l(1, k), h));
      }
  const double pad = 0.04 * std::max(u1 - u0, v1 - v0);
  Frame f(u0 - pad, u1 + pad, v0 - pad, v1 + pad, v.width, 110);
  f.left = 10;
  const Scale sc(hmin, hmax, hmin < 0 && hmax > 0);
  std::string s = open_svg(f, v.title);
  for (const auto& l : v.lines) {  // the nominal plane: the lines at the lowest height
    std::string pts;
    for (Eigen::Index k = 0; k < l.cols(); ++k)
      pts +=
          fmt::format("{:.2f},{:.2f} ", f.X(U(l(0, k), l(1, k))), f.Y(V(l(0, k), l(1, k), hmin)));
    s += "<polyline fill=\"none\" stroke=\"#ccc\" stroke-width=\"1\" points=\"" + pts + "\"/>";
  }
  for (const auto& l : v.lines)
    for (Eigen::Index k = 0; k + 1 < l.cols(); ++k) {
      const double h = 0.5 * (l(2, k) + l(2, k + 1));
      s += fmt::format(
          "<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"{}\" "
          "stroke-width=\"2.2\" stroke-linecap=\"round\"><title>{:g}, {:g} mm: {:.4g}; "
          "{:g}, {:g} mm: {:.4g}</title></line>",
          f.X(U(l(0, k), l(1, k))), f.Y(V(l(0, k), l(1, k), l(2, k))),
          f.X(U(l(0, k + 1), l(1, k + 1))), f.Y(V(l(0, k + 1), l(1, k + 1), l(2, k + 1))), sc(h),
          l(0, k), l(1, k), l(2, k), l(0, k + 1), l(1, k + 1), l(2, k + 1));
    }
  // The plate's x and y directions at its corner, and the magnification.
  const double ax = 0.22 * std::min(x1 - x0 > 0 ? x1 - x0 : size, y1 - y0 > 0 ? y1 - y0 : size);
  auto arrow = [&](double x, double y, const char* name) {
    return fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#666\"/>"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" fill=\"#666\">{}</text>",
        f.X(U(x0, y0)), f.Y(V(x0, y0, hmin)), f.X(U(x, y)), f.Y(V(x, y, hmin)), f.X(U(x, y)) + 3,
        f.Y(V(x, y, hmin)) + 12, name);
  };
  s += arrow(x0 + ax, y0, v.x_name.c_str()) + arrow(x0, y0 + ax, v.y_name.c_str());
  s += colour_bar(f, sc, v.value_label);
  s += fmt::format(
      "<text x=\"{:.1f}\" y=\"{:.1f}\" fill=\"#444\">heights ×{:g} over {} "
      "(isometric view; grey: the lines at the lowest height)</text>",
      f.left, f.top + f.ph + 30, mag, escape(v.base));
  return s + "</svg>";
}

std::string svg(const DistortedGrid& g) {
  const Eigen::Index nu = g.u.size(), nv = g.v.size();
  if (nu < 2 || nv < 2) throw Error(fmt::format("grid '{}': needs >= 2 nodes per axis", g.title));
  for (const Eigen::MatrixXd* m : {&g.du, &g.dv, &g.normal})
    if (m->rows() != nv || m->cols() != nu)
      throw Error(fmt::format("grid '{}': values must be len(v) x len(u)", g.title));
  double step = INFINITY;
  for (const Eigen::VectorXd* a : {&g.u, &g.v})
    for (Eigen::Index i = 1; i < a->size(); ++i) step = std::min(step, (*a)[i] - (*a)[i - 1]);
  const double inplane = std::sqrt((g.du.array().square() + g.dv.array().square()).maxCoeff());
  const double mag = g.magnification > 0 ? g.magnification : nice_magnification(inplane, step);
  const double pad = 0.5 * step;
  const Frame f(g.u[0] - pad, g.u[nu - 1] + pad, g.v[0] - pad, g.v[nv - 1] + pad, g.width, 110);
  const Scale sc(std::isfinite(g.vmin) ? g.vmin : g.normal.minCoeff(),
                 std::isfinite(g.vmax) ? g.vmax : g.normal.maxCoeff(), true);
  std::string s = open_svg(f, g.title);
  for (Eigen::Index i = 0; i < nu; ++i)
    s += fmt::format(
        "<line x1=\"{0:.2f}\" x2=\"{0:.2f}\" y1=\"{1:.2f}\" y2=\"{2:.2f}\" stroke=\"#ccc\"/>",
        f.X(g.u[i]), f.Y(g.v[0]), f.Y(g.v[nv - 1]));
  for (Eigen::Index j = 0; j < nv; ++j)
    s += fmt::format(
        "<line x1=\"{0:.2f}\" x2=\"{1:.2f}\" y1=\"{2:.2f}\" y2=\"{2:.2f}\" stroke=\"#ccc\"/>",
        f.X(g.u[0]), f.X(g.u[nu - 1]), f.Y(g.v[j]));
  auto at = [&](Eigen::Index j, Eigen::Index i) {
    return fmt::format("{:.2f},{:.2f} ", f.X(g.u[i] + mag * g.du(j, i) * 1e-3),
                       f.Y(g.v[j] + mag * g.dv(j, i) * 1e-3));
  };
  for (Eigen::Index j = 0; j < nv; ++j) {
    std::string pts;
    for (Eigen::Index i = 0; i < nu; ++i) pts += at(j, i);
    s += "<polyline fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"1.3\" points=\"" + pts + "\"/>";
  }
  for (Eigen::Index i = 0; i < nu; ++i) {
    std::string pts;
    for (Eigen::Index j = 0; j < nv; ++j) pts += at(j, i);
    s += "<polyline fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"1.3\" points=\"" + pts + "\"/>";
  }
  s += "<g stroke=\"#333\" stroke-width=\"0.5\">";
  for (Eigen::Index j = 0; j < nv; ++j)
    for (Eigen::Index i = 0; i < nu; ++i) {
      const std::string p = at(j, i);
      const auto comma = p.find(',');
      s += fmt::format(
          "<circle cx=\"{}\" cy=\"{}\" r=\"3.5\" fill=\"{}\"><title>{:g}, {:g} mm: in-plane "
          "{:.3f}, {:.3f} µm; {} {:.3f}</title></circle>",
          p.substr(0, comma), p.substr(comma + 1, p.size() - comma - 2), sc(g.normal(j, i)), g.u[i],
          g.v[j], g.du(j, i), g.dv(j, i), escape(g.normal_label), g.normal(j, i));
    }
  s += "</g>";
  s += axes(f, g.u_label, g.v_label) + colour_bar(f, sc, g.normal_label);
  s += fmt::format(
      "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\" fill=\"#1f77b4\">in-plane errors "
      "×{:g}</text>",
      f.left + f.pw, f.top + f.ph + 32, mag);
  return s + "</svg>";
}

DistortedGrid distorted_plane(const map::ErrorMap& m, int a, int b, Eigen::Index at,
                              const std::string& name, double magnification) {
  if (a < 0 || a > 2 || b < 0 || b > 2 || a == b) throw Error("distorted plane: bad axes");
  const int c = 3 - a - b;
  if (at < 0 || at >= m.size(c)) throw Error("distorted plane: node index outside the grid");
  DistortedGrid g;
  const char* axis = "xyz";
  g.title =
      fmt::format("{} at {} = {:g} mm", name, axis[c], m.axes[static_cast<std::size_t>(c)][at]);
  g.u_label = fmt::format("{} (mm)", axis[a]);
  g.v_label = fmt::format("{} (mm)", axis[b]);
  g.normal_label = fmt::format("e{} (µm)", axis[c]);
  g.magnification = magnification;
  g.u = m.axes[static_cast<std::size_t>(a)];
  g.v = m.axes[static_cast<std::size_t>(b)];
  g.du.resize(g.v.size(), g.u.size());
  g.dv.resizeLike(g.du);
  g.normal.resizeLike(g.du);
  for (Eigen::Index j = 0; j < g.v.size(); ++j)
    for (Eigen::Index i = 0; i < g.u.size(); ++i) {
      Eigen::Index idx[3];
      idx[a] = i;
      idx[b] = j;
      idx[c] = at;
      const Eigen::Vector3d e = m.error.col(m.index(idx[0], idx[1], idx[2])) * 1e3;
      g.du(j, i) = e[a];
      g.dv(j, i) = e[b];
      g.normal(j, i) = e[c];
    }
  return g;
}

}  // namespace trueaxis::report

namespace trueaxis::report {

std::string svg(const PlaneView& v) {
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const auto& c : v.curves) {
    if (!c.xy.allFinite())
      throw Error(
          fmt::format("plane view '{}': curve '{}' has a non-finite value", v.title, c.label));
    if (c.xy.cols() == 0) continue;
    x0 = std::min(x0, c.xy.row(0).minCoeff());
    x1 = std::max(x1, c.xy.row(0).maxCoeff());
    y0 = std::min(y0, c.xy.row(1).minCoeff());
    y1 = std::max(y1, c.xy.row(1).maxCoeff());
  }
  if (!std::isfinite(x0)) throw Error(fmt::format("plane view '{}': no data", v.title));
  const double pad = 0.04 * std::max(x1 - x0, y1 - y0);
  const Frame f(x0 - pad, x1 + pad, y0 - pad, y1 + pad, v.width, 0);
  // Room for the legend under the axes: one line per curve with a label (a curve without one
  // belongs to the entry before it, as the second ring of a band).
  const double legend_top = f.height();
  const auto entries = std::count_if(v.curves.begin(), v.curves.end(),
                                     [](const PlaneView::Curve& c) { return !c.label.empty(); });
  const double height = legend_top + 16.0 * static_cast<double>(entries) + 4;
  std::size_t entry = 0;
  std::string s = fmt::format(
      "<svg class=\"ta-fig\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" "
      "height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" role=\"img\" aria-label=\"{}\" "
      "font-family=\"system-ui,sans-serif\" font-size=\"11\">",
      f.width(), height, f.width(), height, escape(v.title));
  s += axes(f, v.x_label, v.y_label);
  for (std::size_t i = 0; i < v.curves.size(); ++i) {
    const auto& c = v.curves[i];
    const std::string dash = c.dashed ? " stroke-dasharray=\"6 4\"" : "";
    // At screen resolution: a point is drawn once per pixel it lands on (a dot of 3.2 px, one
    // round-capped stroke of no length each), a curve through the vertices that bend it by
    // 0.2 px or more.
    Eigen::Matrix2Xd px(2, c.xy.cols());
    for (Eigen::Index k = 0; k < c.xy.cols(); ++k) px.col(k) << f.X(c.xy(0, k)), f.Y(c.xy(1, k));
    if (c.points) {
      std::string d;
      std::set<std::pair<long, long>> drawn;
      for (Eigen::Index k = 0; k < px.cols(); ++k)
        if (drawn.emplace(std::lround(px(0, k)), std::lround(px(1, k))).second)
          d += fmt::format("M{:.1f} {:.1f}h0", px(0, k), px(1, k));
      s += fmt::format(
          "<path stroke=\"{}\" stroke-width=\"3.2\" stroke-linecap=\"round\" d=\"{}\"><title>{}"
          "</title></path>",
          c.color, d, escape(c.label));
    } else if (c.xy.cols() > 1) {
      std::string pts;
      for (const Eigen::Index k : screen_vertices(px, 0.2))
        pts += fmt::format("{:.1f},{:.1f} ", px(0, k), px(1, k));
      s += fmt::format(
          "<{} fill=\"none\" stroke=\"{}\" stroke-width=\"1.4\"{} points=\"{}\"><title>{}</title>"
          "</{}>",
          c.closed ? "polygon" : "polyline", c.color, dash, pts, escape(c.label),
          c.closed ? "polygon" : "polyline");
    }
    if (c.label.empty()) continue;
    const double ly = legend_top + 16.0 * static_cast<double>(entry++) + 8;
    s += c.points ? fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3\" fill=\"{}\"/>",
                                f.left + 12, ly - 4, c.color)
                  : fmt::format(
                        "<line x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" "
                        "stroke=\"{}\" stroke-width=\"2\"{}/>",
                        f.left, f.left + 24, ly - 4, ly - 4, c.color, dash);
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\">{}</text>", f.left + 32, ly, escape(c.label));
  }
  return s + "</svg>";
}

}  // namespace trueaxis::report
