// Surface assembly of a 100 × 100-line network (10⁴ crossings), with a same-run baseline: one
// dense least-squares QR of the same size (see BENCHMARKS.md).
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <Eigen/QR>
#include <cmath>
#include <random>

#include "trueaxis/surface/surface.hpp"

using namespace trueaxis;

namespace {

constexpr int kLines = 100;  // per direction

std::vector<surface::Line> network() {
  std::vector<surface::Line> lines;
  const double h = 10;
  auto height = [](double x, double y) { return 1e-3 * std::sin(x / 170) * std::cos(y / 230); };
  for (int d = 0; d < 2; ++d)
    for (int j = 0; j < kLines; ++j) {
      surface::Line l;
      l.name = fmt::format("{}{}", d == 0 ? "x" : "y", j);
      l.start = d == 0 ? Eigen::Vector2d(0, j * h) : Eigen::Vector2d(j * h, 0);
      l.direction = d == 0 ? Eigen::Vector2d::UnitX() : Eigen::Vector2d::UnitY();
      l.spacing = h;
      l.heights.resize(kLines);
      for (int k = 0; k < kLines; ++k) {
        const Eigen::Vector2d p = l.station(k);
        l.heights[k] = height(p.x(), p.y()) + 1e-3 * (0.3 * j - 0.001 * k * j);  // offset, tilt
      }
      lines.push_back(std::move(l));
    }
  return lines;
}

void BM_SurfaceGrid(benchmark::State& st) {
  const auto lines = network();
  for (auto _ : st) benchmark::DoNotOptimize(surface::build(lines));
  st.SetItemsProcessed(st.iterations() * kLines * kLines);  // crossings
}

// The same network with 0.1 µm of noise on every height: the flatness's uncertainty is then
// stated, from 200 noise trials that reuse the network's factorisation.
std::vector<surface::Line> noisy_network() {
  auto lines = network();
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0, 1e-4);
  for (auto& l : lines)
    for (auto& h : l.heights) h += noise(rng);
  return lines;
}

void BM_SurfaceGridWithUncertainty(benchmark::State& st) {
  const auto lines = noisy_network();
  for (auto _ : st) benchmark::DoNotOptimize(surface::build(lines));
  st.SetItemsProcessed(st.iterations() * kLines * kLines);  // crossings
}

// Without it, the same noisy network (Options::uncertainty off): the same-run baseline.
void BM_SurfaceGridNoisyWithoutUncertainty(benchmark::State& st) {
  const auto lines = noisy_network();
  surface::Options o;
  o.uncertainty = false;
  for (auto _ : st) benchmark::DoNotOptimize(surface::build(lines, o));
  st.SetItemsProcessed(st.iterations() * kLines * kLines);  // crossings
}

// Baseline: a dense Householder QR least-squares solve with the network's shape (one row per
// crossing, two unknowns per line): the cost of the dense formulation itself.
void BM_DenseQrSameShape(benchmark::State& st) {
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(kLines * kLines, 4 * kLines);
  const Eigen::VectorXd b = Eigen::VectorXd::Random(kLines * kLines);
  for (auto _ : st) benchmark::DoNotOptimize(Eigen::VectorXd(A.householderQr().solve(b)));
}

}  // namespace

BENCHMARK(BM_DenseQrSameShape)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SurfaceGrid)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SurfaceGridWithUncertainty)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SurfaceGridNoisyWithoutUncertainty)->Unit(benchmark::kMillisecond)->UseRealTime();
