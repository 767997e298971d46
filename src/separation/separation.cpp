#include "trueaxis/separation/separation.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <span>
#include <tuple>

#include "../common/eigen_instances.hpp"
#include "../common/memory.hpp"
#include "../geometry/profile_min_zone.hpp"
#include "banded_lsq.hpp"
#include "design.hpp"
#include "prefault.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/straightness.hpp"

namespace trueaxis::separation {
namespace {

constexpr double kStepTolerance = 1e-6;  // relative tolerance for equal steps / whole multiples

}  // namespace

const char* to_string(Method m) {
  switch (m) {
    case Method::TwoPoint:
      return "two-point";
    case Method::ThreePoint:
      return "three-point";
    case Method::Lsq:
      return "lsq";
  }
  return "?";
}

const char* to_string(Reference r) {
  switch (r) {
    case Reference::LeastSquares:
      return "ls";
    case Reference::Seed:
      return "patent";
    case Reference::MinZone:
      return "min-zone";
  }
  return "?";
}

Method method_from_string(const std::string& s) {
  if (s == "two-point") return Method::TwoPoint;
  if (s == "three-point") return Method::ThreePoint;
  if (s == "lsq") return Method::Lsq;
  throw Error(fmt::format("unknown method '{}' (expected two-point, three-point or lsq)", s));
}

Reference reference_from_string(const std::string& s) {
  if (s == "ls") return Reference::LeastSquares;
  if (s == "patent" || s == "seed") return Reference::Seed;  // "seed": earlier files
  if (s == "min-zone") return Reference::MinZone;
  throw Error(fmt::format("unknown reference '{}' (expected ls, patent or min-zone)", s));
}

double ProbeData::step() const {
  if (x.size() < 2) throw Error("need at least two stations");
  return (x[x.size() - 1] - x[0]) / static_cast<double>(x.size() - 1);
}

namespace {

// ProbeData::validate in three parts, so that separate() can check the values (one pass over all
// the data) on another core while the method runs; the errors are the same, in the same order.
void check_shapes(const ProbeData& d) {
  const Eigen::Index n = d.x.size();
  const auto& readings = d.readings;
  const auto& offsets = d.offsets;
  const auto& angle = d.angle;
  if (n < 3) throw Error(fmt::format("too few stations: {} (need at least 3)", n));
  if (readings.rows() != n)
    throw Error(fmt::format("readings have {} rows but there are {} stations", readings.rows(), n));
  if (readings.cols() < 2) throw Error("need at least two probes");
  if (static_cast<Eigen::Index>(offsets.size()) != readings.cols())
    throw Error(
        fmt::format("{} probe offsets for {} probe columns", offsets.size(), readings.cols()));
  if (angle.size() != 0 && angle.size() != n)
    throw Error(fmt::format("angle channel has {} values for {} stations", angle.size(), n));
}

void check_values(const ProbeData& data) {
  const Eigen::Index n = data.x.size();
  const auto& x = data.x;
  const auto& readings = data.readings;
  const auto& angle = data.angle;
  // One vectorised pass per array decides; only a failure looks for the first offender.
  auto finite = [](const double* v, Eigen::Index m) {
    // v·0 is NaN for a NaN or an infinity, else 0; Eigen's sum keeps several vector
    // accumulators, so the pass runs at memory speed.
    return (Eigen::Map<const Eigen::ArrayXd>(v, m) * 0.0).sum() == 0;
  };
  bool all_finite = finite(angle.data(), angle.size());
  for (Eigen::Index j = 0; j < readings.cols() && all_finite; ++j)
    all_finite = finite(readings.col(j).data(), n);
  if (!all_finite) throw Error("non-finite value (NaN or Inf) in the data");
  // x's own check rides on the pass over its steps (which are used only once x is finite).
  const double* xp = x.data();
  const double h = n >= 2 ? data.step() : 0.0;  // (not finite with x: reported below)
  const double tolerance = kStepTolerance * h + 1e-12;
  double smallest = h, worst = 0, x_finite = n ? xp[0] * 0.0 : 0.0;
#pragma omp simd reduction(min : smallest) reduction(max : worst) reduction(+ : x_finite)
  for (Eigen::Index k = 1; k < n; ++k) {
    const double d = xp[k] - xp[k - 1];
    x_finite += xp[k] * 0.0;
    smallest = std::min(smallest, d);
    worst = std::max(worst, std::abs(d - h));
  }
  if (!(x_finite == 0)) throw Error("non-finite value (NaN or Inf) in the data");
  if (n < 2) data.step();  // throws its error
  if (!(h > 0)) throw Error("station positions must increase");
  const bool uneven = !(smallest > 0) || worst > tolerance;
  for (Eigen::Index k = 1; k < n && uneven; ++k) {
    const double d = x[k] - x[k - 1];
    if (!(d > 0))
      throw Error(fmt::format("station {} does not increase (x = {} after {})", k, x[k], x[k - 1]));
    if (std::abs(d - h) > tolerance)
      throw Error(fmt::format("uneven step at station {}: {} mm instead of {} mm", k, d, h));
  }
}

void check_offsets(const ProbeData& d) {
  const auto& offsets = d.offsets;
  const double h = d.step();
  if (offsets[0] != 0) throw Error("the first probe offset must be 0 (offsets are from probe A)");
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    const double r = offsets[i] / h;
    if (!std::isfinite(r) ||
        std::abs(r - std::round(r)) > kStepTolerance * std::max(1.0, std::abs(r)))
      throw Error(fmt::format("probe offset {} mm is not a whole multiple of the step {} mm",
                              offsets[i], h));
    for (std::size_t j = 0; j < i; ++j)
      if (std::round(offsets[j] / h) == std::round(r))
        throw Error(
            fmt::format("probes {} and {} have the same offset {} mm", j + 1, i + 1, offsets[i]));
  }
}

}  // namespace

void ProbeData::validate() const {
  check_shapes(*this);
  check_values(*this);
  check_offsets(*this);
}

void Options::validate() const {
  if (sigma && !(*sigma > 0 && std::isfinite(*sigma))) throw Error("sigma must be positive");
  if (!(angle_sigma > 0 && std::isfinite(angle_sigma))) throw Error("angle sigma must be positive");
  if (!(nominal_sigma > 0)) throw Error("nominal sigma must be positive");
  if (!(filter_cutoff >= 0 && std::isfinite(filter_cutoff)))
    throw Error("filter cut-off must be >= 0");
  if (zero_difference && !std::isfinite(*zero_difference))
    throw Error("zero difference must be finite");
  if (reference == Reference::Seed && method != Method::ThreePoint)
    throw Error("reference 'patent' is defined for the three-point method only");
}

// ---------------------------------------------------------------------------------------------
// Design of the least-squares problem, shared by the solver and the layout analysis.
namespace detail {

Eigen::Vector3d zero_difference_weights(const std::vector<long>& p) {
  if (p.size() != 3) throw Error("a zero difference is defined for three-probe layouts only");
  const double sb = static_cast<double>(p[1]), sc = static_cast<double>(p[2]);
  return {1.0, -sc / (sc - sb), sb / (sc - sb)};
}

Design make_design(const std::vector<long>& p, long n, bool angle, std::optional<double> zero_diff,
                   double wa) {
  Design D;
  D.n = n;
  D.N = static_cast<int>(p.size());
  D.p = p;
  const long pmin = *std::min_element(p.begin(), p.end());
  for (long v : p) D.q.push_back(v - pmin);
  D.span = *std::max_element(D.q.begin(), D.q.end());
  D.Q = n + D.span;
  D.angle = angle;
  D.pitch = D.N >= 3 || angle;
  D.wa = wa;
  D.nvars = static_cast<int>(D.Q + n * (D.pitch ? 2 : 1) + D.N + (angle ? 1 : 0));
  D.pinned.assign(static_cast<std::size_t>(D.nvars), 0);
  auto pin = [&](int id, double v) {
    D.pinned[static_cast<std::size_t>(id)] = 1;
    D.pins.emplace_back(id, v);
  };
  // Line: fix the workpiece at its first and last positions. Pinning far-apart points keeps the
  // pinned solution as small as the profile itself (adjacent pins would tilt it by n times the
  // local slope and cost precision); the reference line is applied afterwards.
  pin(D.w(0), 0);
  pin(D.w(D.Q - 1), 0);
  // Offsets: a common offset is absorbed by g; with pitch, an offset ∝ s_i by θ.
  pin(D.o(0), 0);
  int last = 0;
  for (int i = 1; i < D.N; ++i)
    if (std::abs(p[static_cast<std::size_t>(i)]) > std::abs(p[static_cast<std::size_t>(last)]))
      last = i;
  if (D.pitch) {
    if (angle)
      pin(D.oa(), 0);
    else
      pin(D.o(last), 0);
  }
  if (D.pitch && !angle) {
    // Parabola: offsets ∝ s_i² trade against w + c·x². Fixed by a known zero difference (three
    // probes), or else by pinning the middle of the workpiece and applying the guide-quadratic
    // gauge afterwards.
    int other = -1;
    for (int i = 1; i < D.N && other < 0; ++i)
      if (i != last) other = i;
    if (zero_diff) {
      // With o_A and o_last pinned to 0, e = z_other·o_other.
      pin(D.o(other), *zero_diff / zero_difference_weights(p)[other]);
    } else {
      pin(D.w(D.Q / 2), 0);
      D.parabola_free = true;
    }
  } else if (zero_diff) {
    throw Error(angle ? "a zero difference is not needed with an angle channel"
                      : "a zero difference is defined for three-probe layouts only");
  }
  return D;
}

}  // namespace detail

namespace {

using detail::Design;
using detail::make_design;
using detail::station_rows;
using detail::zero_difference_weights;

long gcd_of_steps(const std::vector<long>& q) {
  long d = 0;
  for (long v : q) d = std::gcd(d, v);
  return d;
}

std::string steps_text(const std::vector<long>& p) {
  std::string s;
  for (long v : p) s += (s.empty() ? "" : ", ") + std::to_string(v);
  return s;
}

LayoutAnalysis analyze_layout_uncached(const std::vector<long>& steps, bool angle_channel,
                                       bool zero_difference_known, long stations) {
  LayoutAnalysis a;
  a.steps = steps;
  const long pmin = *std::min_element(steps.begin(), steps.end());
  const long pmax = *std::max_element(steps.begin(), steps.end());
  const long span = pmax - pmin;
  const long na = std::min<long>(stations, std::max<long>(64, 8 * span + 16));
  const Design D =
      make_design(steps, na, angle_channel,
                  zero_difference_known ? std::optional<double>(0.0) : std::nullopt, 1.0);
  a.pitch_modelled = D.pitch;
  a.unobservable.push_back("line");
  if (D.parabola_free) a.unobservable.push_back("parabola");
  if (!D.pitch) a.unobservable.push_back("pitch (not separable with two probes)");
  // Dense design over free variables.
  std::vector<int> col(static_cast<std::size_t>(D.nvars), -1);
  int nf = 0;
  for (int id = 0; id < D.nvars; ++id)
    if (!D.pinned[static_cast<std::size_t>(id)]) col[static_cast<std::size_t>(id)] = nf++;
  std::vector<std::vector<std::pair<int, double>>> rows;
  for (long K = 0; K < na; ++K)
    station_rows(D, K, nullptr, 0.0,
                 [&](const auto& c, double) { rows.emplace_back(c.begin(), c.end()); });
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows.size()), nf);
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (const auto& [id, v] : rows[r])
      A(static_cast<Eigen::Index>(r), col[static_cast<std::size_t>(id)]) += v;
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(A);  // singular values only
  const Eigen::VectorXd sv = svd.singularValues();
  const double tol = 1e-9 * std::max(1.0, sv.size() ? sv[0] : 1.0);
  long rank = 0;
  for (Eigen::Index i = 0; i < sv.size(); ++i)
    if (sv[i] > tol) ++rank;
  a.extra_null_modes = nf - rank;
  if (a.extra_null_modes == 0) return a;

  a.observable = false;
  std::vector<long> q;
  for (long v : steps) q.push_back(v - pmin);
  const long d = gcd_of_steps(q);
  long named = 0;
  std::string why;
  if (d > 1) {
    a.unobservable.push_back(fmt::format("chain offsets ({} chains)", d));
    a.unobservable.push_back(fmt::format("chain tilts ({} chains)", d));
    named = std::min<long>(a.extra_null_modes, 2 * (d - 1));
    why = fmt::format(
        "the probe offsets are multiples of {} steps, so the stations form {} interleaved chains "
        "that no reading ties together",
        d, d);
  }
  if (a.extra_null_modes > named) {
    a.unobservable.push_back(fmt::format("{} blind or edge mode(s)", a.extra_null_modes - named));
    if (!why.empty()) why += "; ";
    why += fmt::format(
        "the layout's difference equation has roots other than 1, whose modes (blind harmonics or "
        "modes that die away from the ends) no reading sees");
  }
  if (stations < na) why += " (or there are too few stations)";
  std::string modes;
  for (std::size_t i = D.parabola_free ? 2 : 1; i < a.unobservable.size(); ++i)
    if (a.unobservable[i].rfind("pitch", 0) != 0)
      modes += (modes.empty() ? "" : ", ") + a.unobservable[i];
  a.message = fmt::format(
      "unobservable layout: probe offsets {} steps{} leave {} mode(s) undetermined beyond the "
      "reference line{} ({}): {}. Use offsets whose step multiples have no common factor and "
      "consecutive spacing of one step, add probes or an angle channel",
      steps_text(steps), angle_channel ? " with an angle channel" : "", a.extra_null_modes,
      D.parabola_free ? " and parabola" : "", modes, why);
  return a;
}

}  // namespace

LayoutAnalysis analyze_layout(const std::vector<long>& steps, bool angle_channel,
                              bool zero_difference_known, long stations) {
  if (steps.empty()) throw Error("analyze_layout: no probes");
  // The analysis looks at a fixed stretch of stations; a layout seen before with at least that
  // many stations gets the same answer, so it is kept (an SVD costs a few milliseconds).
  const long pmin = *std::min_element(steps.begin(), steps.end());
  const long pmax = *std::max_element(steps.begin(), steps.end());
  const long na = std::max<long>(64, 8 * (pmax - pmin) + 16);
  if (stations < na)
    return analyze_layout_uncached(steps, angle_channel, zero_difference_known, stations);
  static std::mutex mutex;
  static std::map<std::tuple<std::vector<long>, bool, bool>, LayoutAnalysis> cache;
  const auto key = std::make_tuple(steps, angle_channel, zero_difference_known);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = cache.find(key); it != cache.end()) return it->second;
  }
  LayoutAnalysis a = analyze_layout_uncached(steps, angle_channel, zero_difference_known, stations);
  const std::lock_guard<std::mutex> lock(mutex);
  if (cache.size() < 256) cache.emplace(key, a);
  return a;
}

// ---------------------------------------------------------------------------------------------
namespace {

// A solution before the reference is applied, on its own grids.
struct Raw {
  Eigen::VectorXd xw, w;      // workpiece grid and values (mm)
  Eigen::VectorXd xg, g;      // station grid, guide (mm)
  Eigen::VectorXd xt, theta;  // pitch grid and values (rad); empty if not modelled
  bool parabola_free = false;
  // xg is known to be strictly increasing (the checked data's stations): its range is its ends.
  bool xg_increasing = false;
};

// Long profiles have independent passes (workpiece and guide, copies) run on two cores.
constexpr Eigen::Index kTwoCorePoints = 50000;

std::launch policy_for(const Raw& r) {
  return r.g.size() >= kTwoCorePoints ? std::launch::async : std::launch::deferred;
}

// Everything the uncertainty propagation needs from a least-squares solve. The banded solve
// leaves its factorisation (engine); the direct solve of a layout without redundancy has none
// (dof 0), and its uncertainties, which depend on the grids alone, are under way on another core
// when wanted (propagation, into uw, ug, ut, from the stations).
struct LsqState {
  Design D;
  std::unique_ptr<detail::BandedLsq> engine;
  double h = 0;
  double ssr = 0;
  long dof = 0;
  Eigen::VectorXd uw, ug, ut;
  std::future<void> propagation;
};

}  // namespace

// Each station's three readings determine its three new unknowns (the workpiece under probe C,
// the guide, the pitch); with the gauge pins the system is square (dof = 0).
bool detail::direct_layout(const std::vector<long>& p, bool angle) {
  return !angle && p == std::vector<long>{0, 1, 2};
}

namespace {

// The least-squares grids for n stations at x (workpiece positions 0..Q−1 at x_0 + (j + pmin)·h,
// guide and pitch at the stations), into r's arrays (sized by the caller).
// Workpiece position j (a whole number) of a least-squares grid starting at the first station x0:
// the one formula for every copy of the grid (the direct solve's uncertainties form their own,
// and must agree with the solve's to the last bit).
inline double workpiece_position(double x0, double j, double h) {
  return x0 + j * h;
}

void fill_lsq_grids(const Eigen::VectorXd& x, long pmin, double h, Raw& r) {
  for (Eigen::Index j = 0; j < r.xw.size(); ++j)
    r.xw[j] = workpiece_position(x[0], static_cast<double>(j + pmin), h);
  r.xg = x;
  if (r.xt.size()) r.xt = x;
}

Raw solve_lsq(const ProbeData& data, const Options& opt, LsqState& st) {
  const long n = data.x.size();
  const double h = data.step();
  std::vector<long> p;
  for (double s : data.offsets) p.push_back(std::lround(s / h));
  const bool angle = data.angle.size() == n;
  const double sp = opt.sigma.value_or(opt.nominal_sigma);
  const double wa = sp / (opt.angle_sigma * h);
  // Centre every channel: only the (nuisance) offsets change, and the pinned offsets then sit
  // close to their true values, so no large parabola enters the pinned solution.
  const Eigen::RowVectorXd mu = data.readings.colwise().mean();
  const double mu_a = angle ? data.angle.mean() : 0.0;
  std::optional<double> e = opt.zero_difference;
  // e refers to the raw offsets; the centred offsets are o_i − μ_i.
  if (e && p.size() == 3) *e -= zero_difference_weights(p).dot(mu.transpose());
  st.D = make_design(p, n, angle, e, wa);
  st.h = h;
  const Design& D = st.D;
  // Iterative refinement: each pass factorises the system with right-hand side b − A·v and
  // corrects v. A single pass carries the error the long chain's conditioning puts into any
  // backward-stable solve (~1e-4 relative at a million stations); a second one removes it.
  // The profiles' arrays hold the unknowns; their pages are committed on another core while the
  // first pass factorises.
  Raw r;
  r.xw.resize(D.Q);
  r.w.resize(D.Q);
  r.xg.resize(n);
  r.g.resize(n);
  if (D.pitch) {
    r.xt.resize(n);
    r.theta.resize(n);
  }
  const detail::Prefault prefault(
      {{r.w.data(), sizeof(double) * static_cast<std::size_t>(D.Q)},
       {r.g.data(), sizeof(double) * static_cast<std::size_t>(n)},
       {r.theta.data(), sizeof(double) * static_cast<std::size_t>(r.theta.size())}});
  // The grids depend on x alone: filled on another core meanwhile.
  for (const Eigen::VectorXd* grid : {&r.xw, &r.xg, &r.xt})
    trueaxis::detail::advise_huge_pages(grid->data(),
                                        sizeof(double) * static_cast<std::size_t>(grid->size()));
  const long pmin = *std::min_element(p.begin(), p.end());
  auto grids = std::async(policy_for(r), [&] { fill_lsq_grids(data.x, pmin, h, r); });
  st.engine = std::make_unique<detail::BandedLsq>(D);
  Eigen::VectorXd angle_mm;
  if (angle) angle_mm = (data.angle.array() - mu_a) * h;
  // The unknowns are solved straight into the profiles' arrays (θ as θ·h until the end). The
  // first pass starts from zero without writing it: it forms the right-hand side from the
  // readings and the pins, and then sets every free unknown.
  std::vector<double> offsets(static_cast<std::size_t>(D.N + (angle ? 1 : 0)), 0.0);
  const detail::Unknowns v{r.w.data(), r.g.data(), D.pitch ? r.theta.data() : nullptr,
                           offsets.data()};
  double pin_size = 0;  // the largest pinned |value|: the refinement never changes those
  for (const auto& [id, value] : D.pins) {
    v(D, id) = value;
    pin_size = std::max(pin_size, std::abs(value));
  }
  double ssr0 = 0, last = 0;
  const double round_off =
      std::max(1e-14, static_cast<double>(n) * std::numeric_limits<double>::epsilon());
  for (int iter = 0; iter < 4; ++iter) {
    if (iter == 0)
      st.engine->factor(data.readings, mu, angle_mm, v, true);
    else
      st.engine->refactor_rhs(data.readings, mu, angle_mm, v);
    if (iter == 0) {
      if (st.engine->min_pivot_ratio() < 1e-10) {
        const LayoutAnalysis a = analyze_layout(p, angle, opt.zero_difference.has_value(), n);
        throw Error(a.observable ? "the data do not determine the solution (rank-deficient system)"
                                 : a.message);
      }
      ssr0 = st.engine->ssr();
    }
    const detail::BandedLsq::Update up = st.engine->solve_add(v, iter == 0);
    // Refinement converges linearly: the next correction is about (this one)²/(the last one).
    // Stop when that is below the round-off floor: the residual b − A·v is itself rounded
    // (~ε of its terms per row) and the long chain carries that into every correction, so after
    // the first refinement the corrections stop falling, at 0.1–0.5·n·ε of the profile (measured
    // at 10⁴–10⁶ stations). A pass predicted to move the result by less than n·ε of it (and never
    // less than 1e-14) would only move it within that noise.
    const double size = std::max({1e-300, up.max_value, pin_size});
    const double now = up.max_correction;
    const double next = iter == 0 ? now : now * (now / std::max(1e-300, last));
    if (now <= round_off * size || next <= round_off * size) break;
    last = now;
  }
  st.ssr = ssr0;
  st.dof = st.engine->rows() - st.engine->unknowns();
  if (D.pitch) r.theta /= h;
  grids.get();
  r.parabola_free = D.parabola_free;
  return r;
}

// The least-squares solution for a direct_layout, without a factorisation. With the pins of
// make_design (w_0 = w_{Q−1} = 0, o_A = o_C = 0, and w_m = 0 at m = Q/2 or o_B from the known
// zero difference) and the centred readings a, b, c of probes A, B, C, station K's rows
//   w_K + g_K = a_K,  w_{K+1} + g_K + t_K + o_B = b_K,  w_{K+2} + g_K + 2t_K = c_K
// (t = θ·h) give g_K and t_K from w, and w_{K+2} = 2w_{K+1} − w_K + f_K + β with
// f_K = a_K − 2b_K + c_K and β = 2·o_B. w is that recurrence run from w_0 = 0, w_1 = α, with α
// and (parabola free) β set by the pins at Q − 1 and m. The chain's rounding (~1e-9 of the
// profile at a million stations) is removed as the banded solve removes its own: one refinement
// with the residual of the recurrence, solved by the same recurrence, which leaves the result at
// the residual's own rounding floor.
Raw solve_lsq_direct(const ProbeData& data, const Options& opt) {
  const long n = data.x.size();
  const double h = data.step();
  const long Q = n + 2, m = Q / 2;
  Raw r;
  r.xw.resize(Q);
  r.w.resize(Q);
  r.xg.resize(n);
  r.g.resize(n);
  r.xt.resize(n);
  r.theta.resize(n);
  const detail::Prefault prefault({{r.g.data(), sizeof(double) * static_cast<std::size_t>(n)},
                                   {r.theta.data(), sizeof(double) * static_cast<std::size_t>(n)}});
  auto grids = std::async(policy_for(r), [&] { fill_lsq_grids(data.x, 0, h, r); });
  const Eigen::RowVectorXd mu = data.readings.colwise().mean();
  const double ma = mu[0], mb = mu[1], mc = mu[2];
  const double* A = data.readings.col(0).data();
  const double* B = data.readings.col(1).data();
  const double* C = data.readings.col(2).data();
  const bool beta_known = opt.zero_difference.has_value();
  // With o_A = o_C = 0, o_B = −e'/2 for the zero difference of the centred offsets,
  // e' = e − (μ_A − 2μ_B + μ_C).
  double beta = beta_known ? (ma - 2 * mb + mc) - *opt.zero_difference : 0.0;
  auto forcing = [&](long K) { return (A[K] - ma) - 2 * (B[K] - mb) + (C[K] - mc); };
  // α·j + δβ·j(j − 1)/2 that brings the values at the pins Q − 1 and m (end, mid) to zero.
  const double e1 = static_cast<double>(Q - 1), e2 = e1 * (e1 - 1) / 2;
  const double m1 = static_cast<double>(m), m2 = m1 * (m1 - 1) / 2;
  auto fit = [&](double end, double mid) -> std::pair<double, double> {
    if (beta_known) return {-end / e1, 0.0};
    const double det = e1 * m2 - e2 * m1;
    return {(e2 * mid - m2 * end) / det, (m1 * end - e1 * mid) / det};
  };
  double* w = r.w.data();
  // The recurrence as two sums (the forcing off the chain), from w_0 = w_1 = 0.
  w[0] = w[1] = 0;
  {
    double x = 0, dx = 0;
    for (long K = 0; K < n; ++K) {
      dx += forcing(K) + beta;
      x += dx;
      w[K + 2] = x;
    }
  }
  // The refinement, with the pins' line and parabola of the first pass applied on the fly: the
  // residual ρ_K of each station's recurrence as the values stand, and the correction δ that
  // it drives, run from δ_0 = δ_1 = 0.
  {
    const auto [a1, b1] = fit(w[Q - 1], w[m]);
    beta += b1;
    auto first = [&, a1 = a1, b1 = b1](long j) {
      const double q = static_cast<double>(j);
      return w[j] + (a1 * q + b1 * (q * (q - 1) * 0.5));
    };
    double o0 = first(0), o1 = first(1), d0 = 0, d1 = 0, dd = 0;
    for (long K = 0; K < n; ++K) {
      const double o2 = first(K + 2);
      dd += (forcing(K) + beta) - ((o2 - 2 * o1) + o0);
      const double d2 = d1 + dd;
      w[K] = o0 + d0;
      o0 = o1;
      o1 = o2;
      d0 = d1;
      d1 = d2;
    }
    w[n] = o0 + d0;
    w[n + 1] = o1 + d1;
  }
  // The pins' line and parabola of the correction, then g and t from each station's A and B rows,
  // in one vectorised pass: t_K needs w_{K+1}, formed again before the next step overwrites it.
  // The station number is a double made from a 32-bit offset in blocks, so that the loop
  // vectorises.
  {
    const auto [a2, b2] = fit(w[Q - 1], w[m]);
    beta += b2;
    const double oB = beta / 2;
    auto fixed = [a2 = a2, b2 = b2](double v, double q) {
      return v + (a2 * q + b2 * (q * (q - 1) * 0.5));
    };
    double* __restrict g = r.g.data();
    double* __restrict t = r.theta.data();
    constexpr long kBlock = 1L << 20;
    for (long K0 = 0; K0 < n; K0 += kBlock) {
      const int len = static_cast<int>(std::min(kBlock, n - K0));
      const double base = static_cast<double>(K0);
      const double *Ab = A + K0, *Bb = B + K0;
      double *wb = w + K0, *gb = g + K0, *tb = t + K0;
#pragma omp simd
      for (int i = 0; i < len; ++i) {
        const double q = base + static_cast<double>(i);
        const double wk = fixed(wb[i], q), wk1 = fixed(wb[i + 1], q + 1);
        const double gk = (Ab[i] - ma) - wk;
        wb[i] = wk;
        gb[i] = gk;
        tb[i] = ((Bb[i] - mb) - oB - wk1 - gk) / h;
      }
    }
    w[n] = fixed(w[n], static_cast<double>(n));
    w[n + 1] = fixed(w[n + 1], static_cast<double>(n + 1));
  }
  grids.get();
  r.parabola_free = !beta_known;
  return r;
}

void require_offsets(const ProbeData& d, std::initializer_list<long> want, const char* method) {
  const double h = d.step();
  bool ok = d.offsets.size() == want.size();
  std::size_t i = 0;
  for (long w : want) {
    if (!ok) break;
    ok = std::lround(d.offsets[i++] / h) == w;
  }
  if (!ok) {
    std::string s;
    for (long w : want)
      s += (s.empty() ? "" : ", ") + fmt::format("{}", static_cast<double>(w) * h);
    throw Error(fmt::format(
        "method {} needs probes at offsets {} mm (spacing equal to the step {} mm); use --method "
        "lsq for other layouts",
        method, s, h));
  }
  if (d.angle.size() != 0)
    throw Error(fmt::format("method {} does not use an angle channel; use --method lsq", method));
}

// The arrays a recurrence fills for n stations, and their regions for Prefault.
Raw recurrence_arrays(Method m, long n) {
  Raw r;
  const long nw = m == Method::TwoPoint ? n + 1 : n;
  r.xw.resize(nw);
  r.w.resize(nw);
  r.xg.resize(n);
  r.g.resize(n);
  if (m == Method::ThreePoint && n > 0) {
    r.xt.resize(n - 1);
    r.theta.resize(n - 1);
  }
  return r;
}

std::vector<detail::Prefault::Region> regions_of(const Raw& r) {
  std::vector<detail::Prefault::Region> out;
  for (const Eigen::VectorXd* v : {&r.g, &r.w, &r.theta, &r.xw, &r.xg, &r.xt})
    out.push_back({v->data(), sizeof(double) * static_cast<std::size_t>(v->size())});
  return out;
}

// Fills r (sized by recurrence_arrays).
void two_point(const ProbeData& d, Raw& r) {
  require_offsets(d, {0, 1}, "two-point");
  const long n = d.x.size();
  const double h = d.step();
  r.xw = Eigen::VectorXd::LinSpaced(n + 1, d.x[0], d.x[0] + static_cast<double>(n) * h);
  r.w = Eigen::VectorXd::Zero(n + 1);
  r.xg = d.x;
  r.g.resize(n);
  const auto mA = d.readings.col(0);
  const auto mB = d.readings.col(1);
  // Spec 01 method A with w_0 = g_0 = 0 and the unknown slope w_1 = 0 (reference line later).
  for (long K = 0; K < n; ++K) {
    if (K + 1 <= n) r.w[K + 1] = r.w[K] + (mB[K] - mB[0]) - (mA[K] - mA[0]);
    r.g[K] = mA[K] - mA[0] - r.w[K];
  }
}

}  // namespace

// The seed's three-point recurrence (JPH0464003B2 eqs. 12–17), exposed for the "seed" reference.
namespace {

// Fills r (sized by recurrence_arrays).
void three_point(const ProbeData& d, std::optional<double> zero_difference, Raw& r) {
  require_offsets(d, {0, 1, 2}, "three-point");
  const long n = d.x.size();  // stations K = 0..n-1
  if (n < 4) throw Error(fmt::format("three-point needs at least 4 stations, got {}", n));
  const double l = d.step();
  const double* A = d.readings.col(0).data();
  const double* B = d.readings.col(1).data();
  const double* C = d.readings.col(2).data();
  const double a0 = A[0], b0 = B[0], c0 = C[0];
  // The profiles' station grids are copies of x: made on another core meanwhile.
  auto grids = std::async(policy_for(r), [&] {
    r.xt = d.x.head(n - 1);
    r.xg = d.x;
    r.xw = d.x;
  });
  // Eq. 12 run from X_0 = 0, X_1 = α with the constant β: X_K = K·α + K(K−1)/2·β + C_K (eq. 15),
  // with D_K = m(K) − m(0) per probe formed on the fly. Returns b = −Σ_{K≥2} a_K·X_K with
  // a_K = (K, K(K−1)/2), for the fit below.
  Eigen::VectorXd& X = r.g;  // the guide is X itself (eq. 13)
  // Run as two sums, ΔX_{K+1} = ΔX_K + f_K and X_{K+2} = X_{K+1} + ΔX_{K+1}, with the forcing f_K
  // formed off the chain: each station waits for two additions, not for the whole expression.
  auto recurrence = [&](double alpha, double beta) {
    X[0] = 0;
    X[1] = alpha;
    double x = alpha, dx = alpha, b0s = 0, b1s = 0;
    for (long K = 0; K + 2 < n; ++K) {
      const double f = (A[K + 2] - a0) - 2 * (A[K + 1] - a0) + 2 * (B[K] - b0) - (C[K] - c0) + beta;
      dx += f;
      x += dx;
      X[K + 2] = x;
      const double k = static_cast<double>(K + 2);
      b0s -= k * x;
      b1s -= k * (k - 1) / 2 * x;
    }
    return Eigen::Vector2d(b0s, b1s);
  };
  // α, β (or α alone when β is known) minimising Σ_{K=2}^{n−1} (X_K + K·α + K(K−1)/2·β)²: the
  // 2×2 normal equations whose closed form is the seed's eqs. 16–17.
  const bool beta_known = zero_difference.has_value();
  // β = 2Y_1 − Y_2 = e − (D_0A − 2D_0B + D_0C) when the zero difference e is known.
  const double beta0 =
      beta_known ? *zero_difference - (d.readings(0, 0) - 2 * d.readings(0, 1) + d.readings(0, 2))
                 : 0.0;
  // Two fits, identical in exact arithmetic to the one-shot formula: C_K can grow like K²·β
  // (1e9 mm at a million stations), so the first fit is used to run the recurrence near its
  // final size and the second fit corrects the small remainder. The first needs only b, a linear
  // function of the forcing: with α = 0 and f_j the forcing (β included), X_K = Σ_{j≤K−2}
  // (K−1−j)·f_j, so b_i = −Σ_j f_j·W_i(j) with W_0(j) = Σ_{K=j+2}^{n−1} K·(K−1−j) and W_1(j) the
  // same with K(K−1)/2. In m = K−1−j ∈ [1, M], M = n−2−j, c = j+1 these are sums of powers of
  // m, which with S1 = M(M+1)/2 close to W_0 = S1·(3n−2−M)/3 and
  // W_1 = S1·(3·S1 + (2c−1)(2M+1) + 3c(c−1))/6 (integers below 2⁵³ up to the last product; the
  // common divisors are applied once). The same pass sums the fit's normal matrix Σ a·aᵀ over
  // K = j+2 into Mn. One vectorised pass, not a recurrence: the counts are doubles made from 32-bit
  // offsets in blocks (64-bit integers do not convert to doubles in vector registers).
  Eigen::Matrix2d Mn;
  auto forcing_moments = [&](double beta) {
    double s0 = 0, s1 = 0, s11 = 0, s12 = 0, s22 = 0;
    const double n1 = static_cast<double>(n - 2), n3 = 3.0 * static_cast<double>(n) - 2;
    constexpr long kBlock = 1L << 20;
    for (long j0 = 0; j0 < n - 2; j0 += kBlock) {
      const int m = static_cast<int>(std::min(kBlock, n - 2 - j0));
      const double base = static_cast<double>(j0);
      const double *Ab = A + j0, *Bb = B + j0, *Cb = C + j0;
#pragma omp simd reduction(+ : s0, s1, s11, s12, s22)
      for (int i = 0; i < m; ++i) {
        const double f =
            (Ab[i + 2] - a0) - 2 * (Ab[i + 1] - a0) + 2 * (Bb[i] - b0) - (Cb[i] - c0) + beta;
        const double j = base + static_cast<double>(i), M = n1 - j, c = j + 1;
        const double S1 = M * (M + 1) * 0.5;
        s0 -= f * (S1 * (n3 - M));
        s1 -= f * (S1 * (3 * S1 + (2 * c - 1) * (2 * M + 1) + 3 * c * (c - 1)));
        const double k = c + 1, t = k * c * 0.5;  // K = j + 2 and K(K−1)/2
        s11 += k * k;
        s12 += k * t;
        s22 += t * t;
      }
    }
    Mn << s11, s12, s12, s22;
    return Eigen::Vector2d(s0 / 3, s1 / 6);
  };
  auto fit = [&](const Eigen::Vector2d& b) {
    if (beta_known) return Eigen::Vector2d(b[0] / Mn(0, 0), 0.0);
    return Eigen::Vector2d(Mn.ldlt().solve(b));
  };
  const Eigen::Vector2d ab1 = fit(forcing_moments(beta0));
  const Eigen::Vector2d ab2 = fit(recurrence(ab1[0], beta0 + ab1[1]));
  // The corrected guide, w (eq. 13) and θ (eq. 14) in one pass: θ_K needs w_{K+1}, which is
  // formed again from X_{K+1} before the next step overwrites it. The station number is a double
  // made from a 32-bit offset in blocks, so that the loop vectorises.
  {
    const double c0 = ab2[0], c1 = ab2[1];
    auto fixed = [c0, c1](double x, double k) { return x + (k * c0 + k * (k - 1) / 2 * c1); };
    double* __restrict Xp = X.data();
    double* __restrict wp = r.w.data();
    double* __restrict tp = r.theta.data();
    const double w1 = (A[1] - a0) - fixed(Xp[1], 1);
    constexpr long kBlock = 1L << 20;
    for (long K0 = 0; K0 + 1 < n; K0 += kBlock) {
      const int m = static_cast<int>(std::min(kBlock, n - 1 - K0));
      const double base = static_cast<double>(K0);
      const double *Ab = A + K0, *Bb = B + K0;
      double *Xb = Xp + K0, *wb = wp + K0, *tb = tp + K0;
#pragma omp simd
      for (int i = 0; i < m; ++i) {
        const double k = base + static_cast<double>(i);
        const double xk = fixed(Xb[i], k), xk1 = fixed(Xb[i + 1], k + 1);
        Xb[i] = xk;
        wb[i] = (Ab[i] - a0) - xk;
        tb[i] = ((Bb[i] - b0) - ((Ab[i + 1] - a0) - xk1) - xk + w1) / l;
      }
    }
    Xp[n - 1] = fixed(Xp[n - 1], static_cast<double>(n - 1));
    wp[n - 1] = (A[n - 1] - a0) - Xp[n - 1];
  }
  grids.get();
  r.parabola_free = !zero_difference.has_value();
}

// Coordinates for the parabola gauge: t = (x - xc)/L.
struct Scale {
  double xc = 0, L = 1;
};

// The scale of grid x: its mid-range and half range (from its ends when it is known to increase).
Scale scale_of(Eigen::Ref<const Eigen::VectorXd> x, bool increasing = false) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const double* xp = x.data();
  if (increasing && x.size()) {
    lo = xp[0];
    hi = xp[x.size() - 1];
  } else {  // one vectorised pass
#pragma omp simd reduction(min : lo) reduction(max : hi)
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      lo = std::min(lo, xp[i]);
      hi = std::max(hi, xp[i]);
    }
  }
  return {0.5 * (lo + hi), std::max(1e-12, 0.5 * (hi - lo))};
}

// A profile's sums in the parabola's coordinate t = (x − x_c)/L: Σtᵏ (k ≤ 4) and Σtᵏ·y (k ≤ 2).
struct Moments {
  double t[5] = {0, 0, 0, 0, 0}, ty[3] = {0, 0, 0};
};

// Coefficients e of the functional φ_K = e_0 + e_1·t_K + e_2·t_K² with φᵀg = the coefficient of t²
// in the LS fit of g by {1, t, t²} (t = (x − x_c)/L): e = G⁻¹·(0, 0, 1), G = TᵀT from the moments
// of t.
Eigen::Vector3d quad_coefficients_from(const Moments& m) {
  Eigen::Matrix3d G;
  G << m.t[0], m.t[1], m.t[2], m.t[1], m.t[2], m.t[3], m.t[2], m.t[3], m.t[4];
  return G.ldlt().solve(Eigen::Vector3d(0, 0, 1));
}

Moments moments_of(Eigen::Ref<const Eigen::VectorXd> x, Eigen::Ref<const Eigen::VectorXd> y,
                   const Scale& s) {
  Moments m;
  const double inv = 1 / s.L;
  double t1 = 0, t2s = 0, t3 = 0, t4 = 0, y0 = 0, y1 = 0, y2 = 0;
  const double *xp = x.data(), *yp = y.data();
#pragma omp simd reduction(+ : t1, t2s, t3, t4, y0, y1, y2)
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double t = (xp[i] - s.xc) * inv, t2 = t * t, v = yp[i];
    t1 += t;
    t2s += t2;
    t3 += t2 * t;
    t4 += t2 * t2;
    y0 += v;
    y1 += t * v;
    y2 += t2 * v;
  }
  m.t[0] = static_cast<double>(x.size());
  m.t[1] = t1;
  m.t[2] = t2s;
  m.t[3] = t3;
  m.t[4] = t4;
  m.ty[0] = y0;
  m.ty[1] = y1;
  m.ty[2] = y2;
  return m;
}

// Σθ and Σ(x − x_c) over a pitch profile, in one vectorised pass.
struct PitchSums {
  double st = 0, sx = 0;
};
PitchSums pitch_sums(const Eigen::VectorXd& xt, const Eigen::VectorXd& theta, const Scale& s) {
  double st = 0, sx = 0;
  const double *xp = xt.data(), *tp = theta.data();
#pragma omp simd reduction(+ : st, sx)
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    st += tp[i];
    sx += xp[i] - s.xc;
  }
  return {st, sx};
}

// y ← y + a·t² less the least-squares line of that sum (found from the moments: the line of y
// plus a times the line of t²), in one pass that also returns the range of the result: the
// least-squares straightness of the profile as referenced.
double add_parabola_less_line(const Eigen::VectorXd& x, Eigen::VectorXd& y, const Moments& m,
                              double a, const Scale& s) {
  const double n = m.t[0], sy = m.ty[0] + a * m.t[2], sty = m.ty[1] + a * m.t[3];
  const double stt = m.t[2] - m.t[1] * m.t[1] / n;
  if (!(stt > 0)) throw Error("least-squares line: all x are equal");
  const double slope = (sty - m.t[1] * sy / n) / stt, icpt = (sy - slope * m.t[1]) / n;
  const double inv = 1 / s.L;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const double* xp = x.data();
  double* yp = y.data();
#pragma omp simd reduction(min : lo) reduction(max : hi)
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double t = (xp[i] - s.xc) * inv;
    const double v = yp[i] + (a * t - slope) * t - icpt;
    yp[i] = v;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  return hi - lo;
}

// The least-squares straightness of the workpiece and guide as referenced, where apply_reference
// found it on the way (the ls reference); NaN otherwise.
struct LsWidths {
  double w = std::numeric_limits<double>::quiet_NaN(), g = w;
};

// Applies the ls / min-zone reference in place (parabola gauge first, if free).
LsWidths apply_reference(Raw& r, Reference ref) {
  const Scale s = scale_of(r.xg, r.xg_increasing);
  LsWidths widths;
  const std::launch policy = policy_for(r);
  // The workpiece's sums (ls reference), and θ's, meanwhile on another core.
  std::future<std::pair<Moments, PitchSums>> wsums;
  if (ref != Reference::MinZone)
    wsums = std::async(policy, [&] {
      return std::make_pair(moments_of(r.xw, r.w, s), pitch_sums(r.xt, r.theta, s));
    });
  // The parabola gauge: c = φᵀg, the guide's t² coefficient, from the guide's sums (which the
  // ls reference needs anyway).
  Moments mg;
  if (r.parabola_free || ref != Reference::MinZone) mg = moments_of(r.xg, r.g, s);
  double c = 0;
  if (r.parabola_free) {
    const Eigen::Vector3d e = quad_coefficients_from(mg);
    c = e[0] * mg.ty[0] + e[1] * mg.ty[1] + e[2] * mg.ty[2];
  }
  if (ref != Reference::MinZone) {
    // Parabola gauge and line in two passes per profile: one for the sums, one for the update.
    // θ's sums (which do not depend on the parabola) are taken with the workpiece's, and θ is
    // updated after the guide: the two cores then move about the same number of bytes.
    const auto sums = wsums.get();  // (named members: clang 14 lambdas cannot capture bindings)
    const Moments& mw = sums.first;
    const PitchSums& pitch = sums.second;
    auto wupdate = std::async(policy, [&] { return add_parabola_less_line(r.xw, r.w, mw, c, s); });
    widths.g = add_parabola_less_line(r.xg, r.g, mg, -c, s);
    if (r.theta.size()) {
      // θ less the parabola's slope, about its mean.
      const double k = 2 * c / (s.L * s.L);
      const double mean = (pitch.st - k * pitch.sx) / static_cast<double>(r.theta.size());
      const double* xt = r.xt.data();
      double* theta = r.theta.data();
#pragma omp simd
      for (Eigen::Index i = 0; i < r.theta.size(); ++i) theta[i] -= k * (xt[i] - s.xc) + mean;
    }
    widths.w = wupdate.get();
    return widths;
  }
  if (r.parabola_free) {
    auto t2 = [&](double x) {
      const double t = (x - s.xc) / s.L;
      return t * t;
    };
    for (Eigen::Index i = 0; i < r.w.size(); ++i) r.w[i] += c * t2(r.xw[i]);
    for (Eigen::Index i = 0; i < r.g.size(); ++i) r.g[i] -= c * t2(r.xg[i]);
    for (Eigen::Index i = 0; i < r.theta.size(); ++i)
      r.theta[i] -= 2 * c * (r.xt[i] - s.xc) / (s.L * s.L);
  }
  auto wzone = std::async(
      policy, [&] { geometry::subtract_line(r.xw, r.w, geometry::min_zone(r.xw, r.w).middle); });
  geometry::subtract_line(r.xg, r.g, geometry::min_zone(r.xg, r.g).middle);
  wzone.get();
  if (r.theta.size()) r.theta.array() -= r.theta.mean();
  return widths;
}

// A least-squares problem's grids (as in Raw) as views: of a Raw's arrays, or of the data's own
// stations where a grid is the stations.
struct GridViews {
  using View = Eigen::Map<const Eigen::VectorXd>;
  View xw, xg, xt;
  bool parabola_free = false, xg_increasing = false;
  static GridViews of(const Raw& r) {
    return {View(r.xw.data(), r.xw.size()), View(r.xg.data(), r.xg.size()),
            View(r.xt.data(), r.xt.size()), r.parabola_free, r.xg_increasing};
  }
};

// The ls reference as linear algebra. Each reported value is y = scale·x_u − U_i·(Vᵀx): the raw
// unknown x_u less its reference (line, and the parabola gauge), with V's columns the functionals
// that define the reference: [w line (2), g line (2), parabola, pitch mean]. With Z the
// covariance of the raw unknowns (per unit reading variance),
//   var(y) = scale²·Z_uu − 2·scale·U_i·(ZV)_u + U_i·(VᵀZV)·U_iᵀ.
// The three profiles share one V (the parabola's column is common). With `with_pitch` false
// (only the noise gain is wanted, which is about the profiles) the pitch is left out. U's and V's
// rows are formed in closed form from each point's x (no n-long matrices); a profile's U has up
// to 3 columns, padded with zeros.
struct ReferenceAlgebra {
  static constexpr int kW0 = 0, kG0 = 2, kMaxCols = 6;
  using Row = Eigen::Matrix<double, kMaxCols, 1>;  // a row of V or ZV
  using Cols = std::array<int, 3>;                 // the V columns a profile's U refers to

  // The orthonormal basis of {1, x} on a grid: (1/√m, (x − x̄)/‖x − x̄‖).
  struct Line {
    double b0 = 1, mean = 0, inv = 1;
    explicit Line(Eigen::Ref<const Eigen::VectorXd> x) {
      const double m = static_cast<double>(x.size());
      b0 = 1 / std::sqrt(m);
      mean = x.mean();
      const double nn = (x.array() - mean).matrix().norm();
      inv = nn > 0 ? 1 / nn : 1.0;
    }
    double b1(double x) const { return (x - mean) * inv; }
  };

  const GridViews r;
  Scale s;
  Line lw, lg;
  bool par = false, pitch = false;
  int k = 4, kPhi = -1, kT = -1;
  Eigen::Index mw = 0, mg = 0, mt = 0;
  double h = 1;
  Eigen::Vector3d e = Eigen::Vector3d::Zero();  // the parabola functional's coefficients
  double pw0 = 0, pw1 = 0, pg0 = 0, pg1 = 0;    // t² on each grid's line basis
  double lin_mean = 0;                          // mean of the parabola's slope on the θ grid
  Cols cw{}, cg{}, ct{};

  // Whether the pitch is among the reported values (then V has the pitch's column), and on how
  // many points (mt; 0 if not).
  static bool reports_pitch(Eigen::Index xt_points, bool with_pitch, bool has_pitch_unknowns) {
    return with_pitch && xt_points && has_pitch_unknowns;
  }
  static Eigen::Index pitch_points(Eigen::Index xt_points, bool with_pitch,
                                   bool has_pitch_unknowns) {
    return reports_pitch(xt_points, with_pitch, has_pitch_unknowns) ? xt_points : 0;
  }

  ReferenceAlgebra(const Raw& raw, bool with_pitch, bool has_pitch_unknowns, double step)
      : ReferenceAlgebra(GridViews::of(raw), with_pitch, has_pitch_unknowns, step) {}
  ReferenceAlgebra(const GridViews& grids, bool with_pitch, bool has_pitch_unknowns, double step)
      : r(grids),
        s(scale_of(grids.xg, grids.xg_increasing)),
        lw(grids.xw),
        lg(grids.xg),
        par(grids.parabola_free),
        h(step) {
    pitch = reports_pitch(grids.xt.size(), with_pitch, has_pitch_unknowns);
    if (par) kPhi = k++;
    if (pitch) kT = k++;
    mw = r.xw.size();
    mg = r.xg.size();
    mt = pitch_points(grids.xt.size(), with_pitch, has_pitch_unknowns);
    cw = {kW0, kW0 + 1, par ? kPhi : 0};
    cg = {kG0, kG0 + 1, par ? kPhi : 0};
    ct = {pitch ? kT : 0, par ? kPhi : 0, 0};
    e_w0 = unit(kW0);
    e_w1 = unit(kW0 + 1);
    e_g0 = unit(kG0);
    e_g1 = unit(kG0 + 1);
    e_phi = unit(kPhi);
    e_t = unit(kT);
    if (par) {
      e = quad_coefficients_from(moments_of(r.xg, r.xg, s));  // (the y sums unused)
      std::tie(pw0, pw1) = t2_on_line(r.xw, lw);
      pw0 *= lw.b0;
      std::tie(pg0, pg1) = t2_on_line(r.xg, lg);
      pg0 *= lg.b0;
      const double* xt = r.xt.data();
      double sum = 0;
#pragma omp simd reduction(+ : sum)
      for (Eigen::Index K = 0; K < mt; ++K) sum += lin(xt[K]);
      if (mt) lin_mean = sum / static_cast<double>(mt);
    }
  }
  // Σt² and Σb1·t² over a grid, in one vectorised pass.
  std::pair<double, double> t2_on_line(Eigen::Ref<const Eigen::VectorXd> x, const Line& l) const {
    const double* xp = x.data();
    double s0 = 0, s1 = 0;
#pragma omp simd reduction(+ : s0, s1)
    for (Eigen::Index j = 0; j < x.size(); ++j) {
      const double q = t2(xp[j]);
      s0 += q;
      s1 += l.b1(xp[j]) * q;
    }
    return {s0, s1};
  }
  // Per point, multiplications by these instead of divisions (the rows are formed ~5 times per
  // station).
  double invL = 1 / s.L, lin_k = 2.0 / (s.L * s.L);
  double t2(double x) const {
    const double t = (x - s.xc) * invL;
    return t * t;
  }
  double lin(double x) const {
    return (x - s.xc) * lin_k;
  }
  // φ(x), the parabola functional's row entry at a guide point (with the parabola free).
  double phi(double x) const {
    const double t = (x - s.xc) * invL;
    return e[0] + t * (e[1] + t * e[2]);
  }

  // U's rows. Workpiece: its line, and the parabola the gauge moves into it (t² less its line).
  [[gnu::always_inline]] Eigen::Vector3d uw(Eigen::Index j) const {
    const double x = r.xw[j], b1 = lw.b1(x);
    return {lw.b0, b1, par ? -(t2(x) - lw.b0 * pw0 - b1 * pw1) : 0.0};
  }
  [[gnu::always_inline]] Eigen::Vector3d ug(Eigen::Index K) const {
    const double x = r.xg[K], b1 = lg.b1(x);
    return {lg.b0, b1, par ? t2(x) - lg.b0 * pg0 - b1 * pg1 : 0.0};
  }
  // Pitch (its unknown is θ·h): about its mean, and the parabola's slope about its mean.
  [[gnu::always_inline]] Eigen::Vector3d ut(Eigen::Index K) const {
    return {1.0 / (h * static_cast<double>(mt)), par ? lin(r.xt[K]) - lin_mean : 0.0, 0.0};
  }
  // V's row of point i of a profile (zero beyond the profile's grid) into out[0..Cols), with the
  // parabola's and the pitch's columns cphi and ct (−1: none). The least-squares solve's callback
  // passes them as compile-time constants, so its rows are indexed by constants only.
  template <int Cols>
  [[gnu::always_inline]] void v_into(Design::Kind kind, Eigen::Index i, int cphi, int ct,
                                     double* out) const {
#pragma GCC unroll 8
    for (int j = 0; j < Cols; ++j) out[j] = 0.0;
    switch (kind) {
      case Design::Kind::w:
        if (i >= 0 && i < mw) {
          out[kW0] = lw.b0;
          out[kW0 + 1] = lw.b1(r.xw[i]);
        }
        break;
      case Design::Kind::g:
        if (i >= 0 && i < mg) {
          out[kG0] = lg.b0;
          out[kG0 + 1] = lg.b1(r.xg[i]);
          if (cphi >= 0) out[cphi] = phi(r.xg[i]);
        }
        break;
      case Design::Kind::t:
        if (ct >= 0 && i >= 0 && i < mt) out[ct] = 1.0;
        break;
      default:
        break;
    }
  }
  // The same rows as whole vectors, as sums of unit rows: v_into's store at a run-time column
  // followed by the row's vector loads stalled each time (a load cannot take its data from a
  // narrower store still in flight). Each entry is the same number (x·1 + 0).
  static Row unit(int c) {
    return c >= 0 ? Row(Row::Unit(c)) : Row(Row::Zero());
  }
  Row e_w0, e_w1, e_g0, e_g1, e_phi, e_t;  // set once the columns are known
  [[gnu::always_inline]] Row vw(Eigen::Index j) const {
    if (j < 0 || j >= mw) return Row::Zero();
    return lw.b0 * e_w0 + lw.b1(r.xw[j]) * e_w1;
  }
  [[gnu::always_inline]] Row vg(Eigen::Index K) const {
    if (K < 0 || K >= mg) return Row::Zero();
    const double x = r.xg[K];
    return lg.b0 * e_g0 + lg.b1(x) * e_g1 + (kPhi >= 0 ? phi(x) : 0.0) * e_phi;
  }
  [[gnu::always_inline]] Row vt(Eigen::Index K) const {
    return kT >= 0 && K >= 0 && K < mt ? e_t : Row(Row::Zero());
  }

  // V's guide and pitch rows' share of VᵀV, as the least-squares solve takes it (see
  // BandedLsq::solve_normal_rows): Σ v_g·v_gᵀ, Σ v_g·v_θᵀ (the same station's) and Σ v_θ·v_θᵀ over
  // every guide and pitch point, three Cols × Cols blocks, row-major, with the parabola's and the
  // pitch's columns cphi and ct (−1: none). A guide row is [b0, b1(x), φ(x)] in its columns, a
  // pitch row a 1 in ct: the sums are moments of the guide's grid, in one vectorised pass.
  template <int Cols>
  std::array<double, 3 * Cols * Cols> local_gram(int cphi, int ct) const {
    const Eigen::Index mgt = ct >= 0 ? std::min(mg, mt) : 0;  // stations with both rows
    const double* x = r.xg.data();
    const bool with_phi = cphi >= 0;
    double s1 = 0, s11 = 0, sp = 0, s1p = 0, spp = 0, c1 = 0, cp = 0;
#pragma omp simd reduction(+ : s1, s11, sp, s1p, spp, c1, cp)
    for (Eigen::Index K = 0; K < mg; ++K) {
      const double b1 = lg.b1(x[K]), phi = with_phi ? this->phi(x[K]) : 0.0;
      const double both = K < mgt ? 1.0 : 0.0;
      s1 += b1;
      s11 += b1 * b1;
      sp += phi;
      s1p += b1 * phi;
      spp += phi * phi;
      c1 += both * b1;
      cp += both * phi;
    }
    std::array<double, 3 * Cols * Cols> out{};
    auto at = [&](int block, int a, int b) -> double& {
      return out[static_cast<std::size_t>(block * Cols * Cols + a * Cols + b)];
    };
    const double b0 = lg.b0;
    auto sym = [&](int a, int b, double v) { at(0, a, b) = at(0, b, a) = v; };
    sym(kG0, kG0, b0 * b0 * static_cast<double>(mg));
    sym(kG0, kG0 + 1, b0 * s1);
    sym(kG0 + 1, kG0 + 1, s11);
    if (with_phi) {
      sym(kG0, cphi, b0 * sp);
      sym(kG0 + 1, cphi, s1p);
      sym(cphi, cphi, spp);
    }
    if (ct >= 0) {
      at(1, kG0, ct) = b0 * static_cast<double>(mgt);
      at(1, kG0 + 1, ct) = c1;
      if (with_phi) at(1, cphi, ct) = cp;
      at(2, ct, ct) = static_cast<double>(mt);
    }
    return out;
  }

  // VᵀZV restricted to a profile's columns (padding columns have zero U).
  static Eigen::Matrix3d restrict(const Eigen::MatrixXd& VZV, const Cols& c) {
    Eigen::Matrix3d S;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        S(a, b) = VZV(c[static_cast<std::size_t>(a)], c[static_cast<std::size_t>(b)]);
    return S;
  }

  // The standard uncertainty √(noise_var·var(y_i)), var(y_i) (unit weight) from Z_uu (`zd`) and
  // the row (ZV)_u (`zv`, all k columns; null when x_u is pinned, which then also ignores zd).
  // Inlined, with u·S·u written out (Eigen's dot stayed a call in the least-squares solve's loop),
  // so that constant columns c index zv by constants. Without Root, the variance
  // max(0, var(y_i))·noise_var instead (its square root taken later, four at a time).
  template <bool Root = true>
  [[gnu::always_inline]] static double point_uncertainty(const Eigen::Vector3d& u, const Cols& c,
                                                         const Eigen::Matrix3d& S, double zd,
                                                         const double* zv, double scale,
                                                         double noise_var) {
    double v = 0;
    for (int a = 0; a < 3; ++a) v += u[a] * (S(a, 0) * u[0] + S(a, 1) * u[1] + S(a, 2) * u[2]);
    if (zv) {
      const double uz = u[0] * zv[c[0]] + u[1] * zv[c[1]] + u[2] * zv[c[2]];
      v += scale * scale * zd - 2 * scale * uz;
    }
    if constexpr (Root)
      return std::sqrt(std::max(0.0, v) * noise_var);
    else
      return std::max(0.0, v) * noise_var;
  }
};

// The standard uncertainties from the variances that point_uncertainty<false> wrote, four per
// instruction, half of each profile on each core for long profiles: in the propagation's loops
// each scalar root held up the instructions after it for its latency (~20 cycles), two or three
// per station.
void take_square_roots(Eigen::VectorXd& uw, Eigen::VectorXd& ug, Eigen::VectorXd& ut) {
  auto roots = [](Eigen::VectorXd& u, Eigen::Index begin, Eigen::Index end) {
    u.segment(begin, end - begin) = u.segment(begin, end - begin).cwiseSqrt();
  };
  if (ug.size() < kTwoCorePoints) {  // a thread would cost more than it saves
    roots(uw, 0, uw.size());
    roots(ug, 0, ug.size());
    roots(ut, 0, ut.size());
    return;
  }
  detail::at_once(
      [&] {
        roots(uw, 0, uw.size() / 2);
        roots(ug, 0, ug.size() / 2);
        roots(ut, 0, ut.size() / 2);
      },
      [&] {
        roots(uw, uw.size() / 2, uw.size());
        roots(ug, ug.size() / 2, ug.size());
        roots(ut, ut.size() / 2, ut.size());
      });
}

// Sizes the three profiles' uncertainties uw, ug, ut to mw, mg, mt points, their storage asked
// for in huge pages, and starts committing their pages on another core, after those of `first`
// (a propagation's own work array) if given. The returned helper must outlive the writes' start.
detail::Prefault results_committed(Eigen::Index mw, Eigen::Index mg, Eigen::Index mt,
                                   Eigen::VectorXd& uw, Eigen::VectorXd& ug, Eigen::VectorXd& ut,
                                   std::optional<detail::Prefault::Region> first = {}) {
  trueaxis::detail::resize_in_huge_pages(uw, mw, 1);
  trueaxis::detail::resize_in_huge_pages(ug, mg, 1);
  trueaxis::detail::resize_in_huge_pages(ut, mt, 1);
  std::vector<detail::Prefault::Region> regions;
  if (first) regions.push_back(*first);
  for (const Eigen::VectorXd* v : {&uw, &ug, &ut})
    regions.push_back({v->data(), sizeof(double) * static_cast<std::size_t>(v->size())});
  return detail::Prefault(std::move(regions));
}

// Standard uncertainties (for noise variance noise_var per row) of the reported w, g, θ under
// the ls reference from the least-squares covariance Z = (AᵀA)⁻¹, on the lsq grids.
void lsq_uncertainties(LsqState& st, const Raw& r, bool with_pitch, double noise_var,
                       Eigen::VectorXd& uw, Eigen::VectorXd& ug, Eigen::VectorXd& ut) {
  const Design& D = st.D;
  // The results are written by the solve's backward pass on both cores. Their pages are committed
  // by another core from here on, while the reference algebra's sums below use only this one.
  const detail::Prefault prefault = results_committed(
      r.xw.size(), r.xg.size(), ReferenceAlgebra::pitch_points(r.xt.size(), with_pitch, D.pitch),
      uw, ug, ut);
  const ReferenceAlgebra ra(r, with_pitch, D.pitch, st.h);
  const int k = ra.k;
  // Each reported point's variance is u·S·u + s²·Z_uu − 2s·u·(ZV)_u (see point_uncertainty), with
  // S = VᵀZV. S comes from the solve's forward rows (their Gram matrix) and is complete before
  // the backward solve hands out (ZV)_u and Z_uu row by row (the selected inversion runs
  // alongside), so each point's variance is written once, as its row arrives, and its square
  // root taken in one vectorised pass at the end. Pinned unknowns have no Z_uu and no (ZV)_u:
  // their variance is u·S·u alone, set after the solve.
  using Kind = Design::Kind;
  // VᵀZV restricted to each profile's columns: workpiece, guide, pitch.
  std::array<Eigen::Matrix3d, 3> S;
  const double inv_h = 1.0 / st.h;  // the pitch unknown is θ·h
  // The column count and the parabola's and pitch's columns (−1: none) as compile-time
  // constants: the rows of V and ZV are then indexed by constants only and stay in registers in
  // the solve's loops (which inline both callbacks, each called up to three times per station).
  auto solve = [&]<int Cols, int KPhi, int KT>() {
    // ReferenceAlgebra's cw, cg, ct as constants (the padding column's u is 0).
    constexpr int phi = KPhi >= 0 ? KPhi : 0;
    static constexpr ReferenceAlgebra::Cols cw{ReferenceAlgebra::kW0, ReferenceAlgebra::kW0 + 1,
                                               phi};
    static constexpr ReferenceAlgebra::Cols cg{ReferenceAlgebra::kG0, ReferenceAlgebra::kG0 + 1,
                                               phi};
    static constexpr ReferenceAlgebra::Cols ct{KT >= 0 ? KT : 0, phi, 0};
    Eigen::Matrix<double, Cols, Cols, Eigen::RowMajor> gram;
    gram.setZero();
    // The guide's and pitch's rows' share of the Gram matrix from their moments, when every one
    // of those unknowns is free (make_design pins only workpiece points and offsets).
    const bool locals_free = std::none_of(D.pins.begin(), D.pins.end(), [&](const auto& pin) {
      const Kind kind = D.place(pin.first).kind;
      return kind == Kind::g || kind == Kind::t;
    });
    const auto local_vv = ra.local_gram<Cols>(KPhi, KT);
    // A point's uncertainty from its Z_uu and row of ZV (null for a pinned unknown).
    auto use = [&](int id, const double* zv, double zuu) __attribute__((always_inline)) {
      const auto [kind, i] = D.place(id);
      switch (kind) {
        case Kind::w:
          uw[i] = ReferenceAlgebra::point_uncertainty<false>(ra.uw(i), cw, S[0], zuu, zv, 1.0,
                                                             noise_var);
          break;
        case Kind::g:
          ug[i] = ReferenceAlgebra::point_uncertainty<false>(ra.ug(i), cg, S[1], zuu, zv, 1.0,
                                                             noise_var);
          break;
        case Kind::t:
          if constexpr (KT >= 0)
            if (i < ra.mt)
              ut[i] = ReferenceAlgebra::point_uncertainty<false>(ra.ut(i), ct, S[2], zuu, zv, inv_h,
                                                                 noise_var);
          break;
        default:
          break;  // an offset: no row of V
      }
    };
    st.engine->solve_normal_rows<Cols>(
        [&](int id, double* out) __attribute__((always_inline)) {
          const auto [kind, i] = D.place(id);
          ra.v_into<Cols>(kind, i, KPhi, KT, out);
        },
        use, gram.data(),
        [&] {
          Eigen::Matrix<double, ReferenceAlgebra::kMaxCols, ReferenceAlgebra::kMaxCols> VZV;
          VZV.setZero();
          VZV.template topLeftCorner<Cols, Cols>() = gram;
          S[0] = ReferenceAlgebra::restrict(VZV.topLeftCorner(k, k), ra.cw);
          S[1] = ReferenceAlgebra::restrict(VZV.topLeftCorner(k, k), ra.cg);
          S[2] = ReferenceAlgebra::restrict(VZV.topLeftCorner(k, k), ra.ct);
        },
        locals_free ? local_vv.data() : nullptr);
    for (const auto& pin : D.pins) use(pin.first, nullptr, 0.0);
  };
  // ReferenceAlgebra numbers its columns 0–3 for the lines, then the parabola's, then the
  // pitch's: k and the two columns follow from which of the two there are.
  if (ra.kPhi >= 0 && ra.kT >= 0)
    solve.template operator()<6, 4, 5>();
  else if (ra.kPhi >= 0)
    solve.template operator()<5, 4, -1>();
  else if (ra.kT >= 0)
    solve.template operator()<5, -1, 4>();
  else
    solve.template operator()<4, -1, -1>();
  take_square_roots(uw, ug, ut);
}

// Σ z·zᵀ over the adjoint vectors z of a propagation (k ≤ kMaxCols entries each), summed a block
// of z at a time: a 6 × 6 outer product per z loaded and stored all of the sum for 36
// multiply-adds, which dominated the adjoint pass.
class GramSum {
 public:
  using Row = ReferenceAlgebra::Row;
  explicit GramSum(int k) : k_(k) { G_.setZero(); }
  void add(const Row& z) {
    zs_.col(zn_++) = z;
    if (zn_ == kBlock) flush();
  }
  // The sum restricted to a profile's columns.
  Eigen::Matrix3d restricted(const ReferenceAlgebra::Cols& c) {
    flush();
    return ReferenceAlgebra::restrict(G_.topLeftCorner(k_, k_), c);
  }

 private:
  static constexpr int kBlock = 192;
  // The k·(k+1)/2 distinct entries, as dot products of contiguous rows. Out of line: inlined into
  // the two-point propagation's loop it made that loop 38 % slower.
  [[gnu::noinline]] void flush() {
    if (zn_ == 0) return;
    // Each dot product as four independent sums over the block's quarters: one sum was a chain
    // of dependent vector additions (latency, not throughput, bound).
    const int q = zn_ / 4;
    for (int i = 0; i < k_; ++i)
      for (int j = 0; j <= i; ++j) {
        const double* a = zs_.row(i).data();
        const double* b = zs_.row(j).data();
        double a0 = 0, a1 = 0, a2 = 0, a3 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3)
        for (int c = 0; c < q; ++c) {
          a0 += a[c] * b[c];
          a1 += a[c + q] * b[c + q];
          a2 += a[c + 2 * q] * b[c + 2 * q];
          a3 += a[c + 3 * q] * b[c + 3 * q];
        }
        for (int c = 4 * q; c < zn_; ++c) a0 += a[c] * b[c];
        const double acc = (a0 + a1) + (a2 + a3);
        G_(i, j) += acc;
        if (j != i) G_(j, i) += acc;
      }
    zn_ = 0;
  }
  int k_;
  int zn_ = 0;
  Eigen::Matrix<double, ReferenceAlgebra::kMaxCols, ReferenceAlgebra::kMaxCols> G_;
  Eigen::Matrix<double, ReferenceAlgebra::kMaxCols, kBlock, Eigen::RowMajor> zs_;
};

// Standard uncertainties (for noise variance noise_var per reading) of the two- and three-point
// results by exact propagation of every reading through the recurrence. T, the map from readings
// to the raw unknowns, is taken with the gauge X_0 = X_1 = 0 and without the first-reading
// offsets: it differs from the method's own map only by lines (and, for three-point, a parabola)
// that the reference removes, so the reported values, and their variances, are the same.
// Z = T·Tᵀ:
// - diag(Z) in closed form (sums of squared integer coefficients);
// - ZV = T·(TᵀV): the adjoint recurrence backwards, then the recurrence forwards, k columns at
//   once; VᵀZV = (TᵀV)ᵀ(TᵀV), the Gram matrix of the adjoint vectors, is summed in the backward
//   pass.
// O(n·k) work and one n × k array, where the least-squares covariance needs a banded
// factorisation, a selected inversion and a solve over all 3n unknowns.
void recurrence_uncertainties(const ProbeData& d, Method method, const Raw& r, bool with_pitch,
                              double noise_var, Eigen::VectorXd& uw, Eigen::VectorXd& ug,
                              Eigen::VectorXd& ut) {
  using Row = ReferenceAlgebra::Row;
  const long n = d.x.size();
  const ReferenceAlgebra ra(r, with_pitch, true, d.step());
  GramSum gram(ra.k);
  // The adjoint state per station (written from the last station back, every entry before it is
  // read) and the variances, their pages committed on another core meanwhile.
  std::vector<Row, Eigen::aligned_allocator<Row>> back(
      static_cast<std::size_t>(method == Method::TwoPoint ? n + 1 : std::max<long>(n - 2, 0)));
  const detail::Prefault prefault =
      results_committed(ra.mw, ra.mg, ra.mt, uw, ug, ut,
                        detail::Prefault::Region{back.data(), sizeof(Row) * back.size()});

  if (method == Method::TwoPoint) {
    // w_0 = 0, w_{K+1} = w_K + B_K − A_K (K < n); g_K = A_K − w_K. Var w_j = 2j, var g_K = 1 + 2K.
    // Adjoint: w̄_j = vw_j − vg_j + w̄_{j+1}; z_B[K] = w̄_{K+1}, z_A[K] = vg_K − w̄_{K+1}.
    Row wb = Row::Zero();
    for (long j = n; j >= 1; --j) {
      wb += ra.vw(j) - ra.vg(j);
      back[static_cast<std::size_t>(j)] = wb;
      gram.add(wb);                 // z_B[j − 1]
      gram.add(ra.vg(j - 1) - wb);  // z_A[j − 1]
    }
    const Eigen::Matrix3d Sw = gram.restricted(ra.cw), Sg = gram.restricted(ra.cg);
    Row Y = Row::Zero();  // (T z) at w_j
    for (long j = 0; j <= n; ++j) {
      uw[j] = ReferenceAlgebra::point_uncertainty<false>(
          ra.uw(j), ra.cw, Sw, 2.0 * static_cast<double>(j), Y.data(), 1.0, noise_var);
      if (j == n) break;
      const Row zB = back[static_cast<std::size_t>(j + 1)];
      const Row zA = ra.vg(j) - zB;
      const Row gz = zA - Y;
      ug[j] = ReferenceAlgebra::point_uncertainty<false>(
          ra.ug(j), ra.cg, Sg, 1.0 + 2.0 * static_cast<double>(j), gz.data(), 1.0, noise_var);
      Y += zB - zA;
    }
    take_square_roots(uw, ug, ut);
    return;
  }

  // Three-point: X_0 = X_1 = 0, X_{K+2} = 2X_{K+1} − X_K + r_K with
  // r_K = −2A_{K+1} + A_{K+2} + 2B_K − C_K; w_K = A_K − X_K, g_K = X_K and the pitch unknown
  // (θ·h) t_K = B_K − A_{K+1} + X_{K+1} − X_K.
  // Adjoint: X̄_K = λ_K + 2X̄_{K+1} − X̄_{K+2} (K ≥ 2) with λ_K = −vw_K + vg_K + vt_{K−1} − vt_K;
  // r̄_K = X̄_{K+2}; z_A[i] = vw_i − vt_{i−1} − 2r̄_{i−1} + r̄_{i−2}, z_B[i] = vt_i + 2r̄_i,
  // z_C[i] = −r̄_i.
  // back holds r̄_0..r̄_{n−3}.
  auto rb = [&](long K) -> Row {
    return K >= 0 && K + 2 < n ? back[static_cast<std::size_t>(K)] : Row(Row::Zero());
  };
  auto zA = [&](long i) -> Row { return ra.vw(i) - ra.vt(i - 1) - 2 * rb(i - 1) + rb(i - 2); };
  auto zB = [&](long i) -> Row { return ra.vt(i) + 2 * rb(i); };
  {
    // Each z is summed into the Gram matrix as soon as the r̄ it needs are known: z_B and z_C at
    // K − 2 with r̄_{K−2}, z_A at K with r̄_{K−1} and r̄_{K−2}; the first two z_A and the last
    // two z_B (no r̄ of their own) after the loop.
    Row x1 = Row::Zero(), x2 = Row::Zero();  // X̄_{K+1} = r̄_{K−1}, X̄_{K+2}
    for (long K = n - 1; K >= 2; --K) {
      const Row x = ra.vg(K) - ra.vw(K) + ra.vt(K - 1) - ra.vt(K) + 2 * x1 - x2;
      back[static_cast<std::size_t>(K - 2)] = x;
      gram.add(ra.vt(K - 2) + 2 * x);  // z_B[K − 2]
      gram.add(x);                     // z_C[K − 2] = −r̄: sign irrelevant here
      gram.add(ra.vw(K) - ra.vt(K - 1) - 2 * x1 + x);  // z_A[K]
      x2 = x1;
      x1 = x;
    }
    for (long i : {0L, 1L}) gram.add(zA(i));
    for (long i : {n - 2, n - 1}) gram.add(zB(i));
  }
  const Eigen::Matrix3d Sw = gram.restricted(ra.cw), Sg = gram.restricted(ra.cg),
                        St = ra.pitch ? gram.restricted(ra.ct) : Eigen::Matrix3d::Zero();
  // Var X_K = the sum of its squared reading coefficients: B_j 2(K−1−j) and C_j −(K−1−j)
  // (j ≤ K−2), A_1 −2(K−1), A_i −(K−1−i) (2 ≤ i ≤ K), for K ≥ 2. Var w_K = var X_K − 1 (the
  // coefficient of A_K in X_K is 1), var t_K = 6K + 4 (K ≥ 1).
  auto s2 = [](double m) { return m * (m + 1) * (2 * m + 1) / 6; };
  auto var_x = [&](long K) {
    if (K < 2) return 0.0;
    const double q = static_cast<double>(K);
    return 5 * s2(q - 1) + 1 + s2(q - 3) + 4 * (q - 1) * (q - 1);
  };
  Row y0 = Row::Zero(), y1 = Row::Zero();  // (T z) at X_K, X_{K+1}
  Row a0 = zA(0), a1 = zA(1);              // z_A[K], z_A[K+1]
  for (long K = 0; K < n; ++K) {
    const Row a2 = zA(K + 2);
    const Row w = a0 - y0;
    uw[K] = ReferenceAlgebra::point_uncertainty<false>(
        ra.uw(K), ra.cw, Sw, K < 2 ? 1.0 : var_x(K) - 1, w.data(), 1.0, noise_var);
    ug[K] = ReferenceAlgebra::point_uncertainty<false>(ra.ug(K), ra.cg, Sg, var_x(K), y0.data(),
                                                       1.0, noise_var);
    const Row b = zB(K);
    if (K < ra.mt) {
      const Row t = b - a1 + y1 - y0;
      ut[K] = ReferenceAlgebra::point_uncertainty<false>(
          ra.ut(K), ra.ct, St, K == 0 ? 2.0 : 6.0 * static_cast<double>(K) + 4, t.data(),
          1.0 / ra.h, noise_var);
    }
    const Row y2 = K + 2 < n ? Row(2 * y1 - y0 - 2 * a1 + a2 + 2 * b + rb(K)) : Row(Row::Zero());
    y0 = y1;
    y1 = y2;
    a0 = a1;
    a1 = a2;
  }
  take_square_roots(uw, ug, ut);
}

// Standard uncertainties (for noise variance noise_var per reading) of the least-squares results
// of the layout without redundancy (solve_lsq_direct), on its grids, by exact propagation of
// every reading as recurrence_uncertainties does. With the gauge w_0 = w_1 = 0, β = 0 and zero
// offsets (the reference removes the difference, as there) the map T from the readings a, b, c of
// probes A, B, C to the raw unknowns is
//   w_{K+2} = 2w_{K+1} − w_K + a_K − 2b_K + c_K,  g_K = a_K − w_K,  t_K = b_K − a_K − w_{K+1} + w_K
// (t the pitch unknown θ·h). Adjoint: X_K = W̄_{K+2} = λ_{K+2} + 2X_{K+1} − X_{K+2} (from
// X_n = X_{n+1} = 0) with λ_j = vw_j − vg_j + vt_j − vt_{j−1}; the adjoint vectors are
// z_a[K] = P_K + X_K, z_b[K] = vt_K − 2X_K and z_c[K] = X_K (P = vg − vt), so that
//   VᵀZV = Σ z·zᵀ = Σ (P·Pᵀ + vt·vtᵀ) + Σ (Q·Xᵀ + X·Qᵀ) + 6·Σ X·Xᵀ,  Q = vg − 3vt,
// and (ZV) = T·(TᵀV) runs forwards as y_{K+2} = 2y_{K+1} − y_K + Q_K + 6X_K (y_0 = y_1 = 0),
// the row of w_K being y_K. Diagonal: var w_j = (j − 1)·j·(2j − 1), var g_K = 1 + var w_K,
// var t_K = 2 + 6K. It uses the grids only (not the readings): the solve can run meanwhile.
//
// Each of V's columns is its own recurrence, and every station's variance is independent once the
// recurrences have reached it: the stations are taken in blocks that fit the first-level cache,
// one array per column. Per block, the recurrences run station by station (two additions per
// column and station, as X_K − X_{K+1} and y_{K+1} − y_K are sums), and everything else (V's
// entries, the Gram sums, the variances and their square roots) runs across stations, four at a
// time. The backward pass keeps only each block's starting state; the forward pass runs the
// block's backward recurrence again from it (the same code on the same numbers, so the same X)
// instead of keeping an n × k array of adjoint vectors.
template <bool Par, bool Pitch>
class DirectPropagation {
 public:
  static constexpr int kW0 = ReferenceAlgebra::kW0, kW1 = kW0 + 1, kG0 = ReferenceAlgebra::kG0,
                       kG1 = kG0 + 1, kPhi = Par ? 4 : -1, kT = Pitch ? 4 + Par : -1,
                       kCols = 4 + Par + Pitch, kBlock = 256;
  // The block's columns after X's: ones, the guide's line slope b1(x_K) and φ(x_K).
  static constexpr int kOnes = kCols, kB1 = kCols + 1, kPhiX = kCols + 2;

  DirectPropagation(const ReferenceAlgebra& ra, double h)
      : ra_(ra), n_(ra.mg), xg_(ra.r.xg.data()), h_(h) {
    for (int i = 0; i < kBlock; ++i) {
      m_[kOnes][i] = 1.0;
      m_[kPhiX][i] = 0.0;  // without the parabola
    }
    if (ra.kPhi != kPhi || ra.kT != kT || ra.mw != n_ + 2 || (Pitch && ra.mt != n_))
      throw std::logic_error("direct propagation: grids or columns do not match the layout");
  }

  void run(double noise_var, Eigen::VectorXd& uw, Eigen::VectorXd& ug, Eigen::VectorXd& ut) {
    const long blocks = (n_ + kBlock - 1) / kBlock;
    std::vector<State> starts(static_cast<std::size_t>(blocks));
    // Backward: the adjoint, block by block from the last station, and the Gram sums.
    State s;
    Sums sums;
    for (long b = blocks - 1; b >= 0; --b) {
      const long lo = b * kBlock;
      const int len = static_cast<int>(std::min<long>(kBlock, n_ - lo));
      starts[static_cast<std::size_t>(b)] = s;
      lambda(lo, len);
      backward(s, len);
      guide_entries(lo, len);
      sums.add(m_, len);
    }
    gram(sums);
    // Forward: y, and every station's variances.
    std::array<double, kCols> y{}, dy{};  // y_K and y_{K+1} − y_K
    double* __restrict pw = uw.data();
    double* __restrict pg = ug.data();
    double* __restrict pt = Pitch ? ut.data() : nullptr;
    for (long b = 0; b < blocks; ++b) {
      const long lo = b * kBlock;
      const int len = static_cast<int>(std::min<long>(kBlock, n_ - lo));
      State x0 = starts[static_cast<std::size_t>(b)];
      lambda(lo, len);
      backward(x0, len);
      guide_entries(lo, len);
      forward(y, dy, len);
      variances(lo, len, noise_var, pw, pg, pt);
    }
    // The two workpiece points beyond the last station: y_n and y_{n+1}.
    ReferenceAlgebra::Row yn = ReferenceAlgebra::Row::Zero();
    for (long j : {n_, n_ + 1}) {
      for (int c = 0; c < kCols; ++c) yn[c] = j == n_ ? y[c] : y[c] + dy[c];
      const double q = static_cast<double>(j);
      uw[j] = ReferenceAlgebra::point_uncertainty(ra_.uw(j), ra_.cw, sw_, (q - 1) * q * (2 * q - 1),
                                                  yn.data(), 1.0, noise_var);
    }
  }

 private:
  struct State {
    std::array<double, kCols> x{}, d{};  // X_K and X_K − X_{K+1} at a block's end
  };
  // Σ X·Xᵀ, Σ X, Σ X·b1(x) and Σ X·φ(x) over the stations (X·Qᵀ's parts): each of X's columns
  // against the block's [X, 1, b1, φ], all kCols + 3 sums in one pass over the block (a general
  // matrix product spent more time packing these small blocks than multiplying).
  struct Sums {
    static constexpr int kM = kCols + 3;
    Eigen::Matrix<double, kCols, kM> xm = Eigen::Matrix<double, kCols, kM>::Zero();
    // Named accumulators: an array reduction was summed in order, one lane at a time.
    void add(const double (&m)[kM][kBlock], int len) {
      static_assert(kM >= 7 && kM <= 9);
      for (int c = 0; c < kCols; ++c) {
        const double* a = m[c];
        double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, s5 = 0, s6 = 0, s7 = 0, s8 = 0;
#pragma omp simd reduction(+ : s0, s1, s2, s3, s4, s5, s6, s7, s8)
        for (int i = 0; i < len; ++i) {
          const double v = a[i];
          s0 += v * m[0][i];
          s1 += v * m[1][i];
          s2 += v * m[2][i];
          s3 += v * m[3][i];
          s4 += v * m[4][i];
          s5 += v * m[5][i];
          s6 += v * m[6][i];
          if constexpr (kM > 7) s7 += v * m[7][i];
          if constexpr (kM > 8) s8 += v * m[8][i];
        }
        const double sum[] = {s0, s1, s2, s3, s4, s5, s6, s7, s8};
        for (int d = 0; d < kM; ++d) xm(c, d) += sum[d];
      }
    }
  };

  // λ_{K+2} of every column for the block's stations K = lo … lo + len − 1, into m_. The guide's
  // rows end at station n − 1; the pitch's part is a single −1, at K + 2 = mt.
  void lambda(long lo, int len) {
    const int inside = static_cast<int>(std::clamp<long>(n_ - 2 - lo, 0, len));
    const double* xg = xg_ + lo + 2;
    const double bw = ra_.lw.b0, bg = ra_.lg.b0, base = static_cast<double>(lo + 2);
#pragma omp simd
    for (int i = 0; i < len; ++i) {
      m_[kW0][i] = bw;
      m_[kW1][i] = ra_.lw.b1(workpiece_x(base + static_cast<double>(i)));
    }
#pragma omp simd
    for (int i = 0; i < inside; ++i) {
      m_[kG0][i] = -bg;
      m_[kG1][i] = -ra_.lg.b1(xg[i]);
      if constexpr (Par) m_[kPhi][i] = -ra_.phi(xg[i]);
      if constexpr (Pitch) m_[kT][i] = 0.0;
    }
    for (int i = inside; i < len; ++i)
      for (int c = kG0; c < kCols; ++c) m_[c][i] = 0.0;
    if constexpr (Pitch)
      if (const long spike = ra_.mt - 2 - lo; spike >= 0 && spike < len) m_[kT][spike] = -1.0;
  }
  // X_K = X_{K+1} + (X_K − X_{K+1}) and X_K − X_{K+1} = λ_{K+2} + (X_{K+1} − X_{K+2}), over the
  // block from its last station back, λ replaced by X in m_.
  void backward(State& s, int len) {
    std::array<double, kCols> x = s.x, d = s.d;
    for (int i = len - 1; i >= 0; --i) {
#pragma GCC unroll 8
      for (int c = 0; c < kCols; ++c) {
        d[c] += m_[c][i];
        x[c] += d[c];
        m_[c][i] = x[c];
      }
    }
    s.x = x;
    s.d = d;
  }
  // The guide's line slope b1(x_K) and φ(x_K) at the block's stations.
  void guide_entries(long lo, int len) {
    const double* xg = xg_ + lo;
#pragma omp simd
    for (int i = 0; i < len; ++i) {
      m_[kB1][i] = ra_.lg.b1(xg[i]);
      if constexpr (Par) m_[kPhiX][i] = ra_.phi(xg[i]);
    }
  }
  // VᵀZV from the sums, and its restrictions to the three profiles' columns.
  void gram(const Sums& sums) {
    const auto local = ra_.local_gram<kCols>(kPhi, kT);  // Σ vg·vgᵀ, Σ vg·vtᵀ, Σ vt·vtᵀ
    Eigen::MatrixXd G(kCols, kCols);
    for (int a = 0; a < kCols; ++a)
      for (int b = 0; b < kCols; ++b) {
        auto at = [&](int block, int i, int j) {
          return local[static_cast<std::size_t>(block * kCols * kCols + i * kCols + j)];
        };
        G(a, b) = at(0, a, b) - at(1, a, b) - at(1, b, a) + 2 * at(2, a, b) + 6 * sums.xm(a, b);
      }
    // Q·Xᵀ + X·Qᵀ with Q = (b0, b1(x), φ(x), −3) in the guide's, parabola's and pitch's columns.
    auto add_q = [&](int q, int sum, double scale) {
      for (int c = 0; c < kCols; ++c) {
        G(q, c) += scale * sums.xm(c, sum);
        G(c, q) += scale * sums.xm(c, sum);
      }
    };
    add_q(kG0, kOnes, ra_.lg.b0);
    add_q(kG1, kB1, 1.0);
    if constexpr (Par) add_q(kPhi, kPhiX, 1.0);
    if constexpr (Pitch) add_q(kT, kOnes, -3.0);
    sw_ = ReferenceAlgebra::restrict(G, ra_.cw);
    sg_ = ReferenceAlgebra::restrict(G, ra_.cg);
    if constexpr (Pitch) st_ = ReferenceAlgebra::restrict(G, ra_.ct);
  }
  // y_K for the block's stations and the one after (y_{K+1} − y_K = previous + Q_K + 6X_K).
  void forward(std::array<double, kCols>& y, std::array<double, kCols>& dy, int len) {
    const double bg = ra_.lg.b0;
    for (int i = 0; i < len; ++i) {
#pragma GCC unroll 8
      for (int c = 0; c < kCols; ++c) {
        double q = 0.0;
        if (c == kG0) q = bg;
        if (c == kG1) q = m_[kB1][i];
        if (c == kPhi) q = m_[kPhiX][i];
        if (c == kT) q = -3.0;
        y_[c][i] = y[c];
        y[c] += dy[c];
        dy[c] += q + 6 * m_[c][i];
      }
    }
    for (int c = 0; c < kCols; ++c) y_[c][len] = y[c];
  }
  // The block's standard uncertainties: u·S·u + scale²·var − 2·scale·u·(ZV)_u for each profile
  // (see ReferenceAlgebra::point_uncertainty), written out across stations.
  void variances(long lo, int len, double noise_var, double* __restrict pw, double* __restrict pg,
                 double* __restrict pt) const {
    const ReferenceAlgebra& ra = ra_;
    const Eigen::Matrix3d &Sw = sw_, &Sg = sg_, &St = st_;
    const double w00 = Sw(0, 0), w01 = Sw(0, 1), w02 = Sw(0, 2), w11 = Sw(1, 1), w12 = Sw(1, 2),
                 w22 = Sw(2, 2);
    const double g00 = Sg(0, 0), g01 = Sg(0, 1), g02 = Sg(0, 2), g11 = Sg(1, 1), g12 = Sg(1, 2),
                 g22 = Sg(2, 2);
    const double t00 = St(0, 0), t01 = St(0, 1), t11 = St(1, 1);
    auto quad = [](double a, double b, double c, double s00, double s01, double s02, double s11,
                   double s12, double s22) {
      return a * (s00 * a + 2 * (s01 * b + s02 * c)) + b * (s11 * b + 2 * s12 * c) + c * s22 * c;
    };
    const double bw = ra.lw.b0, bg = ra.lg.b0, inv_h = 1 / h_;
    const double tu0 = Pitch ? 1.0 / (h_ * static_cast<double>(ra.mt)) : 0.0;
    const double* xg = xg_ + lo;
    const double base = static_cast<double>(lo);
    double *w = pw + lo, *g = pg + lo, *t = Pitch ? pt + lo : nullptr;
#pragma omp simd
    for (int i = 0; i < len; ++i) {
      const double q = base + static_cast<double>(i);
      const double var_w = (q - 1) * q * (2 * q - 1);
      // Workpiece point K: its row of ZV is y_K.
      const double xw = workpiece_x(q);
      const double u1 = ra.lw.b1(xw);
      const double u2 = Par ? -(ra.t2(xw) - bw * ra.pw0 - u1 * ra.pw1) : 0.0;
      double uy = bw * y_[kW0][i] + u1 * y_[kW1][i];
      if constexpr (Par) uy += u2 * y_[kPhi][i];
      const double vw = quad(bw, u1, u2, w00, w01, w02, w11, w12, w22) + var_w - 2 * uy;
      w[i] = std::max(0.0, vw) * noise_var;
      // Guide point K: z_a[K] − y_K.
      const double g1 = m_[kB1][i];
      const double g2 = Par ? ra.t2(xg[i]) - bg * ra.pg0 - g1 * ra.pg1 : 0.0;
      double gz = bg * (bg + m_[kG0][i] - y_[kG0][i]) + g1 * (g1 + m_[kG1][i] - y_[kG1][i]);
      if constexpr (Par) gz += g2 * (m_[kPhiX][i] + m_[kPhi][i] - y_[kPhi][i]);
      const double vg = quad(bg, g1, g2, g00, g01, g02, g11, g12, g22) + 1 + var_w - 2 * gz;
      g[i] = std::max(0.0, vg) * noise_var;
      // Pitch at K: z_b[K] − z_a[K] − y_{K+1} + y_K.
      if constexpr (Pitch) {
        const double tu1 = Par ? ra.lin(xg[i]) - ra.lin_mean : 0.0;
        double tz = tu0 * (2 - 3 * m_[kT][i] - y_[kT][i + 1] + y_[kT][i]);
        if constexpr (Par)
          tz += tu1 * (-m_[kPhiX][i] - 3 * m_[kPhi][i] - y_[kPhi][i + 1] + y_[kPhi][i]);
        const double vt = tu0 * (t00 * tu0 + 2 * t01 * tu1) + tu1 * t11 * tu1 +
                          inv_h * inv_h * (2 + 6 * q) - 2 * inv_h * tz;
        t[i] = std::max(0.0, vt) * noise_var;
      }
    }
    // The square roots, four per instruction (std::sqrt in the loop above kept it scalar).
    auto roots = [len](double* v) {
      Eigen::Map<Eigen::ArrayXd> a(v, len);
      a = a.sqrt();
    };
    roots(w);
    roots(g);
    if constexpr (Pitch) roots(t);
  }

  double workpiece_x(double j) const {
    return workpiece_position(xg_[0], j, h_);
  }

  const ReferenceAlgebra& ra_;
  const long n_;
  const double* xg_;
  const double h_;
  Eigen::Matrix3d sw_, sg_, st_ = Eigen::Matrix3d::Zero();
  // The block's columns: λ, then X, and the columns kOnes, kB1, kPhiX; y (one station more).
  alignas(64) double m_[kCols + 3][kBlock];
  alignas(64) double y_[kCols][kBlock + 1];
};

// x: the stations; parabola_free: as solve_lsq_direct's (no known zero difference).
void direct_uncertainties(const Eigen::VectorXd& x, bool parabola_free, bool with_pitch, double h,
                          double noise_var, Eigen::VectorXd& uw, Eigen::VectorXd& ug,
                          Eigen::VectorXd& ut) {
  // The guide's and pitch's grids are the stations themselves; only the workpiece's is made.
  const Eigen::Index n = x.size();
  Eigen::VectorXd xw;
  trueaxis::detail::resize_in_huge_pages(xw, n + 2, 1);
  for (Eigen::Index j = 0; j < n + 2; ++j)
    xw[j] = workpiece_position(x[0], static_cast<double>(j), h);
  using View = GridViews::View;
  const GridViews grids{View(xw.data(), xw.size()), View(x.data(), n),
                        View(x.data(), with_pitch ? n : 0), parabola_free,
                        true};  // increasing: used only once the values are checked
  const ReferenceAlgebra ra(grids, with_pitch, true, h);
  // The variances' pages are committed on another core while the backward pass runs.
  const detail::Prefault prefault = results_committed(ra.mw, ra.mg, ra.mt, uw, ug, ut);
  auto go = [&]<bool Par, bool Pitch>() {
    auto p = std::make_unique<DirectPropagation<Par, Pitch>>(ra, h);
    p->run(noise_var, uw, ug, ut);
  };
  if (ra.par && ra.pitch)
    go.template operator()<true, true>();
  else if (ra.par)
    go.template operator()<true, false>();
  else if (ra.pitch)
    go.template operator()<false, true>();
  else
    go.template operator()<false, false>();
}

// `ls`: the least-squares straightness when already known (not NaN). x is one of separate()'s
// grids, strictly increasing by construction from the checked stations.
Straightness straightness_of(const Eigen::VectorXd& x, const Eigen::VectorXd& v, double ls) {
  return {std::isnan(ls) ? geometry::ls_straightness(x, v) : ls,
          geometry::detail::min_zone_of_increasing(x, v).width};
}

}  // namespace

Result detail::separate(const ProbeData& data, const Options& opt, LsqSolver solver) {
  // A recurrence's arrays are known in size from the start: their pages are committed on another
  // core while the data are checked and the recurrence runs.
  Raw raw;
  std::optional<detail::Prefault> prefault;
  if (opt.method != Method::Lsq) {
    raw = recurrence_arrays(opt.method, data.x.size());
    prefault.emplace(regions_of(raw));
  }
  check_shapes(data);
  const long n = data.x.size();
  // The values (finite, evenly stepped: one pass over all the data) are checked on another core
  // while the offsets, the layout and the method go on. Their error, if any, is the one reported,
  // as if they had been checked first, and nothing computed from the data is used before.
  std::future<void> values =
      std::async(n >= kTwoCorePoints ? std::launch::async : std::launch::deferred,
                 [&data] { check_values(data); });
  bool values_known = false;
  auto values_first = [&] {  // rethrows the values' error, once
    if (values_known) return;
    values_known = true;
    values.get();
  };
  Result res;
  res.method = opt.method;
  res.reference = opt.reference;
  const double h = data.step();
  const bool angle = data.angle.size() == n;
  std::vector<long> p;
  // The least-squares solve gives the Lsq answer and its covariance. The recurrences (A, B)
  // propagate each reading exactly through their own equations. Without redundancy (A, B) the
  // noise level cannot be estimated, so their uncertainty needs a given sigma.
  const bool unc_possible =
      opt.compute_uncertainty && opt.filter_cutoff == 0 && opt.reference != Reference::Seed;
  LsqState st;
  try {
    check_offsets(data);
    // Offsets of an absurd number of steps can only come from a broken x (which the values check
    // reports): nothing is sized by them before that check has answered.
    constexpr double kAbsurdSteps = 2147483647.0;
    for (double s : data.offsets)
      if (!(std::abs(s / h) <= kAbsurdSteps)) values_first();
    opt.validate();
    for (double s : data.offsets) p.push_back(std::lround(s / h));
    // The layout must be observable (beyond line and, by convention, parabola) for every method.
    const LayoutAnalysis la = analyze_layout(p, angle, opt.zero_difference.has_value(), n);
    if (!la.observable) throw Error(la.message);
    res.unobservable = la.unobservable;
    switch (opt.method) {
      case Method::TwoPoint:
        two_point(data, raw);
        break;
      case Method::ThreePoint:
        three_point(data, opt.zero_difference, raw);
        break;
      case Method::Lsq:
        if (solver == detail::LsqSolver::Automatic && detail::direct_layout(p, angle)) {
          // Its uncertainties need the grids only, and a noise level that only a given sigma can
          // set (no redundancy): they are propagated on another core while the solve runs.
          if (unc_possible) {
            const bool with_pitch = opt.sigma.has_value();
            const double noise_var = with_pitch ? *opt.sigma * *opt.sigma : 1.0;
            st.propagation = std::async(
                n >= kTwoCorePoints ? std::launch::async : std::launch::deferred,
                [&st, &data, h, with_pitch, noise_var, par = !opt.zero_difference] {
                  direct_uncertainties(data.x, par, with_pitch, h, noise_var, st.uw, st.ug, st.ut);
                });
          }
          raw = solve_lsq_direct(data, opt);
        } else {
          raw = solve_lsq(data, opt, st);
        }
        break;
    }
  } catch (...) {
    values_first();  // the values' error first
    throw;
  }
  values_first();
  raw.xg_increasing = true;  // every method's guide grid is the stations, now checked
  const bool want_unc = unc_possible && (opt.method == Method::Lsq || opt.sigma.has_value());
  res.dof = st.engine ? st.dof : 0;

  LsWidths widths;  // NaN unless the reference found them
  if (opt.reference == Reference::Seed) {
    res.gauge =
        "patent (JPH0464003B2): X_0 = Y_0 = 0, alpha = X_1 and beta = 2Y_1 - Y_2 minimise sum of "
        "X_K^2 (K >= 2); "
        "pitch relative to the first station";
    if (opt.zero_difference) res.gauge += "; beta from the known zero difference";
  } else {
    widths = apply_reference(raw, opt.reference);
    res.gauge = opt.reference == Reference::MinZone
                    ? "workpiece and guide relative to the middle lines of their minimum zones"
                    : "workpiece and guide are residuals from their own least-squares lines";
    if (raw.theta.size()) res.gauge += "; pitch about its mean";
    if (raw.parabola_free)
      res.gauge += "; parabola: the guide is taken to have no quadratic (least-squares) component";
    else if (opt.zero_difference)
      res.gauge += "; parabola fixed by the known zero difference";
    else if (angle)
      res.gauge += "; parabola fixed by the angle channel";
  }

  Eigen::VectorXd uw, ug, ut;
  if (unc_possible) {
    double s2 = 0;
    if (want_unc && opt.sigma) {
      s2 = (*opt.sigma) * (*opt.sigma);
      res.sigma = opt.sigma;
    } else if (want_unc && st.dof > 0) {
      // Every row (probe, or angle scaled by its weight) carries the probe noise, so the
      // residual variance estimates the probe variance directly.
      s2 = st.ssr / static_cast<double>(st.dof);
      res.sigma = std::sqrt(s2);
      res.sigma_estimated = true;
    }
    // Standard uncertainties; without a noise level, those for unit noise.
    const double noise_var = res.sigma ? s2 : 1.0;
    if (st.propagation.valid()) {  // the direct solve's, launched with it
      st.propagation.get();
      uw = std::move(st.uw);
      ug = std::move(st.ug);
      ut = std::move(st.ut);
    } else if (opt.method == Method::Lsq)
      lsq_uncertainties(st, raw, res.sigma.has_value(), noise_var, uw, ug, ut);
    else
      recurrence_uncertainties(data, opt.method, raw, res.sigma.has_value(), noise_var, uw, ug, ut);
    if (!res.sigma) {
      // No noise level: state no uncertainty, only how strongly the layout amplifies noise.
      res.noise_gain = std::max(uw.maxCoeff(), ug.maxCoeff());
      uw.resize(0);
      ug.resize(0);
      ut.resize(0);
    }
  }
  if (st.engine && st.dof > 0)
    res.residual_rms = std::sqrt(st.ssr / static_cast<double>(st.engine->rows()));

  if (opt.filter_cutoff > 0) {
    raw.w = geometry::gaussian_filter(raw.w, h, opt.filter_cutoff);
    raw.g = geometry::gaussian_filter(raw.g, h, opt.filter_cutoff);
    widths = {};  // the filtered profiles' own
  }
  {
    // The two minimum zones are independent: the guide's on another core for long profiles.
    auto guide =
        std::async(policy_for(raw), [&] { return straightness_of(raw.xg, raw.g, widths.g); });
    res.workpiece_straightness = straightness_of(raw.xw, raw.w, widths.w);
    res.guide_straightness = guide.get();
  }
  res.workpiece = {std::move(raw.xw), std::move(raw.w), std::move(uw)};
  res.guide = {std::move(raw.xg), std::move(raw.g), std::move(ug)};
  if (raw.theta.size()) res.pitch = Profile{std::move(raw.xt), std::move(raw.theta), std::move(ut)};
  return res;
}

Result separate(const ProbeData& data, const Options& opt) {
  return detail::separate(data, opt, detail::LsqSolver::Automatic);
}

void express_in_reference(Profile& workpiece, Profile& guide, Profile* pitch, Reference reference,
                          bool parabola_free) {
  if (reference == Reference::Seed)
    throw Error("express_in_reference: the patent reference depends on the readings");
  Raw r;
  r.xw = workpiece.x;
  r.w = workpiece.value;
  r.xg = guide.x;
  r.g = guide.value;
  if (pitch) {
    r.xt = pitch->x;
    r.theta = pitch->value;
  }
  r.parabola_free = parabola_free;
  apply_reference(r, reference);
  workpiece.value = r.w;
  guide.value = r.g;
  if (pitch) pitch->value = r.theta;
}

std::vector<std::string> Result::warnings() const {
  std::vector<std::string> w;
  const auto check = [&](const char* what, const Profile& p, const Straightness& st) {
    if (p.uncertainty.size() == 0 || !p.uncertainty.allFinite()) return;
    const double expanded = 2 * p.uncertainty.maxCoeff();
    if (!(expanded > st.ls)) return;
    w.push_back(fmt::format(
        "the {} straightness {:.3g} um is smaller than its own expanded uncertainty (k = 2, up "
        "to {:.3g} um): this probe layout cannot resolve it. Use more probes, an angle channel "
        "(--angle), a known zero difference, or --method lsq with redundant probes",
        what, st.ls * 1e3, expanded * 1e3));
  };
  check("workpiece", workpiece, workpiece_straightness);
  check("guide", guide, guide_straightness);
  if (workpiece.uncertainty.size() == 0 && noise_gain && std::isfinite(*noise_gain) &&
      *noise_gain > 0) {
    const double st = std::min(workpiece_straightness.ls, guide_straightness.ls);
    w.push_back(fmt::format(
        "no uncertainty is stated: without redundant readings the probe noise cannot be "
        "estimated. This layout multiplies probe noise by up to {:.3g} along the profiles, so "
        "probe noise above {:.2g} um (standard deviation) would hide a straightness of {:.3g} um. "
        "Give --sigma UM (the probes' noise) for uncertainties, or use more probes or an angle "
        "channel",
        *noise_gain, st / (2 * *noise_gain) * 1e3, st * 1e3));
  }
  return w;
}

std::string Result::summary() const {
  std::string s = fmt::format("method {}, reference {}\n", to_string(method), to_string(reference));
  s += fmt::format("  workpiece straightness: {:.4f} um (LS), {:.4f} um (min-zone), {} points\n",
                   workpiece_straightness.ls * 1e3, workpiece_straightness.min_zone * 1e3,
                   workpiece.x.size());
  s += fmt::format("  guide straightness:     {:.4f} um (LS), {:.4f} um (min-zone), {} stations\n",
                   guide_straightness.ls * 1e3, guide_straightness.min_zone * 1e3, guide.x.size());
  if (pitch && pitch->value.size())
    s += fmt::format("  pitch range:            {:.4f} urad\n",
                     (pitch->value.maxCoeff() - pitch->value.minCoeff()) * 1e6);
  if (workpiece.uncertainty.size())
    s += fmt::format(
        "  max standard uncertainty: workpiece {:.4f} um, guide {:.4f} um (sigma {:.4f} um{})\n",
        workpiece.uncertainty.maxCoeff() * 1e3, guide.uncertainty.maxCoeff() * 1e3,
        sigma.value_or(0) * 1e3, sigma_estimated ? ", estimated from residuals" : "");
  std::string u;
  for (const auto& m : unobservable) u += (u.empty() ? "" : ", ") + m;
  s += fmt::format("  unobservable: {}\n  gauge: {}\n", u, gauge);
  return s;
}

}  // namespace trueaxis::separation
