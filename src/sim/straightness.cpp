#include "trueaxis/sim/straightness.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "common.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::sim {

void StraightnessOptions::validate() const {
  if (stations < 3) throw Error(fmt::format("stations must be at least 3 (got {})", stations));
  if (!(step > 0 && std::isfinite(step))) throw Error("step must be positive");
  if (offsets.size() < 2) throw Error("need at least two probe offsets");
  if (offsets[0] != 0) throw Error("the first probe offset must be 0");
  for (double s : offsets) {
    const double r = s / step;
    if (!std::isfinite(r) || std::abs(r - std::round(r)) > 1e-9 * std::max(1.0, std::abs(r)))
      throw Error(
          fmt::format("probe offset {} mm is not a whole multiple of the step {} mm", s, step));
  }
  for (double v : {workpiece_amplitude, guide_amplitude, pitch_amplitude, offset_amplitude, noise,
                   angle_noise})
    if (!(v >= 0 && std::isfinite(v))) throw Error("amplitudes and noise must be >= 0");
}

StraightnessCampaign simulate_straightness(const StraightnessOptions& o) {
  o.validate();
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::normal_distribution<double> Nd(0.0, 1.0);
  const double h = o.step;
  const long n = o.stations;
  const detail::ProbeGrid grid(o.offsets, h, n);
  const std::vector<long>& p = grid.steps;
  const long pmin = grid.pmin, Q = grid.points;
  const double L = grid.length;
  const double xs = o.x0 + static_cast<double>(pmin) * h;  // first position

  // Smooth parts as sums of sinusoids with random wavelength/phase.
  using detail::eval_waves;
  const auto w_waves = detail::random_waves(rng, 4, o.workpiece_amplitude, L, 0.08, 1.2);
  const auto g_waves = detail::random_waves(rng, 2, 0.5 * o.guide_amplitude, L, 0.2, 1.5);
  const double g_bow = o.guide_amplitude * (U(rng) < 0.5 ? -1 : 1) * (0.5 + 0.5 * U(rng));
  const auto t_waves = detail::random_waves(rng, 2, o.pitch_amplitude, L, 0.15, 1.0);
  const double t_drift = o.pitch_amplitude * (2 * U(rng) - 1);

  StraightnessCampaign c;
  StraightnessTruth& T = c.truth;
  T.first_station_index = -pmin;
  T.step = h;
  T.x.resize(Q);
  T.workpiece.resize(Q);
  T.guide.resize(Q);
  T.pitch.resize(Q);
  const double tex = 0.2 * o.workpiece_amplitude / std::sqrt(static_cast<double>(Q));
  double walk = 0;
  for (long q = 0; q < Q; ++q) {
    const double x = xs + static_cast<double>(q) * h;
    const double u = x - xs;
    const double t = 2 * u / std::max(L, 1e-12) - 1;  // -1..1
    walk += tex * Nd(rng);
    T.x[q] = x;
    T.workpiece[q] = eval_waves(w_waves, u) + walk;
    T.guide[q] = g_bow * (t * t - 1.0 / 3.0) + eval_waves(g_waves, u);
    T.pitch[q] = t_drift * t + eval_waves(t_waves, u);
  }
  separation::ProbeData& d = c.data;
  detail::start_probe_data(rng, o.offsets, n, o.offset_amplitude, o.angle, T, d);
  for (long K = 0; K < n; ++K) {
    const long qs = K - pmin;
    d.x[K] = o.x0 + static_cast<double>(K) * h;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double s = static_cast<double>(p[i]) * h;
      d.readings(K, static_cast<Eigen::Index>(i)) = T.workpiece[qs + p[i]] + T.guide[qs] +
                                                    s * T.pitch[qs] + T.probe_offsets[i] +
                                                    o.noise * Nd(rng);
    }
    if (o.angle) d.angle[K] = T.pitch[qs] + T.angle_offset + o.angle_noise * Nd(rng);
  }
  return c;
}

Eigen::VectorXd StraightnessTruth::sample(const Eigen::VectorXd& at,
                                          const Eigen::VectorXd& values) const {
  Eigen::VectorXd out(at.size());
  for (Eigen::Index i = 0; i < at.size(); ++i) {
    const double r = (at[i] - x[0]) / step;
    const long q = std::lround(r);
    if (q < 0 || q >= values.size() || std::abs(r - static_cast<double>(q)) > 1e-6)
      throw Error(fmt::format("position {} mm is not on the truth grid", at[i]));
    out[i] = values[q];
  }
  return out;
}

separation::Result StraightnessTruth::like(const separation::Result& r,
                                           std::optional<bool> parabola_free) const {
  const bool par = parabola_free.value_or(
      std::find(r.unobservable.begin(), r.unobservable.end(), "parabola") != r.unobservable.end());
  separation::Result t = r;
  t.workpiece = {r.workpiece.x, sample(r.workpiece.x, workpiece), {}};
  t.guide = {r.guide.x, sample(r.guide.x, guide), {}};
  if (r.pitch) t.pitch = separation::Profile{r.pitch->x, sample(r.pitch->x, pitch), {}};
  const auto ref = r.reference == separation::Reference::Seed ? separation::Reference::LeastSquares
                                                              : r.reference;
  separation::express_in_reference(t.workpiece, t.guide, t.pitch ? &*t.pitch : nullptr, ref, par);
  return t;
}

}  // namespace trueaxis::sim
