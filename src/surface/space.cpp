#include "trueaxis/surface/space.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <cmath>
#include <random>

#include "../common/eigen_instances.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/separation/separation.hpp"
#include "trueaxis/surface/surface.hpp"

namespace trueaxis::surface {
namespace {

constexpr const char* kAxis = "xyz";
// How the map's own uncertainty grows as the grid gets finer (U ∝ h^−kNoiseGrowth, see
// space_warnings), and the gain over this grid's predicted RMS a better spacing must promise
// before the grid is called too fine.
constexpr double kNoiseGrowth = 1.5;
constexpr double kClearGain = 0.8;

// Seeds for the individual runs of one campaign: reproducible and independent.
std::uint64_t run_seed(std::uint64_t seed, std::uint64_t counter) {
  std::seed_seq s{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                  static_cast<std::uint32_t>(counter), static_cast<std::uint32_t>(counter >> 32)};
  std::uint32_t w[2];
  s.generate(w, w + 2);
  return (static_cast<std::uint64_t>(w[0]) << 32) | w[1];
}

// Least-squares rigid-body motion t + ω × (p − centre) fitted to vectors v at points p, removed
// from v in place.
void remove_rigid(const Eigen::Matrix3Xd& p, Eigen::Matrix3Xd& v) {
  const Eigen::Index n = p.cols();
  const Eigen::Vector3d centre = p.rowwise().mean();
  Eigen::MatrixXd A(3 * n, 6);
  Eigen::VectorXd b(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d q = p.col(i) - centre;
    A.row(3 * i) << 1, 0, 0, 0, q.z(), -q.y();
    A.row(3 * i + 1) << 0, 1, 0, -q.z(), 0, q.x();
    A.row(3 * i + 2) << 0, 0, 1, q.y(), -q.x(), 0;
    b.segment<3>(3 * i) = v.col(i);
  }
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  const Eigen::VectorXd fit = A * x;
  for (Eigen::Index i = 0; i < n; ++i) v.col(i) -= fit.segment<3>(3 * i);
}

struct Campaign {
  const sim::Machine& m;
  const SpacePlan& plan;
  const std::array<Eigen::VectorXd, 3>& axes;
  std::array<Eigen::Index, 3> n{};  // nodes per axis
  std::array<double, 3> h{};        // grid step per axis (mm)
  std::uint64_t seed;
  std::uint64_t counter = 0;  // runs so far: each run's seed is derived from it
  // Outputs.
  std::vector<LevelSurface> surfaces;
  long straightness_runs = 0, laser_runs = 0;
  std::function<void()> tick;  // called after every level surface and at the end
  std::vector<std::string> unobservable;

  Campaign(const sim::Machine& machine, const SpacePlan& p,
           const std::array<Eigen::VectorXd, 3>& grid, std::uint64_t s)
      : m(machine), plan(p), axes(grid), seed(s) {
    for (std::size_t k = 0; k < 3; ++k) {
      n[k] = axes[k].size();
      h[k] = (axes[k][n[k] - 1] - axes[k][0]) / static_cast<double>(n[k] - 1);
    }
  }

  Eigen::Index node(Eigen::Index i, Eigen::Index j, Eigen::Index k) const {
    return i + n[0] * (j + n[1] * k);
  }
  Eigen::Index node(const std::array<Eigen::Index, 3>& ijk) const {
    return node(ijk[0], ijk[1], ijk[2]);
  }
  Eigen::Vector3d position(const std::array<Eigen::Index, 3>& ijk) const {
    return {axes[0][ijk[0]], axes[1][ijk[1]], axes[2][ijk[2]]};
  }

  // Heights (mm) along a straightness run: probe run + separation.
  Eigen::VectorXd straightness(const Eigen::Vector3d& start, const Eigen::Vector3d& dir, int c,
                               long stations, double step) {
    sim::ProbeRunOptions o;
    o.start = start;
    o.direction = dir;
    o.sensing = Eigen::Vector3d::Unit(c);
    o.stations = stations;
    o.step = step;
    o.noise = plan.probe_noise;
    o.profile_amplitude = plan.profile_amplitude;
    o.seed = run_seed(seed, counter++);
    separation::Options so;
    so.compute_uncertainty = false;
    if (plan.probes == ProbeMethod::TwoPoint) {
      o.offsets = {0, step};
      so.method = separation::Method::TwoPoint;
    } else {
      o.offsets = {0, step, 2 * step};
      so.method = separation::Method::ThreePoint;
    }
    const auto run = sim::simulate_probe_run(m, o);
    if (plan.probes == ProbeMethod::ThreePoint) {
      // The probes' zero difference is calibrated beforehand (reversal on a reference flat).
      const auto& po = run.truth.probe_offsets;
      so.zero_difference = po[0] - 2 * po[1] + po[2];
    }
    ++straightness_runs;
    const auto r = separation::separate(run.data, so);
    if (r.guide.value.size() != stations)
      throw Error("internal: separation returned a guide of unexpected length");
    return r.guide.value;
  }

  Eigen::VectorXd laser(const Eigen::Vector3d& start, const Eigen::Vector3d& dir, long stations,
                        double step) {
    ++laser_runs;
    return sim::simulate_laser_run(m, start, dir, stations, step, plan.laser_noise,
                                   run_seed(seed, counter++));
  }

  // Surface of component c on level k: heights (mm) into E(c, nodes of the level), about the
  // level's least-squares plane.
  void level_surface(int c, Eigen::Index k, Eigen::Matrix3Xd& E) {
    const int a = (c + 1) % 3, b = (c + 2) % 3;
    std::vector<Line> lines;
    struct Ref {
      int kind;  // 0: along a (index j of b), 1: along b (index i of a), 2: diagonal
      Eigen::Index index;
    };
    std::vector<Ref> refs;
    auto ijk = [&](Eigen::Index i, Eigen::Index j) {
      std::array<Eigen::Index, 3> r{};
      r[static_cast<std::size_t>(a)] = i;
      r[static_cast<std::size_t>(b)] = j;
      r[static_cast<std::size_t>(c)] = k;
      return r;
    };
    const Eigen::Vector3d ea = Eigen::Vector3d::Unit(a), eb = Eigen::Vector3d::Unit(b);
    for (Eigen::Index j = 0; j < n[b]; ++j) {
      Line l;
      l.name = fmt::format("{}-line {}={:g}", kAxis[a], kAxis[b], axes[b][j]);
      l.start = {axes[a][0], axes[b][j]};
      l.direction = {1, 0};
      l.spacing = h[a];
      l.heights = straightness(position(ijk(0, j)), ea, c, n[a], h[a]);
      lines.push_back(std::move(l));
      refs.push_back({0, j});
    }
    for (Eigen::Index i = 0; i < n[a]; ++i) {
      Line l;
      l.name = fmt::format("{}-line {}={:g}", kAxis[b], kAxis[a], axes[a][i]);
      l.start = {axes[a][i], axes[b][0]};
      l.direction = {0, 1};
      l.spacing = h[b];
      l.heights = straightness(position(ijk(i, 0)), eb, c, n[b], h[b]);
      lines.push_back(std::move(l));
      refs.push_back({1, i});
    }
    if (plan.diagonals) {
      const Eigen::Index md = std::min(n[a], n[b]);
      const double step = std::hypot(h[a], h[b]);
      Line l;
      l.name = fmt::format("{}{}-diagonal", kAxis[a], kAxis[b]);
      l.start = {axes[a][0], axes[b][0]};
      l.direction = Eigen::Vector2d(h[a], h[b]).normalized();
      l.spacing = step;
      l.heights =
          straightness(position(ijk(0, 0)), (h[a] * ea + h[b] * eb).normalized(), c, md, step);
      lines.push_back(std::move(l));
      refs.push_back({2, 0});
    }
    Options so;
    so.uncertainty = false;  // the level's heights only; the space states its own uncertainty
    const Result s = build(lines, so);
    surfaces.push_back({c, axes[c][k], s.closure_rms, s.flatness_ls});
    if (std::find(s.unobservable.begin(), s.unobservable.end(), "twist") != s.unobservable.end() &&
        std::find(unobservable.begin(), unobservable.end(), "twist of every level") ==
            unobservable.end())
      unobservable.push_back("twist of every level");
    // Node heights: the mean of every line's height at the node (they differ by the closure).
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n[a], n[b]), count = sum;
    for (const Point& p : s.points) {
      const Ref& r = refs[static_cast<std::size_t>(p.line)];
      const Eigen::Index i = r.kind == 1 ? r.index : p.station;
      const Eigen::Index j = r.kind == 0 ? r.index : p.station;
      sum(i, j) += p.height;
      count(i, j) += 1;
    }
    for (Eigen::Index i = 0; i < n[a]; ++i)
      for (Eigen::Index j = 0; j < n[b]; ++j) E(c, node(ijk(i, j))) = sum(i, j) / count(i, j);
  }

  // Planes of the levels of component c relative to its first level, from positioning runs
  // along c at the four corner columns; added to E.
  void stack(int c, Eigen::Matrix3Xd& E) {
    const int a = (c + 1) % 3, b = (c + 2) % 3;
    const Eigen::Index L = n[c];
    const double am = 0.5 * (axes[a][0] + axes[a][n[a] - 1]),
                 as = 0.5 * (axes[a][n[a] - 1] - axes[a][0]);
    const double bm = 0.5 * (axes[b][0] + axes[b][n[b] - 1]),
                 bs = 0.5 * (axes[b][n[b] - 1] - axes[b][0]);
    const Eigen::Index cols[4][2] = {{0, 0}, {n[a] - 1, 0}, {0, n[b] - 1}, {n[a] - 1, n[b] - 1}};
    // Unknowns: (α, β, γ) of levels 1..L−1, then one offset per column.
    const Eigen::Index U = 3 * (L - 1) + 4;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4 * L, U);
    Eigen::VectorXd rhs(4 * L);
    for (int col = 0; col < 4; ++col) {
      std::array<Eigen::Index, 3> ijk{};
      ijk[static_cast<std::size_t>(a)] = cols[col][0];
      ijk[static_cast<std::size_t>(b)] = cols[col][1];
      ijk[static_cast<std::size_t>(c)] = 0;
      const Eigen::VectorXd r = laser(position(ijk), Eigen::Vector3d::Unit(c), L, h[c]);
      const double u = (axes[a][cols[col][0]] - am) / as, v = (axes[b][cols[col][1]] - bm) / bs;
      for (Eigen::Index k = 0; k < L; ++k) {
        ijk[static_cast<std::size_t>(c)] = k;
        const Eigen::Index row = 4 * k + col;
        if (k > 0) A.block(row, 3 * (k - 1), 1, 3) << 1, u, v;
        A(row, 3 * (L - 1) + col) = 1;
        rhs[row] = r[k] - E(c, node(ijk));
      }
    }
    const Eigen::VectorXd x = A.colPivHouseholderQr().solve(rhs);
    for (Eigen::Index k = 1; k < L; ++k)
      for (Eigen::Index i = 0; i < n[a]; ++i)
        for (Eigen::Index j = 0; j < n[b]; ++j) {
          std::array<Eigen::Index, 3> ijk{};
          ijk[static_cast<std::size_t>(a)] = i;
          ijk[static_cast<std::size_t>(b)] = j;
          ijk[static_cast<std::size_t>(c)] = k;
          const double u = (axes[a][i] - am) / as, v = (axes[b][j] - bm) / bs;
          E(c, node(ijk)) += x[3 * (k - 1)] + x[3 * (k - 1) + 1] * u + x[3 * (k - 1) + 2] * v;
        }
  }

  // One plane per component (q0 + q1·a + q2·b), from laser runs along the three face diagonals:
  // fixes the squareness errors (the rest of those planes is a rigid-body motion).
  void squareness(Eigen::Matrix3Xd& E) {
    // Unknowns: 3 planes × 3, then 3 run offsets. Solved with minimum norm (the rigid-body
    // motions are its null space and are removed afterwards anyway).
    std::vector<Eigen::RowVectorXd> rows;
    std::vector<double> rhs;
    auto plane_terms = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& d,
                           Eigen::RowVectorXd& row) {
      for (int c = 0; c < 3; ++c) {
        const int a = (c + 1) % 3, b = (c + 2) % 3;
        row[3 * c] = d[c];
        row[3 * c + 1] = d[c] * p[a] * 1e-3;  // per metre, for conditioning
        row[3 * c + 2] = d[c] * p[b] * 1e-3;
      }
    };
    for (int face = 0; face < 3; ++face) {
      const int p = (face + 1) % 3, q = (face + 2) % 3, mid = face;  // face ⟂ axis `face`
      const Eigen::Index md = std::min(n[p], n[q]);
      const Eigen::Vector3d d =
          (h[p] * Eigen::Vector3d::Unit(p) + h[q] * Eigen::Vector3d::Unit(q)).normalized();
      std::array<Eigen::Index, 3> ijk{};
      ijk[static_cast<std::size_t>(mid)] = n[mid] / 2;
      const Eigen::VectorXd r = laser(position(ijk), d, md, std::hypot(h[p], h[q]));
      for (Eigen::Index m = 0; m < md; ++m) {
        ijk[static_cast<std::size_t>(p)] = m;
        ijk[static_cast<std::size_t>(q)] = m;
        Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(12);
        plane_terms(position(ijk), d, row);
        row[9 + face] = 1;
        rows.push_back(row);
        rhs.push_back(r[m] - d.dot(E.col(node(ijk))));
      }
    }
    Eigen::MatrixXd A(static_cast<Eigen::Index>(rows.size()), 12);
    Eigen::VectorXd b(static_cast<Eigen::Index>(rows.size()));
    for (std::size_t i = 0; i < rows.size(); ++i) {
      A.row(static_cast<Eigen::Index>(i)) = rows[i];
      b[static_cast<Eigen::Index>(i)] = rhs[i];
    }
    const Eigen::VectorXd x = A.completeOrthogonalDecomposition().solve(b);
    for (Eigen::Index nd = 0; nd < E.cols(); ++nd) {
      const Eigen::Vector3d p(axes[0][nd % n[0]], axes[1][(nd / n[0]) % n[1]],
                              axes[2][nd / (n[0] * n[1])]);
      for (int c = 0; c < 3; ++c) {
        const int a = (c + 1) % 3, bb = (c + 2) % 3;
        E(c, nd) += x[3 * c] + x[3 * c + 1] * p[a] * 1e-3 + x[3 * c + 2] * p[bb] * 1e-3;
      }
    }
  }

  Eigen::Matrix3Xd run() {
    Eigen::Matrix3Xd E = Eigen::Matrix3Xd::Zero(3, n[0] * n[1] * n[2]);
    for (int c = 0; c < 3; ++c) {
      for (Eigen::Index k = 0; k < n[c]; ++k) {
        level_surface(c, k, E);
        if (tick) tick();
      }
      stack(c, E);
    }
    if (plan.diagonals)
      squareness(E);
    else
      unobservable.push_back("squareness xy, xz, yz");
    if (tick) tick();
    return E;
  }
};

}  // namespace

void SpacePlan::validate() const {
  if (!(spacing > 0 && std::isfinite(spacing))) throw Error("the grid spacing must be positive");
  for (double v : {probe_noise, laser_noise, profile_amplitude})
    if (!(v >= 0 && std::isfinite(v))) throw Error("noise and amplitudes must be >= 0");
  if (monte_carlo < 0 || monte_carlo == 1)
    throw Error("monte_carlo must be 0 (no uncertainty) or at least 2 repetitions");
}

std::array<Eigen::VectorXd, 3> space_axes(const sim::Machine& m, const SpacePlan& plan) {
  plan.validate();
  std::array<Eigen::VectorXd, 3> axes;
  for (int k = 0; k < 3; ++k) {
    const auto& r = m.range[static_cast<std::size_t>(k)];
    const double want = std::ceil((r[1] - r[0]) / plan.spacing - 1e-9);
    if (!(want < static_cast<double>(kMaxGridNodes)))
      throw Error(
          fmt::format("spacing {:g} mm gives more than {} nodes along {}; a campaign "
                      "measures at most {} nodes: choose a larger spacing",
                      plan.spacing, kMaxGridNodes, kAxis[k], kMaxGridNodes));
    // `spacing` is the largest step; a three-point run needs at least 4 stations on a line.
    const Eigen::Index fewest = plan.probes == ProbeMethod::ThreePoint ? 3 : 2;
    const auto steps = std::max<Eigen::Index>(fewest, static_cast<Eigen::Index>(want));
    axes[static_cast<std::size_t>(k)] = Eigen::VectorXd::LinSpaced(steps + 1, r[0], r[1]);
  }
  const Eigen::Index nodes = axes[0].size() * axes[1].size() * axes[2].size();
  if (nodes > kMaxGridNodes)
    throw Error(fmt::format(
        "spacing {:g} mm gives a {} x {} x {} grid ({} nodes); a campaign measures at most {} "
        "nodes: choose a larger spacing",
        plan.spacing, axes[0].size(), axes[1].size(), axes[2].size(), nodes, kMaxGridNodes));
  return axes;
}

void remove_rigid_motion(map::ErrorMap& map) {
  Eigen::Matrix3Xd p(3, map.nodes());
  for (Eigen::Index i = 0; i < map.nodes(); ++i) p.col(i) = map.node(i);
  remove_rigid(p, map.error);
}

SpaceResult measure_space(const sim::Machine& machine, const SpacePlan& plan,
                          const std::function<void(double)>& progress) {
  machine.validate();
  const auto axes = space_axes(machine, plan);
  SpaceResult out;
  out.map.axes = axes;
  // Progress: one tick per level surface (and one per campaign's end), over every campaign.
  const double ticks = static_cast<double>((axes[0].size() + axes[1].size() + axes[2].size() + 1) *
                                           (1 + (plan.monte_carlo >= 2 ? plan.monte_carlo : 0)));
  double done = 0;
  const std::function<void()> tick = [&] {
    if (progress) progress(std::min(1.0, ++done / ticks));
  };
  Campaign c0(machine, plan, axes, plan.seed);
  c0.tick = tick;
  out.map.error = c0.run();
  remove_rigid_motion(out.map);
  out.surfaces = c0.surfaces;
  out.straightness_runs = c0.straightness_runs;
  out.laser_runs = c0.laser_runs;
  out.unobservable = c0.unobservable;
  out.unobservable.insert(out.unobservable.begin(), "rigid-body motion (6)");
  out.gauge =
      "the least-squares rigid-body motion (translation and rotation) of the whole field is zero";
  if (std::find(out.unobservable.begin(), out.unobservable.end(), "twist of every level") !=
      out.unobservable.end())
    out.gauge += "; every level's twist is zero in the least-squares sense";
  if (!plan.diagonals) out.gauge += "; no squareness error in the least-squares sense";

  if (plan.monte_carlo >= 2) {
    // Repetitions with independent noise (and straightedges): the scatter is the uncertainty.
    Eigen::Matrix3Xd mean = Eigen::Matrix3Xd::Zero(3, out.map.nodes()), m2 = mean;
    for (int r = 0; r < plan.monte_carlo; ++r) {
      map::ErrorMap rep;
      rep.axes = axes;
      Campaign c(machine, plan, axes,
                 run_seed(plan.seed, 1'000'000 + static_cast<std::uint64_t>(r)));
      c.tick = tick;
      rep.error = c.run();
      remove_rigid_motion(rep);
      const Eigen::Matrix3Xd d = rep.error - mean;
      mean += d / static_cast<double>(r + 1);
      m2 += d.cwiseProduct(rep.error - mean);
    }
    out.map.uncertainty = (m2 / static_cast<double>(plan.monte_carlo - 1)).cwiseSqrt();
  }

  map::ErrorMap truth =
      map::sample(axes, [&](const Eigen::Vector3d& p) { return machine.error(p); });
  remove_rigid_motion(truth);
  const Eigen::Matrix3Xd diff = out.map.error - truth.error;
  out.truth_rms = std::sqrt(diff.colwise().squaredNorm().mean());
  out.truth_max = diff.colwise().norm().maxCoeff();
  return out;
}

std::string SpaceResult::summary() const {
  std::string s = fmt::format(
      "error space on a {} x {} x {} grid ({} straightness runs, {} laser runs, {} surfaces)\n",
      map.size(0), map.size(1), map.size(2), straightness_runs, laser_runs, surfaces.size());
  double worst_closure = 0;
  for (const auto& l : surfaces) worst_closure = std::max(worst_closure, l.closure_rms);
  s += fmt::format("  worst surface closure RMS: {:.4f} µm\n", worst_closure * 1e3);
  const Eigen::VectorXd norms = map.error.colwise().norm();
  s += fmt::format("  error vectors: max {:.3f} µm, RMS {:.3f} µm\n", norms.maxCoeff() * 1e3,
                   std::sqrt(norms.squaredNorm() / static_cast<double>(norms.size())) * 1e3);
  if (map.uncertainty.size() != 0)
    s += fmt::format("  standard uncertainty: max {:.3f} µm per component\n",
                     map.uncertainty.maxCoeff() * 1e3);
  else
    s += "  standard uncertainty: not computed (set monte_carlo in the plan)\n";
  s += fmt::format("  against the virtual machine's truth: RMS {:.4f} µm, max {:.4f} µm\n",
                   truth_rms * 1e3, truth_max * 1e3);
  std::string u;
  for (const auto& x : unobservable) u += (u.empty() ? "" : ", ") + x;
  s += "  unobservable: " + u + "\n  gauge: " + gauge + "\n";
  return s;
}

std::vector<std::string> space_warnings(const SpaceResult& space, const Verification* v) {
  std::vector<std::string> w;
  if (v && v->after_rms > v->before_rms)
    w.push_back(fmt::format(
        "compensating with this map makes the machine worse (RMS {:.3f} µm before, {:.3f} µm "
        "after): do not use it",
        v->before_rms * 1e3, v->after_rms * 1e3));
  if (space.map.uncertainty.size() == 0) {
    w.push_back(
        "the map's uncertainty was not computed (monte_carlo is 0 in the plan): its noise, and "
        "whether this grid is finer than the campaign supports, cannot be judged; set "
        "monte_carlo to 20 or more");
    return w;
  }
  // Finer grids interpolate better but make longer three-point runs, whose noise grows with
  // their length; past the balance the map gets worse. Model of the predicted RMS at k times this
  // spacing h: interpolation I·k² (linear interpolation of a smooth error: O(h²)), the map's own
  // uncertainty U·k^(−3/2) (each separated profile value is a double sum of reading noise over up
  // to L/h stations, so its standard deviation grows as (L/h)^(3/2)). Its minimum is at
  // k⁴⁺²ᵃ = a·U²/(2·I²), a = 3/2. Warn when that spacing is larger and predicts a clearly
  // better map; near the balance the prediction is flat and the grid is a fair choice.
  if (v && v->interpolation_rms > 0 && v->uncertainty_rms > 0) {
    const double I = v->interpolation_rms, U = v->uncertainty_rms, a = kNoiseGrowth;
    const double k = std::pow(a * U * U / (2 * I * I), 1 / (4 + 2 * a));
    const double best = std::sqrt(I * I * std::pow(k, 4) + U * U * std::pow(k, -2 * a));
    const double now = std::hypot(I, U);
    if (k > 1 && best < kClearGain * now) {
      const Eigen::VectorXd& x = space.map.axes[0];
      const double h =
          x.size() > 1 ? (x[x.size() - 1] - x[0]) / static_cast<double>(x.size() - 1) : 0.0;
      w.push_back(fmt::format(
          "the grid is finer than this campaign supports: the map's own uncertainty (RMS {:.3f} "
          "µm) outweighs what interpolation on this grid costs ({:.3f} µm); a spacing about "
          "{:.1f} times larger{} would predict a compensated RMS of about {:.2f} µm instead of "
          "{:.2f} µm",
          U * 1e3, I * 1e3, k, h > 0 ? fmt::format(" (about {:.0f} mm)", k * h) : std::string(),
          best * 1e3, now * 1e3));
    }
  }
  return w;
}

Verification verify_compensation(const sim::Machine& machine, const map::ErrorMap& space,
                                 long points, std::uint64_t seed,
                                 const map::CompensateOptions& options) {
  if (points < 10) throw Error("the verification needs at least 10 points");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Eigen::Matrix3Xd c(3, points);
  for (Eigen::Index i = 0; i < points; ++i)
    for (int a = 0; a < 3; ++a) {
      const auto& x = space.axes[static_cast<std::size_t>(a)];
      c(a, i) = x[0] + (x[x.size() - 1] - x[0]) * U(rng);
    }
  auto residual = [&](const Eigen::Matrix3Xd& commands) {
    Eigen::Matrix3Xd r(3, points);
    for (Eigen::Index i = 0; i < points; ++i)
      r.col(i) = machine.actual(commands.col(i)) - machine.offset - c.col(i);
    remove_rigid(c, r);
    return r;
  };
  auto rms = [](const Eigen::Matrix3Xd& r) { return std::sqrt(r.colwise().squaredNorm().mean()); };
  Verification v;
  v.points = points;
  const Eigen::Matrix3Xd before = residual(c);
  Eigen::Matrix3Xd cp = c;
  map::compensate(space, cp, options);
  const Eigen::Matrix3Xd after = residual(cp);
  v.commands = c;
  v.before = before;
  v.after = after;
  v.before_rms = rms(before);
  v.before_max = before.colwise().norm().maxCoeff();
  v.after_rms = rms(after);
  v.after_max = after.colwise().norm().maxCoeff();
  // The same grid filled with the truth: what interpolation alone leaves.
  const map::ErrorMap truth =
      map::sample(space.axes, [&](const Eigen::Vector3d& p) { return machine.error(p); });
  Eigen::Matrix3Xd ct = c;
  map::compensate(truth, ct, options);
  v.interpolation_rms = rms(residual(ct));
  v.uncertainty_known = space.uncertainty.size() != 0;
  if (v.uncertainty_known) {
    map::ErrorMap u;
    u.axes = space.axes;
    u.error = space.uncertainty.cwiseProduct(space.uncertainty);  // interpolate variances
    const Eigen::Matrix3Xd var = map::evaluate(u, c);
    v.uncertainty_rms = std::sqrt(var.colwise().sum().mean());
  }
  v.predicted_rms = std::hypot(v.interpolation_rms, v.uncertainty_rms);
  return v;
}

}  // namespace trueaxis::surface
