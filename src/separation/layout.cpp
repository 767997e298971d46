// The least-squares design of straightness separation (which unknowns, which are pinned to fix
// the gauge freedoms) and the observability of a probe layout: the rank of that design over a
// stretch of stations long enough to show every mode, with the unobservable modes named (chains
// of stations no reading ties together, blind harmonics, edge modes).
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "../common/eigen_instances.hpp"
#include "design.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/separation/separation.hpp"

namespace trueaxis::separation {
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
  // The rank from a column-pivoted QR (Golub & Van Loan, "Matrix Computations", 4th ed.,
  // §5.4.2): its pivots |R_ii| decrease, and each null mode of the layout leaves one at round-off,
  // far below the threshold. An SVD gives the same count at several times the cost (JacobiSVD:
  // 47 ms against 6 ms at 200 unknowns).
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::VectorXd pivots = qr.matrixQR().diagonal().cwiseAbs();
  const double tol = 1e-9 * std::max(1.0, pivots.size() ? pivots[0] : 1.0);
  long rank = 0;
  for (Eigen::Index i = 0; i < pivots.size(); ++i)
    if (pivots[i] > tol) ++rank;
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

}  // namespace trueaxis::separation
