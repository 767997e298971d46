// Private: the least-squares design of straightness separation (unknown numbering, pins), shared
// by the solver, its uncertainty propagation and the layout analysis.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "../common/memory.hpp"
#include "trueaxis/separation/separation.hpp"

namespace trueaxis::separation::detail {

// Unknowns, all in mm: w (workpiece at positions 0..Q-1, position j at x_0 + (j + pmin)·h), g
// (guide at the n stations), θ·h (pitch times the step, when modelled), the probe zero offsets
// o_i and, with an angle channel, its offset. Some are pinned to fix the gauge freedoms.
struct Design {
  long n = 0;           // stations
  int N = 0;            // probes
  std::vector<long> p;  // offsets in steps (p[0] = 0)
  std::vector<long> q;  // p - pmin: position index offsets (>= 0)
  long span = 0;        // max q
  long Q = 0;           // number of workpiece positions: n + span
  bool pitch = false;   // θ modelled (>= 3 probes or angle channel)
  bool angle = false;
  bool parabola_free = false;  // parabola fixed by a pin + the guide-quadratic gauge afterwards
  double wa = 0;               // weight of angle rows (relative to probe rows)
  int nvars = 0;
  // per unknown (3n + … bytes: aligned and in huge pages, like the solver's buffers)
  std::vector<char, trueaxis::detail::HugePageAllocator<char>> pinned;
  std::vector<std::pair<int, double>> pins;  // the few pinned unknowns and their values

  double pin_value(int id) const {
    for (const auto& [i, value] : pins)
      if (i == id) return value;
    return 0.0;
  }

  int w(long pos) const { return static_cast<int>(pos); }
  int g(long K) const { return static_cast<int>(Q + K); }
  int t(long K) const { return static_cast<int>(Q + n + K); }  // θ scaled by h (mm)
  int o(int i) const { return static_cast<int>(Q + n * (pitch ? 2 : 1) + i); }
  int oa() const { return o(N); }
  // Which unknowns an id is among (workpiece, guide, pitch, offsets) and its index there.
  enum class Kind { w, g, t, o };
  struct Place {
    Kind kind;
    long i;
  };
  Place place(int id) const {
    if (id < g(0)) return {Kind::w, id - w(0)};
    if (id < (pitch ? t(0) : o(0))) return {Kind::g, id - g(0)};
    if (id < o(0)) return {Kind::t, id - t(0)};
    return {Kind::o, id - o(0)};
  }
};

// Weights of the zero difference e = Σ z_i·o_i of a three-probe layout: z_A = 1 and z annihilates
// constants and the offsets (for 0, l, 2l: z = 1, −2, 1).
Eigen::Vector3d zero_difference_weights(const std::vector<long>& p);

// The design for offsets p (in steps), n stations, with or without an angle channel whose rows
// carry weight wa; pins the line, the offsets' gauge and (without a zero difference or angle
// channel) the parabola. Throws Error if a zero difference cannot be used with this layout.
Design make_design(const std::vector<long>& p, long n, bool angle, std::optional<double> zero_diff,
                   double wa);

// Which least-squares solver separate() may use: the direct solve of a layout without redundancy
// where it applies (Automatic), or always the banded factorisation (Banded; tests compare the two).
enum class LsqSolver { Automatic, Banded };
Result separate(const ProbeData& data, const Options& opt, LsqSolver solver);

// Whether Automatic solves offsets p (in steps), with or without an angle channel, directly: the
// layouts without redundancy whose least-squares solution is the exact one (three probes at 0, 1
// and 2 steps, no angle channel).
bool direct_layout(const std::vector<long>& p, bool angle);

// Rows of station K: probes then angle. Coefficients on free ids; pinned values moved to rhs.
template <class Emit>
void station_rows(const Design& D, long K, const double* m, double angle_mm, Emit&& emit) {
  // At most four unknowns per row (w, g, theta, offset); a fixed buffer, no allocation.
  std::array<std::pair<int, double>, 4> buf;
  std::size_t used = 0;
  auto add = [&](int id, double v, double& rhs) {
    if (D.pinned[static_cast<std::size_t>(id)])
      rhs -= v * D.pin_value(id);
    else
      buf[used++] = {id, v};
  };
  const auto c = [&] { return std::span<const std::pair<int, double>>(buf.data(), used); };
  for (int i = 0; i < D.N; ++i) {
    used = 0;
    double rhs = m ? m[i] : 0.0;
    add(D.w(K + D.q[static_cast<std::size_t>(i)]), 1.0, rhs);
    add(D.g(K), 1.0, rhs);
    if (D.pitch && D.p[static_cast<std::size_t>(i)] != 0)
      add(D.t(K), static_cast<double>(D.p[static_cast<std::size_t>(i)]), rhs);
    add(D.o(i), 1.0, rhs);
    emit(c(), rhs);
  }
  if (D.angle) {
    used = 0;
    double rhs = D.wa * angle_mm;
    add(D.t(K), D.wa, rhs);
    add(D.oa(), D.wa, rhs);
    emit(c(), rhs);
  }
}

}  // namespace trueaxis::separation::detail
