// Sphere fits per second (a CMM probes every ball of a ball gauge: thousands of fits per map),
// against the closed-form plane fit of the same points in the same run (see BENCHMARKS.md).
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
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

// `n` points on a Ø50 cylinder, 100 mm long, axis tilted through (100, 50, 20) mm, 0.5 µm noise,
// in random order.
Eigen::Matrix3Xd cylinder(long n) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, 0.5e-3);
  const Eigen::Vector3d a = Eigen::Vector3d(0.1, 0.2, 1).normalized(), e1 = a.unitOrthogonal(),
                        e2 = a.cross(e1);
  Eigen::Matrix3Xd p(3, n);
  for (long i = 0; i < n; ++i) {
    const double t = 100 * u(rng), ph = 2 * M_PI * u(rng), r = 25 + noise(rng);
    p.col(i) = Eigen::Vector3d(100, 50, 20) + t * a + r * (std::cos(ph) * e1 + std::sin(ph) * e2);
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

void BM_CylinderFit(benchmark::State& st) {
  const Eigen::Matrix3Xd p = cylinder(st.range(0));
  for (auto _ : st) benchmark::DoNotOptimize(geometry::fit(geometry::Element::Cylinder, p));
  st.SetItemsProcessed(st.iterations());
}

}  // namespace

BENCHMARK(BM_PlaneFit)->Arg(25)->Arg(100)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_SphereFit)
    ->Arg(25)
    ->Arg(100)
    ->Arg(1000)
    ->Arg(100000)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
// A large scan: a cylinder against a sphere fit of as many points (target: ≤ 10×).
BENCHMARK(BM_SphereFit)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CylinderFit)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();
