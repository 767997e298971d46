// Minimum-zone flatness (an exact LP, GLPK) against the least-squares plane of the same points in
// the same run (see BENCHMARKS.md). Points: a 100 × 100 lattice over 1000 × 800 mm (10⁴ points
// at the default size) with a smooth µm-level form, a tilt and noise, like a measured plate.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "trueaxis/geometry/flatness.hpp"

using namespace trueaxis;

namespace {

struct Points {
  Eigen::VectorXd x, y, z;
};

Points plate(long n) {
  const long side = std::lround(std::sqrt(static_cast<double>(n)));
  Points p;
  p.x.resize(side * side);
  p.y.resize(side * side);
  p.z.resize(side * side);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0, 0.05e-3);
  for (long j = 0, k = 0; j < side; ++j)
    for (long i = 0; i < side; ++i, ++k) {
      const double x = 1000.0 * i / (side - 1), y = 800.0 * j / (side - 1);
      p.x[k] = x;
      p.y[k] = y;
      p.z[k] =
          2e-3 * std::sin(x / 170) * std::cos(y / 230) + 1e-3 * x * y / 8e5 + 5e-6 * x + noise(rng);
    }
  return p;
}

void BM_LsPlane(benchmark::State& st) {
  const Points p = plate(st.range(0));
  for (auto _ : st) benchmark::DoNotOptimize(geometry::ls_plane(p.x, p.y, p.z));
  st.SetItemsProcessed(st.iterations() * p.x.size());
}

void BM_MinZonePlane(benchmark::State& st) {
  const Points p = plate(st.range(0));
  for (auto _ : st) benchmark::DoNotOptimize(geometry::min_zone_plane(p.x, p.y, p.z));
  st.SetItemsProcessed(st.iterations() * p.x.size());
}

}  // namespace

BENCHMARK(BM_LsPlane)
    ->Arg(1000)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_MinZonePlane)
    ->Arg(1000)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
