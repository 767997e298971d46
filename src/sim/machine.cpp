#include "trueaxis/sim/machine.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "../io/fast_text.hpp"
#include "common.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::sim {
namespace {

constexpr const char* kAxes = "XYZ";
constexpr const char* kComponents = "XYZABC";
// reference_lines: the angle asin(d_a · d_b) between reference lines, signed as the squareness
// parameters act (positive EC0Y leans Y towards −X, EB0Z leans Z towards +X, EA0Z leans Z towards
// −Y).
constexpr double kSquarenessSign[3] = {-1, 1, -1};  // c0y, b0z, a0z

bool finite(double v) {
  return std::isfinite(v);
}

// Polynomial coefficients (in v = u / 1000) of Σ_k a_k ξ^k with ξ = (u − mid) / half.
std::vector<double> centred_to_metres(const std::vector<double>& a, double mid, double half) {
  // ξ = α v + β with α = 1000 / half, β = −mid / half. Expand by repeated multiplication.
  const double alpha = 1000.0 / half, beta = -mid / half;
  std::vector<double> out(a.size(), 0.0), power{1.0};  // power = coefficients of ξ^k in v
  for (std::size_t k = 0; k < a.size(); ++k) {
    for (std::size_t j = 0; j < power.size(); ++j) out[j] += a[k] * power[j];
    std::vector<double> next(power.size() + 1, 0.0);
    for (std::size_t j = 0; j < power.size(); ++j) {
      next[j] += beta * power[j];
      next[j + 1] += alpha * power[j];
    }
    power = std::move(next);
  }
  return out;
}

}  // namespace

double ErrorFunction::operator()(double u) const {
  double v = 0;
  const double m = u * 1e-3;
  for (auto it = polynomial.rbegin(); it != polynomial.rend(); ++it) v = v * m + *it;
  for (const Sine& s : sines) v += s.amplitude * std::sin(2 * M_PI * u / s.period + s.phase);
  if (!table_u.empty()) {
    const auto hi = std::upper_bound(table_u.begin(), table_u.end(), u);
    std::size_t j = static_cast<std::size_t>(hi - table_u.begin());
    j = std::clamp<std::size_t>(j, 1, table_u.size() - 1);
    const double t = (u - table_u[j - 1]) / (table_u[j] - table_u[j - 1]);
    v += table_value[j - 1] + t * (table_value[j] - table_value[j - 1]);
  }
  return v;
}

void ErrorFunction::validate(const std::string& what, double lo, double hi) const {
  for (double c : polynomial)
    if (!finite(c)) throw Error(what + ": polynomial coefficients must be finite");
  for (const Sine& s : sines) {
    if (!finite(s.amplitude) || !finite(s.phase))
      throw Error(what + ": sine amplitude and phase must be finite");
    if (!(s.period > 0 && finite(s.period)))
      throw Error(fmt::format("{}: sine period must be positive (got {})", what, s.period));
  }
  if (table_u.size() != table_value.size())
    throw Error(fmt::format("{}: table has {} positions but {} values", what, table_u.size(),
                            table_value.size()));
  if (table_u.empty()) return;
  if (table_u.size() < 2) throw Error(what + ": a table needs at least two nodes");
  for (std::size_t i = 0; i < table_u.size(); ++i) {
    if (!finite(table_u[i]) || !finite(table_value[i]))
      throw Error(fmt::format("{}: table entry {} is not finite", what, i));
    if (i > 0 && !(table_u[i] > table_u[i - 1]))
      throw Error(fmt::format("{}: table positions must increase strictly ({} after {})", what,
                              table_u[i], table_u[i - 1]));
  }
  if (table_u.front() > lo || table_u.back() < hi)
    throw Error(fmt::format("{}: table covers [{}, {}] mm but the axis range is [{}, {}] mm", what,
                            table_u.front(), table_u.back(), lo, hi));
}

std::string error_name(int axis, Component c) {
  return fmt::format("E{}{}", kComponents[static_cast<int>(c)], kAxes[axis]);
}

std::array<int, 3> Machine::order() const {
  std::array<int, 3> o{};
  int n = 0;
  for (char ch : chain) {
    if (ch == 'F') continue;
    const char* p = std::strchr(kAxes, ch);
    if (p == nullptr || *p == 0 || n == 3) throw Error(fmt::format("bad chain '{}'", chain));
    o[static_cast<std::size_t>(n++)] = static_cast<int>(p - kAxes);
  }
  return o;
}

void Machine::validate() const {
  const auto bad_chain = [&] {
    throw Error(fmt::format(
        "chain '{}' must list X, Y, Z once each and the frame F once, workpiece to tool (e.g. "
        "FYXZ for a bridge CMM, FXYZ or XFYZ for machine tools)",
        chain));
  };
  if (chain.size() != 4 || std::count(chain.begin(), chain.end(), 'F') != 1) bad_chain();
  for (char a : {'X', 'Y', 'Z'})
    if (std::count(chain.begin(), chain.end(), a) != 1) bad_chain();
  for (int k = 0; k < 3; ++k) {
    const auto& r = range[static_cast<std::size_t>(k)];
    if (!finite(r[0]) || !finite(r[1]) || !(r[1] > r[0]))
      throw Error(fmt::format("range of {} must be [min, max] with min < max (got [{}, {}])",
                              kAxes[k], r[0], r[1]));
    for (int c = 0; c < 6; ++c)
      errors[static_cast<std::size_t>(k)][static_cast<std::size_t>(c)].validate(
          error_name(k, static_cast<Component>(c)), r[0], r[1]);
  }
  if (!offset.allFinite()) throw Error("the stylus/tool offset must be finite");
  for (double s : {squareness_c0y, squareness_b0z, squareness_a0z})
    if (!finite(s) || std::abs(s) > 0.1) throw Error("squareness errors must be finite and small");
}

bool Machine::contains(const Eigen::Vector3d& c, double tol) const {
  for (int k = 0; k < 3; ++k)
    if (!(c[k] >= range[static_cast<std::size_t>(k)][0] - tol &&
          c[k] <= range[static_cast<std::size_t>(k)][1] + tol))
      return false;
  return true;
}

Eigen::Isometry3d Machine::pose(const Eigen::Vector3d& c) const {
  const Eigen::Vector3d d[3] = {
      Eigen::Vector3d::UnitX(),
      Eigen::AngleAxisd(squareness_c0y, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d::UnitY(),
      Eigen::AngleAxisd(squareness_a0z, Eigen::Vector3d::UnitX()) *
          (Eigen::AngleAxisd(squareness_b0z, Eigen::Vector3d::UnitY()) * Eigen::Vector3d::UnitZ())};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int k : order()) {
    const auto& e = errors[static_cast<std::size_t>(k)];
    const double u = c[k];
    Eigen::Isometry3d A = Eigen::Isometry3d::Identity();
    A.linear() = detail::rotation({e[3](u), e[4](u), e[5](u)});
    A.translation() = u * d[k] + Eigen::Vector3d(e[0](u), e[1](u), e[2](u));
    T = T * A;
  }
  return T;
}

Eigen::Matrix3Xd Machine::errors_at(const Eigen::Matrix3Xd& commands) const {
  Eigen::Matrix3Xd out(3, commands.cols());
  const auto n = static_cast<std::size_t>(commands.cols());
  // ~1 µs per point (18 error functions, 3 rotations): worth a thread from a few thousand on.
  io::detail::parallel_ranges(
      n, io::detail::workers_for(n * 16), [&](int, std::size_t b, std::size_t e) {
        for (auto i = static_cast<Eigen::Index>(b); i < static_cast<Eigen::Index>(e); ++i)
          out.col(i) = error(commands.col(i));
      });
  return out;
}

ReferenceLines reference_lines(const Machine& m, const Eigen::Vector3d& at, int samples) {
  if (samples < 3) throw Error("reference lines: at least 3 samples per axis");
  ReferenceLines out;
  for (int k = 0; k < 3; ++k) {
    const auto& r = m.range[static_cast<std::size_t>(k)];
    Eigen::Matrix3Xd c(3, samples);
    Eigen::VectorXd u(samples);
    for (int i = 0; i < samples; ++i) {
      u[i] = r[0] + (r[1] - r[0]) * i / (samples - 1.0);
      c.col(i) = at;
      c(k, i) = u[i];
    }
    // The actual tool point along the axis, less its nominal: a line fitted to the errors is the
    // reference line's departure from the axis direction (no cancellation against millimetres).
    const Eigen::Matrix3Xd e = m.errors_at(c);
    const double um = u.mean();
    const Eigen::VectorXd du = u.array() - um;
    const double suu = du.squaredNorm();
    Eigen::Vector3d slope, mean = e.rowwise().mean();
    for (int j = 0; j < 3; ++j) slope[j] = suu > 0 ? e.row(j).dot(du) / suu : 0.0;
    Eigen::Vector3d d = slope;
    d[k] += 1;
    out.direction[static_cast<std::size_t>(k)] = d.normalized();
    int across = 0;
    for (int j = 0; j < 3; ++j) {
      if (j == k) continue;
      double lo = 0, hi = 0;
      for (int i = 0; i < samples; ++i) {
        const double dev = e(j, i) - mean[j] - slope[j] * du[i];
        lo = i == 0 ? dev : std::min(lo, dev);
        hi = i == 0 ? dev : std::max(hi, dev);
      }
      out.straightness[static_cast<std::size_t>(k)][static_cast<std::size_t>(across++)] = hi - lo;
    }
  }
  // Out of squareness: the angle between two reference lines less 90°, asin of minus the
  // cosine; signs as the model's squareness parameters act (tests/sim/machine_test.cpp).
  auto angle = [&](int a, int b) {
    return std::asin(std::clamp(
        out.direction[static_cast<std::size_t>(a)].dot(out.direction[static_cast<std::size_t>(b)]),
        -1.0, 1.0));
  };
  out.c0y = kSquarenessSign[0] * angle(0, 1);
  out.b0z = kSquarenessSign[1] * angle(0, 2);
  out.a0z = kSquarenessSign[2] * angle(1, 2);
  return out;
}

std::string Machine::summary(const std::vector<std::string>& not_determined) const {
  std::string s =
      fmt::format("{} (chain {}, ranges x [{:g}, {:g}], y [{:g}, {:g}], z [{:g}, {:g}] mm)\n",
                  name.empty() ? "machine" : name, chain, range[0][0], range[0][1], range[1][0],
                  range[1][1], range[2][0], range[2][1]);
  // Straightness and squareness as ISO 230-1 defines them at the tool point, with the other
  // axes mid-range: about the reference lines, not the error functions' own slopes.
  Eigen::Vector3d mid;
  for (int k = 0; k < 3; ++k)
    mid[k] = (range[static_cast<std::size_t>(k)][0] + range[static_cast<std::size_t>(k)][1]) / 2;
  const ReferenceLines lines = reference_lines(*this, mid);
  s += "  span over the axis range   positioning  straightness (2)     roll/pitch/yaw (3)\n";
  for (int k = 0; k < 3; ++k) {
    const auto& r = range[static_cast<std::size_t>(k)];
    double span[6];
    for (int c = 0; c < 6; ++c) {
      const auto& f = errors[static_cast<std::size_t>(k)][static_cast<std::size_t>(c)];
      double lo = 0, hi = 0;
      for (int i = 0; i <= 200; ++i) {
        const double v = f(r[0] + (r[1] - r[0]) * i / 200.0);
        lo = i == 0 ? v : std::min(lo, v);
        hi = i == 0 ? v : std::max(hi, v);
      }
      span[c] = (hi - lo) * (c < 3 ? 1e3 : 1e6);
    }
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    span[std::min(a, b)] = lines.straightness[static_cast<std::size_t>(k)][0] * 1e3;
    span[std::max(a, b)] = lines.straightness[static_cast<std::size_t>(k)][1] * 1e3;
    auto cell = [&](int c, int width, int digits) {
      const std::string name = error_name(k, static_cast<Component>(c));
      for (const auto& n : not_determined)
        if (n == name) return fmt::format("{:>{}}", "n/d", width);
      return fmt::format("{:{}.{}f}", span[c], width, digits);
    };
    s += fmt::format("  {} axis                    {} µm    {} {} µm        {} {} {} µrad\n",
                     kAxes[k], cell(k, 6, 2), cell(std::min(a, b), 5, 2),
                     cell(std::max(a, b), 5, 2), cell(3, 5, 1), cell(4, 5, 1), cell(5, 5, 1));
  }
  if (!not_determined.empty())
    s += "  n/d: not determined by the data (no effect on these measurements)\n";
  s += "  straightness: range about the axis' reference line (ISO 230-1), at the tool point\n";
  s += fmt::format(
      "  squareness EC0Y {:.1f}, EB0Z {:.1f}, EA0Z {:.1f} µrad (angles between the reference "
      "lines, less 90 deg)\n",
      lines.c0y * 1e6, lines.b0z * 1e6, lines.a0z * 1e6);
  return s;
}

void MachineOptions::validate() const {
  Machine m;
  m.chain = chain;
  m.range = range;
  m.offset = offset;
  m.validate();
  for (double v : {straightness, angular, positioning, squareness, lead_amplitude})
    if (!(v >= 0 && finite(v))) throw Error("error magnitudes must be >= 0 and finite");
  if (!(lead > 0 && finite(lead))) throw Error("the lead-screw period must be positive");
}

Machine random_machine(const MachineOptions& o) {
  o.validate();
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::normal_distribution<double> N(0.0, 1.0);
  const auto sign = [&] { return U(rng) < 0.5 ? -1.0 : 1.0; };
  Machine m;
  m.name = fmt::format("random {} machine, seed {}", o.chain, o.seed);
  m.chain = o.chain;
  m.range = o.range;
  m.offset = o.offset;
  for (int k = 0; k < 3; ++k) {
    const double lo = o.range[static_cast<std::size_t>(k)][0];
    const double hi = o.range[static_cast<std::size_t>(k)][1];
    const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo), L = hi - lo;
    auto& e = m.errors[static_cast<std::size_t>(k)];
    // Positioning: a scale error from the axis' start (the home switch) and a small bow.
    {
      const double slope = o.positioning * N(rng);
      const double bow = 0.2 * o.positioning * half * N(rng);
      // slope·(u − lo) + bow·(ξ² − 1) with ξ = (u − mid)/half: zero at both ends for the bow.
      auto& f = e[static_cast<std::size_t>(k)];  // E_kk
      f.polynomial = centred_to_metres({slope * (mid - lo) - bow, slope * half, bow}, mid, half);
      if (o.lead_amplitude > 0)
        f.sines.push_back({o.lead_amplitude * (0.5 + 0.5 * U(rng)), o.lead, 2 * M_PI * U(rng)});
    }
    // Straightness across the axis: PV about `straightness` over 500 mm, growing like L^1.5
    // for longer axes (bow + cubic + one long wave).
    for (int c = 1; c <= 2; ++c) {
      const double s = o.straightness * std::pow(L / 500.0, 1.5);
      const double bow = 0.5 * s * sign() * (0.4 + 0.6 * U(rng));
      const double cubic = 0.2 * s * N(rng);
      const int comp = (k + c) % 3;  // the two directions across axis k
      auto& f = e[static_cast<std::size_t>(comp)];
      f.polynomial = centred_to_metres({-bow / 3, 0, bow, cubic}, mid, half);
      f.sines.push_back(
          {0.15 * s * (0.5 + 0.5 * U(rng)), L * (0.3 + 0.7 * U(rng)), 2 * M_PI * U(rng)});
    }
    // Angular: drift, bow and one wave, about `angular`.
    for (int c = 3; c < 6; ++c) {
      auto& f = e[static_cast<std::size_t>(c)];
      const double a = o.angular;
      f.polynomial = centred_to_metres({0, 0.6 * a * N(rng), 0.4 * a * N(rng)}, mid, half);
      f.sines.push_back(
          {0.3 * a * (0.5 + 0.5 * U(rng)), L * (0.25 + 0.75 * U(rng)), 2 * M_PI * U(rng)});
    }
  }
  m.squareness_c0y = o.squareness * N(rng);
  m.squareness_b0z = o.squareness * N(rng);
  m.squareness_a0z = o.squareness * N(rng);
  m.validate();
  return m;
}

void ProbeRunOptions::validate() const {
  if (stations < 3) throw Error(fmt::format("stations must be at least 3 (got {})", stations));
  if (!(step > 0 && finite(step))) throw Error("step must be positive");
  if (!start.allFinite()) throw Error("start must be finite");
  if (!(direction.allFinite() && direction.norm() > 0))
    throw Error("direction must be a non-zero vector");
  if (!(sensing.allFinite() && sensing.norm() > 0))
    throw Error("sensing direction must be a non-zero vector");
  if (std::abs(direction.normalized().dot(sensing.normalized())) > 1e-9)
    throw Error("the sensing direction must be perpendicular to the direction of motion");
  StraightnessOptions so;  // the probe layout rules are the straightness simulator's
  so.stations = stations;
  so.step = step;
  so.offsets = offsets;
  so.noise = noise;
  so.angle_noise = angle_noise;
  so.workpiece_amplitude = profile_amplitude;
  so.offset_amplitude = offset_amplitude;
  so.validate();
}

StraightnessCampaign simulate_probe_run(const Machine& m, const ProbeRunOptions& o) {
  m.validate();
  o.validate();
  const Eigen::Vector3d d = o.direction.normalized(), n = o.sensing.normalized();
  const double h = o.step;
  const long stations = o.stations;
  for (long K : {0L, stations - 1}) {
    const Eigen::Vector3d c = o.start + static_cast<double>(K) * h * d;
    if (!m.contains(c))
      throw Error(fmt::format("the run leaves the machine's range: stop {} at ({}, {}, {}) mm", K,
                              c.x(), c.y(), c.z()));
  }
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> Nd(0.0, 1.0);
  const detail::ProbeGrid grid(o.offsets, h, stations);
  const std::vector<long>& p = grid.steps;
  const long pmin = grid.pmin, Q = grid.points;
  const double L = grid.length;
  const double x0 = o.start.dot(d);
  const double xs = x0 + static_cast<double>(pmin) * h;

  const auto waves = detail::random_waves(rng, 4, o.profile_amplitude, L, 0.08, 1.2);
  StraightnessCampaign camp;
  StraightnessTruth& T = camp.truth;
  T.first_station_index = -pmin;
  T.step = h;
  T.x.resize(Q);
  T.workpiece.resize(Q);
  T.guide.setConstant(Q, std::numeric_limits<double>::quiet_NaN());
  T.pitch.setConstant(Q, std::numeric_limits<double>::quiet_NaN());
  for (long q = 0; q < Q; ++q) {
    T.x[q] = xs + static_cast<double>(q) * h;
    T.workpiece[q] = detail::eval_waves(waves, T.x[q] - xs);
  }
  separation::ProbeData& data = camp.data;
  detail::start_probe_data(rng, o.offsets, stations, o.offset_amplitude, o.angle, T, data);
  for (long K = 0; K < stations; ++K) {
    const long qs = K - pmin;
    const Eigen::Vector3d c = o.start + static_cast<double>(K) * h * d;
    const Eigen::Isometry3d P = m.pose(c);
    const Eigen::Vector3d nominal = c + m.offset;
    data.x[K] = x0 + static_cast<double>(K) * h;
    T.guide[qs] = n.dot(P * m.offset - nominal);
    T.pitch[qs] = n.dot(P.linear() * d);
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double s = static_cast<double>(p[i]) * h;
      // The probe's own actual tip, not the linearised g + s·θ: the readings are the simulator's.
      const double e = n.dot(P * (m.offset + s * d) - (nominal + s * d));
      data.readings(K, static_cast<Eigen::Index>(i)) =
          T.workpiece[qs + p[i]] + e + T.probe_offsets[i] + o.noise * Nd(rng);
    }
    if (o.angle) data.angle[K] = T.pitch[qs] + T.angle_offset + o.angle_noise * Nd(rng);
  }
  return camp;
}

Eigen::VectorXd simulate_laser_run(const Machine& m, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& direction, long stations, double step,
                                   double noise, std::uint64_t seed) {
  if (stations < 2) throw Error("a laser run needs at least two stops");
  if (!(step > 0) || !(direction.norm() > 0) || !(noise >= 0))
    throw Error("a laser run needs a positive step, a direction and a noise >= 0");
  const Eigen::Vector3d d = direction.normalized();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> Nd(0.0, 1.0);
  Eigen::VectorXd r(stations);
  double e0 = 0;
  for (long i = 0; i < stations; ++i) {
    const Eigen::Vector3d c = start + static_cast<double>(i) * step * d;
    if (!m.contains(c, 1e-6))
      throw Error(fmt::format("the laser run leaves the machine's range at ({}, {}, {}) mm", c.x(),
                              c.y(), c.z()));
    const double e = d.dot(m.error(c));
    if (i == 0) e0 = e;
    r[i] = e - e0 + noise * Nd(rng);
  }
  return r;
}

}  // namespace trueaxis::sim
