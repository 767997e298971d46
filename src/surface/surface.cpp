#include "trueaxis/surface/surface.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <random>
#include <set>

#include "../common/figures.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/flatness.hpp"

namespace trueaxis::surface {
namespace {

constexpr double kArcsec = 3.14159265358979323846 / 648000.0;  // rad

void validate(std::vector<Line>& lines) {
  if (lines.size() < 2)
    throw Error(fmt::format("surface: need at least 2 lines, got {}", lines.size()));
  std::set<std::string> names;
  for (Line& l : lines) {
    if (l.name.empty()) throw Error("surface: a line has no name");
    if (!names.insert(l.name).second)
      throw Error(fmt::format("surface: duplicated line name '{}'", l.name));
    if (!l.start.allFinite()) throw Error(fmt::format("line '{}': start must be finite", l.name));
    const double d = l.direction.norm();
    if (!std::isfinite(d) || d <= 0)
      throw Error(fmt::format("line '{}': direction must be a non-zero vector", l.name));
    l.direction /= d;
    if (!std::isfinite(l.spacing) || l.spacing <= 0)
      throw Error(fmt::format("line '{}': spacing must be positive, got {}", l.name, l.spacing));
    if (l.heights.size() < 2)
      throw Error(
          fmt::format("line '{}': needs at least 2 stations, got {}", l.name, l.heights.size()));
    if (!l.heights.allFinite())
      throw Error(fmt::format("line '{}': heights must be finite", l.name));
  }
}

// Height on line l at distance t (mm) from its start, linear between stations.
double height_at(const Line& l, const Eigen::VectorXd& h, double t) {
  const double s = t / l.spacing;
  const long n = h.size();
  long k = std::clamp(static_cast<long>(std::floor(s)), 0L, n - 2);
  const double f = s - static_cast<double>(k);
  return h[k] * (1 - f) + h[k + 1] * f;
}

std::vector<Crossing> find_crossings(const std::vector<Line>& lines, double tol) {
  std::vector<Crossing> out;
  for (int i = 0; i < static_cast<int>(lines.size()); ++i)
    for (int j = i + 1; j < static_cast<int>(lines.size()); ++j) {
      const Line &a = lines[static_cast<std::size_t>(i)], &b = lines[static_cast<std::size_t>(j)];
      Eigen::Matrix2d M;
      M << a.direction, -b.direction;
      if (std::abs(M.determinant()) < 1e-12) continue;  // parallel
      const Eigen::Vector2d t = M.fullPivLu().solve(b.start - a.start);
      if (t[0] < -tol || t[0] > a.length() + tol || t[1] < -tol || t[1] > b.length() + tol)
        continue;
      Crossing c;
      c.a = i;
      c.b = j;
      c.ta = std::clamp(t[0], 0.0, a.length());
      c.tb = std::clamp(t[1], 0.0, b.length());
      c.xy = a.start + a.direction * c.ta;
      out.push_back(c);
    }
  return out;
}

void require_connected(const std::vector<Line>& lines, const std::vector<Crossing>& cs,
                       double tol) {
  std::vector<int> parent(lines.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[static_cast<std::size_t>(x)] != x) x = parent[static_cast<std::size_t>(x)];
    return x;
  };
  for (const Crossing& c : cs) parent[static_cast<std::size_t>(find(c.a))] = find(c.b);
  std::vector<std::string> apart;
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (find(static_cast<int>(i)) != find(0)) apart.push_back(lines[i].name);
  if (!apart.empty()) {
    std::string s;
    for (const auto& n : apart) s += (s.empty() ? "'" : ", '") + n + "'";
    throw Error(fmt::format(
        "surface: lines {} do not cross the network of line '{}' (lines must cross, within {} "
        "mm, inside both lines' extents)",
        s, lines[0].name, tol));
  }
}

// Fits columns `basis` to z by least squares and returns the coefficients.
Eigen::VectorXd lsq_fit(const Eigen::MatrixXd& basis, const Eigen::VectorXd& z) {
  return basis.colPivHouseholderQr().solve(z);
}

// `figures`: also the flatness figures and the grid (a noise trial of state_uncertainty needs
// only the heights and the closure).
void finish(Result& r, const std::vector<Line>& lines, const std::vector<Eigen::VectorXd>& h,
            bool subtract_plane, bool figures = true) {
  r.lines.clear();
  for (const Line& l : lines) r.lines.push_back(l.name);
  r.points.clear();
  for (std::size_t i = 0; i < lines.size(); ++i)
    for (long k = 0; k < h[i].size(); ++k)
      r.points.push_back({static_cast<int>(i), k, lines[i].station(k), h[i][k]});
  const long m = static_cast<long>(r.points.size());
  Eigen::VectorXd x(m), y(m), z(m);
  for (long i = 0; i < m; ++i) {
    x[i] = r.points[static_cast<std::size_t>(i)].xy.x();
    y[i] = r.points[static_cast<std::size_t>(i)].xy.y();
    z[i] = r.points[static_cast<std::size_t>(i)].height;
  }
  const geometry::HeightPlane ls = geometry::ls_plane(x, y, z);
  if (subtract_plane) {
    for (auto& p : r.points) p.height -= ls(p.xy.x(), p.xy.y());
    r.reference = "least-squares plane of all points";
  }
  r.flatness_ls = ls.width;
  if (figures) r.flatness_min_zone = geometry::min_zone_plane(x, y, z).width;
  // Closure after assembly (the plane does not change differences at a crossing).
  double s2 = 0;
  r.closure_max = 0;
  for (Crossing& c : r.crossings) {
    const auto ia = static_cast<std::size_t>(c.a), ib = static_cast<std::size_t>(c.b);
    c.residual = height_at(lines[ia], h[ia], c.ta) - height_at(lines[ib], h[ib], c.tb);
    s2 += c.residual * c.residual;
    r.closure_max = std::max(r.closure_max, std::abs(c.residual));
  }
  r.closure_rms = r.crossings.empty() ? 0 : std::sqrt(s2 / static_cast<double>(r.crossings.size()));
  if (!figures) return;
  // Grid when the points cover a full lattice (coincident points averaged).
  auto key = [](double v) { return std::llround(v * 1e6); };  // nm
  std::map<long long, double> xs, ys;
  for (const auto& p : r.points) {
    xs[key(p.xy.x())] = p.xy.x();
    ys[key(p.xy.y())] = p.xy.y();
  }
  if (xs.size() >= 2 && ys.size() >= 2 && xs.size() * ys.size() <= r.points.size()) {
    std::map<long long, int> ix, iy;
    Grid g;
    g.x.resize(static_cast<Eigen::Index>(xs.size()));
    g.y.resize(static_cast<Eigen::Index>(ys.size()));
    int k = 0;
    for (const auto& [kk, v] : xs) g.x[ix[kk] = k++] = v;
    k = 0;
    for (const auto& [kk, v] : ys) g.y[iy[kk] = k++] = v;
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(g.y.size(), g.x.size());
    Eigen::MatrixXi cnt = Eigen::MatrixXi::Zero(g.y.size(), g.x.size());
    for (const auto& p : r.points) {
      const int a = iy[key(p.xy.y())], b = ix[key(p.xy.x())];
      sum(a, b) += p.height;
      ++cnt(a, b);
    }
    if ((cnt.array() > 0).all()) g.height = sum.array() / cnt.cast<double>().array(), r.grid = g;
  }
}

// The crossings' conditions on every line's offset a_i and tilt b_i (per `scale` mm): row k says
// a_a + b_a·ta − a_b − b_b·tb = −(height on a − height on b) at crossing k. Lengths are scaled to
// O(1) (the longest line) for the rank decision.
// The network's geometry, factorised once (heights do not enter): the noise trials of
// state_uncertainty reuse it.
struct CrossingSystem {
  std::vector<Crossing> crossings;
  double scale = 1;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
};
CrossingSystem crossing_system(const std::vector<Line>& lines, std::vector<Crossing> cs) {
  CrossingSystem S;
  const auto L = static_cast<Eigen::Index>(lines.size()), C = static_cast<Eigen::Index>(cs.size());
  for (const Line& l : lines) S.scale = std::max(S.scale, l.length());
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(C, 2 * L);
  for (Eigen::Index k = 0; k < C; ++k) {
    const Crossing& c = cs[static_cast<std::size_t>(k)];
    M(k, 2 * c.a) += 1;
    M(k, 2 * c.a + 1) += c.ta / S.scale;
    M(k, 2 * c.b) -= 1;
    M(k, 2 * c.b + 1) -= c.tb / S.scale;
  }
  S.cod.setThreshold(1e-10);
  S.cod.compute(M);
  S.crossings = std::move(cs);
  return S;
}
// The right-hand side: −(height on a − height on b) at every crossing.
Eigen::VectorXd crossing_rhs(const std::vector<Line>& lines, const std::vector<Crossing>& cs) {
  Eigen::VectorXd d(static_cast<Eigen::Index>(cs.size()));
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const Line &a = lines[static_cast<std::size_t>(cs[k].a)],
               &b = lines[static_cast<std::size_t>(cs[k].b)];
    d[static_cast<Eigen::Index>(k)] =
        -(height_at(a, a.heights, cs[k].ta) - height_at(b, b.heights, cs[k].tb));
  }
  return d;
}

// `system`: the network's factorisation when already known (a noise trial of the same lines).
Result build_lsq(const std::vector<Line>& lines, const Options& o, bool figures,
                 const CrossingSystem* system = nullptr) {
  Result r;
  r.method = "lsq";
  CrossingSystem own;
  if (!system) {
    auto cs = find_crossings(lines, o.crossing_tolerance);
    require_connected(lines, cs, o.crossing_tolerance);
    own = crossing_system(lines, std::move(cs));
    system = &own;
  }
  r.crossings = system->crossings;
  const int L = static_cast<int>(lines.size());
  const auto& cod = system->cod;
  const Eigen::VectorXd d = crossing_rhs(lines, r.crossings);
  const double scale = system->scale;
  const long nullity = 2L * L - cod.rank();
  r.redundancy = static_cast<int>(static_cast<long>(r.crossings.size()) - cod.rank());
  // Directions present (up to sign): with only two, the quadratic (n1·p)(n2·p) is linear along
  // every line and therefore invisible (the twist).
  std::vector<Eigen::Vector2d> dirs;
  for (const Line& l : lines) {
    bool seen = false;
    for (const auto& u : dirs)
      seen = seen || std::abs(u.x() * l.direction.y() - u.y() * l.direction.x()) < 1e-9;
    if (!seen) dirs.push_back(l.direction);
  }
  const bool twist_free = nullity == 4 && dirs.size() == 2;
  if (nullity != 3 && !twist_free)
    throw Error(fmt::format(
        "surface: the line network leaves {} mode(s) undetermined beyond the reference plane{}; "
        "add lines that cross the others in new directions (e.g. a diagonal)",
        nullity - 3, dirs.size() == 2 ? " and twist" : ""));
  const Eigen::VectorXd p = cod.solve(d);
  std::vector<Eigen::VectorXd> h(lines.size());
  for (int i = 0; i < L; ++i) {
    const Line& l = lines[static_cast<std::size_t>(i)];
    h[static_cast<std::size_t>(i)] = l.heights;
    for (long k = 0; k < l.heights.size(); ++k)
      h[static_cast<std::size_t>(i)][k] +=
          p[2 * i] + p[2 * i + 1] * static_cast<double>(k) * l.spacing / scale;
  }
  r.unobservable = {"plane"};
  r.gauge = "heights are residuals from the least-squares plane of all points";
  if (twist_free) {
    // Remove the twist component (LS fit of 1, x, y, q over all points, q the invisible quadratic).
    const Eigen::Vector2d n1(-dirs[0].y(), dirs[0].x()), n2(-dirs[1].y(), dirs[1].x());
    long m = 0;
    for (const auto& v : h) m += v.size();
    Eigen::MatrixXd B(m, 4);
    Eigen::VectorXd z(m);
    long row = 0;
    for (std::size_t i = 0; i < lines.size(); ++i)
      for (long k = 0; k < h[i].size(); ++k, ++row) {
        const Eigen::Vector2d q = lines[i].station(k) / scale;
        B.row(row) << 1, q.x(), q.y(), n1.dot(q) * n2.dot(q);
        z[row] = h[i][k];
      }
    const double c3 = lsq_fit(B, z)[3];
    for (std::size_t i = 0; i < lines.size(); ++i)
      for (long k = 0; k < h[i].size(); ++k) {
        const Eigen::Vector2d q = lines[i].station(k) / scale;
        h[i][k] -= c3 * n1.dot(q) * n2.dot(q);
      }
    r.unobservable.push_back("twist");
    r.gauge +=
        "; twist (unobservable: every line is parallel to one of two directions) fixed by taking "
        "the surface to have no twist component in the least-squares sense";
  }
  finish(r, lines, h, true, figures);
  return r;
}

bool parallel(const Eigen::Vector2d& u, const Eigen::Vector2d& axis) {
  return std::abs(u.x() * axis.y() - u.y() * axis.x()) < 1e-9;
}

Result build_seed(const std::vector<Line>& lines, const Options& o, bool figures) {
  Result r;
  r.method = "boundary";
  std::vector<int> xl, yl;
  for (int i = 0; i < static_cast<int>(lines.size()); ++i) {
    const Line& l = lines[static_cast<std::size_t>(i)];
    if (parallel(l.direction, Eigen::Vector2d::UnitX()))
      xl.push_back(i);
    else if (parallel(l.direction, Eigen::Vector2d::UnitY()))
      yl.push_back(i);
    else
      throw Error(fmt::format(
          "boundary method: line '{}' is neither along x nor along y; use --method lsq", l.name));
  }
  if (xl.empty() || yl.size() != 2)
    throw Error(
        fmt::format("boundary method: needs a family of x lines and exactly two boundary y lines "
                    "(got {} x lines "
                    "and {} y lines); use --method lsq for other layouts",
                    xl.size(), yl.size()));
  auto xrange = [&](int i) {
    const Line& l = lines[static_cast<std::size_t>(i)];
    const double x0 = l.start.x(), x1 = l.station(l.heights.size() - 1).x();
    return std::pair{std::min(x0, x1), std::max(x0, x1)};
  };
  const auto [xmin, xmax] = xrange(xl[0]);
  const double tol = std::max(o.crossing_tolerance, 1e-9 * (xmax - xmin));
  for (int i : xl) {
    const auto [a, b] = xrange(i);
    if (std::abs(a - xmin) > tol || std::abs(b - xmax) > tol)
      throw Error(
          fmt::format("boundary method: x line '{}' spans x = {}..{} mm but the family spans "
                      "{}..{} mm (every x "
                      "line must end on the two boundary lines)",
                      lines[static_cast<std::size_t>(i)].name, a, b, xmin, xmax));
  }
  int left = -1, right = -1;
  for (int j : yl) {
    const double x = lines[static_cast<std::size_t>(j)].start.x();
    if (std::abs(x - xmin) <= tol) left = j;
    if (std::abs(x - xmax) <= tol) right = j;
  }
  if (left < 0 || right < 0 || left == right)
    throw Error(
        fmt::format("boundary method: the two y lines must lie at the x family's end coordinates x "
                    "= {} and {} mm",
                    xmin, xmax));
  r.crossings = find_crossings(lines, tol);
  require_connected(lines, r.crossings, tol);
  if (figures)
    r.redundancy = static_cast<int>(static_cast<long>(r.crossings.size()) -
                                    crossing_system(lines, r.crossings).cod.rank());
  // Hang every x line on the boundary curves (their own heights, i.e. their own references).
  std::vector<Eigen::VectorXd> h(lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) h[i] = lines[i].heights;
  auto boundary_at = [&](int j, double y) {
    const Line& b = lines[static_cast<std::size_t>(j)];
    const double t = (y - b.start.y()) / b.direction.y();
    if (t < -tol || t > b.length() + tol)
      throw Error(
          fmt::format("boundary method: boundary line '{}' does not reach y = {} mm", b.name, y));
    return height_at(b, b.heights, std::clamp(t, 0.0, b.length()));
  };
  for (int i : xl) {
    const Line& l = lines[static_cast<std::size_t>(i)];
    const long n = l.heights.size();
    const Eigen::Vector2d p0 = l.start, p1 = l.station(n - 1);
    const double z0 = boundary_at(std::abs(p0.x() - xmin) <= tol ? left : right, p0.y());
    const double z1 = boundary_at(std::abs(p1.x() - xmin) <= tol ? left : right, p1.y());
    const double a = z0 - l.heights[0];
    const double b = (z1 - l.heights[n - 1] - a) / static_cast<double>(n - 1);
    for (long k = 0; k < n; ++k)
      h[static_cast<std::size_t>(i)][k] = l.heights[k] + a + b * static_cast<double>(k);
  }
  r.unobservable = {"plane", "twist"};
  r.gauge =
      "boundary construction: x lines hung on the two boundary y lines, whose own reference lines "
      "fix "
      "the twist; heights are residuals from the least-squares plane of all points";
  finish(r, lines, h, true, figures);
  return r;
}

}  // namespace

Eigen::VectorXd heights_from_slopes(const Eigen::VectorXd& slopes, double spacing) {
  Eigen::VectorXd h(slopes.size() + 1);
  h[0] = 0;
  for (Eigen::Index i = 0; i < slopes.size(); ++i) h[i + 1] = h[i] + slopes[i] * spacing;
  return h;
}

namespace {

// The options' and lines' checks (the lines normalised), before any assembly.
void check_network(std::vector<Line>& lines, const Options& o) {
  if (!(o.crossing_tolerance >= 0)) throw Error("surface: crossing_tolerance must be >= 0");
  validate(lines);
}

Result build_impl(std::vector<Line> lines, const Options& o, bool figures) {
  check_network(lines, o);
  return o.method == Method::Seed ? build_seed(lines, o, figures) : build_lsq(lines, o, figures);
}

constexpr int kTrials = 200;  // Monte Carlo trials: u_max to a few per cent

// States r.U (see Result::U): `trial(rng)` assembles the same network from readings that are
// independent standard normal noise (one unit of the input: mm of height, or an arc-second of
// slope) without the figures. The assembly is linear in the readings, so the closure a trial
// shows per unit of noise scales the data's closure to the noise level, and the trials' heights
// (about their least-squares plane) give every point's uncertainty. `display` converts the input
// unit to `unit` for Result::sigma.
void state_uncertainty(Result& r, const std::function<Result(std::mt19937_64&)>& trial,
                       double display, const std::string& unit) {
  const auto n = static_cast<Eigen::Index>(r.points.size());
  double size = 0, data2 = 0;
  for (const auto& p : r.points) size = std::max(size, std::abs(p.height));
  for (const auto& c : r.crossings) data2 += c.residual * c.residual;
  if (r.redundancy <= 0) {
    r.no_uncertainty_reason = fmt::format(
        "every one of the {} crossings is needed to assemble the lines, so no closure shows the "
        "readings' noise: the flatness carries no stated uncertainty (add a line that crosses "
        "the others)",
        r.crossings.size());
    return;
  }
  if (detail::is_round_off(r.closure_rms, size)) {
    r.no_uncertainty_reason =
        fmt::format("the lines agree at every crossing to round-off ({:.1e} µm RMS): {}",
                    r.closure_rms * 1e3, detail::noise_free_reason("the readings'"));
    return;
  }
  // The least-squares plane of the points, as a projection (heights about it are what the
  // flatness sees).
  Eigen::MatrixXd B(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    B.row(i) << 1, r.points[static_cast<std::size_t>(i)].xy.x(),
        r.points[static_cast<std::size_t>(i)].xy.y();
  const Eigen::Matrix3d N = B.transpose() * B;
  const Eigen::MatrixXd G = N.inverse() * B.transpose();
  std::mt19937_64 rng(1);
  Eigen::VectorXd sum2 = Eigen::VectorXd::Zero(n);
  double closure2 = 0;
  for (int k = 0; k < kTrials; ++k) {
    const Result t = trial(rng);
    if (static_cast<Eigen::Index>(t.points.size()) != n || t.crossings.size() != r.crossings.size())
      throw Error("surface: a noise trial assembled another network (internal error)");
    Eigen::VectorXd h(n);
    for (Eigen::Index i = 0; i < n; ++i) h[i] = t.points[static_cast<std::size_t>(i)].height;
    h -= B * (G * h);
    sum2 += h.cwiseAbs2();
    for (const auto& c : t.crossings) closure2 += c.residual * c.residual;
  }
  if (!(closure2 > 0)) {
    r.no_uncertainty_reason =
        "this assembly leaves no closure at the crossings, so none shows the readings' noise: the "
        "flatness carries no stated uncertainty (use --method lsq)";
    return;
  }
  const double sigma = std::sqrt(data2 / (closure2 / kTrials));  // input units
  r.u_max = sigma * std::sqrt(sum2.maxCoeff() / kTrials);
  r.U = detail::peak_to_valley_U(r.u_max, static_cast<long>(n));
  r.sigma = sigma * display;
  r.sigma_unit = unit;
  r.no_uncertainty_reason.clear();
}

Result moody_impl(const MoodyData& data, bool least_squares, bool figures);

}  // namespace

Result build(std::vector<Line> lines, const Options& o) {
  check_network(lines, o);
  // Least squares: the network is factorised once, and the noise trials reuse it (the costly
  // part at 10⁴ crossings); the boundary construction factorises nothing.
  std::optional<CrossingSystem> system;
  if (o.method == Method::Lsq) {
    auto cs = find_crossings(lines, o.crossing_tolerance);
    require_connected(lines, cs, o.crossing_tolerance);
    system = crossing_system(lines, std::move(cs));
  }
  Result r = system ? build_lsq(lines, o, true, &*system) : build_seed(lines, o, true);
  if (!o.uncertainty) {
    r.no_uncertainty_reason = "not asked for";
    return r;
  }
  std::normal_distribution<double> noise;
  state_uncertainty(
      r,
      [&](std::mt19937_64& rng) {
        for (Line& l : lines)
          for (auto& v : l.heights) v = noise(rng);
        return system ? build_lsq(lines, o, false, &*system) : build_seed(lines, o, false);
      },
      1e3, "um");
  return r;
}

Result moody(const MoodyData& data, bool least_squares) {
  Result r = moody_impl(data, least_squares, true);
  MoodyData trial = data;
  std::normal_distribution<double> noise;
  state_uncertainty(
      r,
      [&](std::mt19937_64& rng) {
        for (auto& [name, v] : trial.readings)
          for (auto& x : v) x = noise(rng);
        return moody_impl(trial, least_squares, false);
      },
      1.0, "arc-second");
  return r;
}

namespace {

Result moody_impl(const MoodyData& data, bool least_squares, bool figures) {
  const double d = data.foot_spacing;
  if (!(d > 0) || !std::isfinite(d)) throw Error("Moody: foot spacing must be positive");
  std::map<std::string, Eigen::VectorXd> r;
  for (const char* name : kMoodyLines) {
    const auto it = data.readings.find(name);
    if (it == data.readings.end()) throw Error(fmt::format("Moody: line '{}' is missing", name));
    if (it->second.size() < 2)
      throw Error(fmt::format("Moody: line '{}' needs at least 2 readings", name));
    if (!it->second.allFinite())
      throw Error(fmt::format("Moody: line '{}' has non-finite readings", name));
    r[name] = it->second;
  }
  auto n = [&](const char* name) { return static_cast<long>(r[name].size()); };
  const long nw = n("NE_NW"), nh = n("NE_SE");
  auto require_eq = [&](const char* a, long want, const char* why) {
    if (n(a) != want)
      throw Error(fmt::format("Moody: '{}' has {} readings but {} has {}", a, n(a), why, want));
  };
  require_eq("SE_SW", nw, "NE_NW (the opposite edge)");
  require_eq("E_W", nw, "NE_NW (the parallel edge)");
  require_eq("NW_SW", nh, "NE_SE (the opposite edge)");
  require_eq("N_S", nh, "NE_SE (the parallel edge)");
  require_eq("NE_SW", n("NW_SE"), "NW_SE (the other diagonal)");
  // An odd number of readings puts a line's middle between two stations: the worksheet's
  // middle heights (diagonals' zero, the edge midpoints the centre lines hang on, the centre
  // lines' closure) are then the mean of the two stations beside it (mid() below), the linear
  // interpolation at the middle, as the worksheet does for any line.
  // Geometry in station units of the edges; the diagonals' stations are evenly spaced between
  // corners.
  const Eigen::Vector2d NW(0, static_cast<double>(nh)),
      NE(static_cast<double>(nw), static_cast<double>(nh)), SE(static_cast<double>(nw), 0),
      SW(0, 0);
  const std::map<std::string, std::pair<Eigen::Vector2d, Eigen::Vector2d>> ends{
      {"NW_SE", {NW, SE}},
      {"NE_SW", {NE, SW}},
      {"NE_NW", {NE, NW}},
      {"SE_SW", {SE, SW}},
      {"E_W", {(NE + SE) / 2, (NW + SW) / 2}},
      {"NE_SE", {NE, SE}},
      {"NW_SW", {NW, SW}},
      {"N_S", {(NW + NE) / 2, (SW + SE) / 2}}};
  // Worksheet steps 1-2: S_j = sum_{i<=j} (r_i - r_1), in arc-second x station units.
  std::map<std::string, Eigen::VectorXd> S;
  for (const auto& [name, v] : r) {
    Eigen::VectorXd s(v.size() + 1);
    s[0] = 0;
    for (Eigen::Index j = 0; j < v.size(); ++j) s[j + 1] = s[j] + (v[j] - v[0]);
    S[name] = s;
  }
  auto mid = [](const Eigen::VectorXd& v) {
    const long m = v.size() - 1;  // n
    return m % 2 == 0 ? v[m / 2] : 0.5 * (v[m / 2] + v[m / 2 + 1]);
  };
  std::vector<Line> lines;
  for (const char* name : kMoodyLines) {
    Line l;
    l.name = name;
    const auto& [a, b] = ends.at(name);
    l.start = a * d;
    l.direction = (b - a).normalized();
    l.spacing = (b - a).norm() * d / static_cast<double>(r[name].size());
    lines.push_back(l);
  }
  if (least_squares) {
    for (Line& l : lines) l.heights = S[l.name] * (kArcsec * d);
    Result res = build_impl(lines, Options{}, figures);
    res.method = "moody-lsq";
    return res;
  }
  std::map<std::string, Eigen::VectorXd> H;
  // Step 3: diagonals, zero at the middle, equal ends.
  for (const char* name : {"NW_SE", "NE_SW"}) {
    const Eigen::VectorXd& s = S[name];
    const double m = static_cast<double>(s.size() - 1), sn = s[s.size() - 1];
    Eigen::VectorXd h(s.size());
    for (Eigen::Index j = 0; j < s.size(); ++j)
      h[j] = s[j] - (sn / m) * static_cast<double>(j) + (sn / 2 - mid(s));
    H[name] = h;
  }
  // Step 4-5: hang a line linearly between two heights.
  auto hang = [&](const char* name, double c0, double cend) {
    const Eigen::VectorXd& s = S[name];
    const double m = static_cast<double>(s.size() - 1), cn = cend - s[s.size() - 1];
    Eigen::VectorXd h(s.size());
    for (Eigen::Index j = 0; j < s.size(); ++j)
      h[j] = s[j] + c0 + (cn - c0) * static_cast<double>(j) / m;
    H[name] = h;
  };
  const double cNE = H["NE_SW"][0], cSW = H["NE_SW"][H["NE_SW"].size() - 1];
  const double cNW = H["NW_SE"][0], cSE = H["NW_SE"][H["NW_SE"].size() - 1];
  hang("NE_NW", cNE, cNW);
  hang("NE_SE", cNE, cSE);
  hang("SE_SW", cSE, cSW);
  hang("NW_SW", cNW, cSW);
  hang("E_W", mid(H["NE_SE"]), mid(H["NW_SW"]));
  hang("N_S", mid(H["NE_NW"]), mid(H["SE_SW"]));
  std::vector<std::string> closure;
  for (const char* name : {"E_W", "N_S"}) {
    const double c = mid(H[name]);
    closure.push_back(fmt::format("{} {:.3f} arc-second x foot", name, c));
    H[name].array() -= c;
  }
  // Step 6: lowest point zero, to length.
  double lo = 1e300;
  for (const auto& [name, h] : H) lo = std::min(lo, h.minCoeff());
  std::vector<Eigen::VectorXd> hs;
  for (Line& l : lines) {
    l.heights = (H[l.name].array() - lo) * (kArcsec * d);
    hs.push_back(l.heights);
  }
  Result res;
  res.method = "moody";
  res.crossings = find_crossings(lines, 1e-6 * d);
  if (figures)
    res.redundancy = static_cast<int>(static_cast<long>(res.crossings.size()) -
                                      crossing_system(lines, res.crossings).cod.rank());
  finish(res, lines, hs, false, figures);
  res.reference = "Moody's worksheet: the lowest point is zero";
  res.unobservable = {"plane"};
  res.gauge = fmt::format(
      "Moody 1955: diagonals zero at the centre with equal ends; perimeter hung on the diagonal "
      "corners; centre lines hung on the edge midpoints, then shifted by their closure ({})",
      fmt::join(closure, ", "));
  return res;
}

}  // namespace

std::string Result::uncertainty_basis() const {
  if (!U) return "";
  return fmt::format(
      "reading noise {} {} (one standard deviation, the same for every reading) from the closure "
      "at {} crossings ({} degrees of freedom), propagated to every point (largest u {} µm)",
      detail::two_digits(sigma), sigma_unit, crossings.size(), redundancy,
      detail::two_digits(u_max * 1e3));
}

std::string Result::summary() const {
  std::string s = fmt::format("surface ({}): {} lines, {} points, {} crossings\n", method,
                              lines.size(), points.size(), crossings.size());
  if (!U)
    s += fmt::format("  flatness: {:.4g} µm (LS plane), {:.4g} µm (min-zone); {}\n",
                     flatness_ls * 1e3, flatness_min_zone * 1e3, no_uncertainty());
  else if (*resolved())
    s += fmt::format("  flatness: {} µm (LS plane), {} µm (min-zone), U = {} µm (95 %)\n  U: {}\n",
                     detail::rounded_to(flatness_ls * 1e3, *U * 1e3),
                     detail::rounded_to(flatness_min_zone * 1e3, *U * 1e3),
                     detail::two_digits(*U * 1e3), uncertainty_basis());
  else
    s += fmt::format(
        "  flatness: not resolved (U = {} µm, 95 %, reaches the value): the readings' noise hides "
        "the form\n  U: {}\n",
        detail::two_digits(*U * 1e3), uncertainty_basis());
  s += fmt::format("  closure at crossings: RMS {:.4f} µm, max {:.4f} µm\n", closure_rms * 1e3,
                   closure_max * 1e3);
  s += fmt::format("  unobservable: {}\n  gauge: {}\n", fmt::join(unobservable, ", "), gauge);
  return s;
}

}  // namespace trueaxis::surface
