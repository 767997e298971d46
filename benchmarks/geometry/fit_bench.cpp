// Sphere fits per second (a CMM probes every ball of a ball gauge: thousands of fits per map),
// against the closed-form plane fit of the same points in the same run (see BENCHMARKS.md).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "trueaxis/geometry/fit.hpp"

using namespace trueaxis;

namespace {

// `n` probed points on a hemisphere cap of a 25 mm ball at (400, 300, 200) mm, 0.5 µm noise.
Eigen::Matrix3Xd ball(long n) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, 0.5e-3);
  Eigen::Matrix3Xd p(3, n);
  for (long i = 0; i < n; ++i) {
    const double th = std::acos(u(rng)), ph = 2 * M_PI * u(rng), r = 12.5 + noise(rng);
    p.col(i) =
        Eigen::Vector3d(400, 300, 200) +
        r * Eigen::Vector3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
  }
  return p;
}

void BM_PlaneFit(benchmark::State& st) {
  const Eigen::Matrix3Xd p = ball(st.range(0));
  for (auto _ : st) benchmark::DoNotOptimize(geometry::fit(geometry::Element::Plane, p));
  st.SetItemsProcessed(st.iterations());
}

void BM_SphereFit(benchmark::State& st) {
  const Eigen::Matrix3Xd p = ball(st.range(0));
  for (auto _ : st) benchmark::DoNotOptimize(geometry::fit(geometry::Element::Sphere, p));
  st.SetItemsProcessed(st.iterations());
}

}  // namespace

BENCHMARK(BM_PlaneFit)->Arg(25)->Arg(100)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_SphereFit)->Arg(25)->Arg(100)->Unit(benchmark::kMicrosecond)->UseRealTime();
