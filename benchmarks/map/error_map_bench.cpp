// Error-map hot paths at 10^7 points, with a same-run baseline: a plain copy of the same points
// (see BENCHMARKS.md).
#include <benchmark/benchmark.h>

#include <cstring>
#include <random>

#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/map/error_map.hpp"
#include "trueaxis/sim/ballgauge.hpp"

using namespace trueaxis;

namespace {

constexpr Eigen::Index kPoints = 10'000'000;

const map::ErrorMap& grid() {
  static const map::ErrorMap m = map::sample(
      {Eigen::VectorXd::LinSpaced(17, 0, 800), Eigen::VectorXd::LinSpaced(13, 0, 600),
       Eigen::VectorXd::LinSpaced(11, 0, 500)},
      [](const Eigen::Vector3d& p) {
        return Eigen::Vector3d(1e-2 * std::sin(p.x() / 300), 1e-2 * std::cos(p.y() / 250),
                               1e-2 * std::sin(p.z() / 200 + p.x() / 500));
      });
  return m;
}

const Eigen::Matrix3Xd& points() {
  static const Eigen::Matrix3Xd p = [] {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    Eigen::Matrix3Xd q(3, kPoints);
    for (Eigen::Index i = 0; i < kPoints; ++i) q.col(i) << 800 * U(rng), 600 * U(rng), 500 * U(rng);
    return q;
  }();
  return p;
}

// Baseline: copying the 240 MB of points once (what any batch pass must at least read and write).
void BM_Memcpy(benchmark::State& st) {
  const auto& p = points();
  Eigen::Matrix3Xd out(3, p.cols());
  for (auto _ : st) {
    std::memcpy(out.data(), p.data(), sizeof(double) * static_cast<std::size_t>(p.size()));
    benchmark::ClobberMemory();
  }
  st.SetItemsProcessed(st.iterations() * p.cols());
  st.SetBytesProcessed(st.iterations() * p.size() * 8);
}

void BM_Compensate(benchmark::State& st, map::Interpolation how, int iterations) {
  const auto& m = grid();
  const auto& p = points();
  Eigen::Matrix3Xd out(3, p.cols());
  map::CompensateOptions o;
  o.eval.interpolation = how;
  o.iterations = iterations;
  for (auto _ : st) {
    std::memcpy(out.data(), p.data(), sizeof(double) * static_cast<std::size_t>(p.size()));
    map::compensate(m, out, o);
    benchmark::ClobberMemory();
  }
  st.SetItemsProcessed(st.iterations() * p.cols());
}

// One timed pass: copy the input, correct it in place.
void time_correct(benchmark::State& st, const map::ErrorMap& m, const Eigen::Matrix3Xd& p) {
  Eigen::Matrix3Xd out(3, p.cols());
  for (auto _ : st) {
    std::memcpy(out.data(), p.data(), sizeof(double) * static_cast<std::size_t>(p.size()));
    map::correct(m, out);
    benchmark::ClobberMemory();
  }
  st.SetItemsProcessed(st.iterations() * p.cols());
}

// The ball-gauge map of Oya, Hokari and Tamura (1988): their 5 × 4 × 4 grid, calibrated on the
// virtual CMM from 0.5 µm-noise probing, so its axes are cluster means (not exactly uniform: the
// cell is guessed from the mean spacing and corrected), and 10^7 points spread over its 320 × 240 ×
// 240 mm box.
void BM_CorrectBallGauge(benchmark::State& st) {
  static const map::ErrorMap m = [] {
    const auto g = sim::frame_gauge();
    const auto poses = sim::stacked_poses(g, 3, {150, 120, 60});
    sim::BallGaugeOptions o;
    o.noise = 0.5e-3;
    sim::MachineOptions mo;
    mo.seed = 5;
    const auto c = sim::simulate_ballgauge(sim::random_machine(mo), g, poses, o);
    return *ballgauge::calibrate(g, c.placements).grid;
  }();
  static const Eigen::Matrix3Xd p = [] {
    std::mt19937_64 rng(2);
    Eigen::Matrix3Xd q(3, kPoints);
    std::uniform_real_distribution<double> U[3] = {
        std::uniform_real_distribution<double>(m.axes[0][0], m.axes[0][m.size(0) - 1]),
        std::uniform_real_distribution<double>(m.axes[1][0], m.axes[1][m.size(1) - 1]),
        std::uniform_real_distribution<double>(m.axes[2][0], m.axes[2][m.size(2) - 1])};
    for (Eigen::Index i = 0; i < kPoints; ++i) q.col(i) << U[0](rng), U[1](rng), U[2](rng);
    return q;
  }();
  time_correct(st, m, p);
}

void BM_Correct(benchmark::State& st) {
  time_correct(st, grid(), points());
}

}  // namespace

BENCHMARK(BM_Memcpy)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Correct)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CorrectBallGauge)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Compensate, linear_2iter, map::Interpolation::Linear, 2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_Compensate, cubic_2iter, map::Interpolation::Cubic, 2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
