// Minimum zone of a long noisy straightness profile (10⁶ points), with a same-run baseline: a copy
// of the profile's heights (8 MB), the floor for one pass over them (see BENCHMARKS.md).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "trueaxis/geometry/straightness.hpp"

namespace {

struct Profile {
  Eigen::VectorXd x, y;
};

// 1 µm-scale form (a slow sine) and 10 nm noise on 10⁶ stations 1 mm apart.
const Profile& profile() {
  static const Profile p = [] {
    constexpr long n = 1000000;
    Profile q{Eigen::VectorXd(n), Eigen::VectorXd(n)};
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise(0, 1e-5);
    for (long i = 0; i < n; ++i) {
      q.x[i] = static_cast<double>(i);
      q.y[i] = 1e-3 * std::sin(1e-5 * static_cast<double>(i)) + noise(rng);
    }
    return q;
  }();
  return p;
}

void BM_MemcpyProfileHeights(benchmark::State& st) {
  const Profile& p = profile();
  std::vector<double> dst(static_cast<std::size_t>(p.y.size()));
  for (auto _ : st) {
    std::memcpy(dst.data(), p.y.data(), dst.size() * sizeof(double));
    benchmark::ClobberMemory();
  }
}

void BM_MinZoneProfile(benchmark::State& st) {
  const Profile& p = profile();
  for (auto _ : st) benchmark::DoNotOptimize(trueaxis::geometry::min_zone(p.x, p.y));
  st.SetItemsProcessed(st.iterations() * p.x.size());
}

}  // namespace

BENCHMARK(BM_MemcpyProfileHeights)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MinZoneProfile)->Unit(benchmark::kMillisecond);
