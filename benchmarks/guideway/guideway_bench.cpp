// Five guideway errors at 10⁶ positions (3 QPDs, 6 readings each) against a plain copy of the
// same readings in the same run (see BENCHMARKS.md).
#include <benchmark/benchmark.h>

#include <cstring>
#include <random>

#include "trueaxis/guideway/guideway.hpp"

using namespace trueaxis;

namespace {

constexpr long kPositions = 1000000;

guideway::Layout layout() {
  guideway::Layout l;
  l.detectors = {{"a", guideway::Kind::Position, {-60, 0, 0}, 0},
                 {"b", guideway::Kind::Position, {60, 0, 150}, 0},
                 {"c", guideway::Kind::Position, {0, 80, 300}, 0}};
  return l;
}

const Eigen::MatrixXd& readings() {
  static const Eigen::MatrixXd m = [] {
    std::mt19937_64 rng(1);
    std::normal_distribution<double> n(0, 1e-3);
    Eigen::MatrixXd r(kPositions, 6);
    for (Eigen::Index i = 0; i < r.size(); ++i) r.data()[i] = n(rng);
    return r;
  }();
  return m;
}

void BM_CopyReadings(benchmark::State& st) {
  const Eigen::MatrixXd& r = readings();
  Eigen::MatrixXd out(r.rows(), r.cols());
  for (auto _ : st) {
    std::memcpy(out.data(), r.data(), sizeof(double) * static_cast<std::size_t>(r.size()));
    benchmark::ClobberMemory();
  }
  st.SetBytesProcessed(st.iterations() * r.size() * 8);
}

// Second baseline: what the result itself costs in memory traffic. The solve returns nine new
// vectors of 10⁶ doubles (s, five errors, residual, two straightness curves); allocating and
// writing them (first touch: the kernel zeroes every page) while reading the readings once.
void BM_ReadOnceWriteResult(benchmark::State& st) {
  const Eigen::MatrixXd& r = readings();
  for (auto _ : st) {
    std::vector<Eigen::VectorXd> out(9);
    for (int j = 0; j < 9; ++j) out[static_cast<std::size_t>(j)] = r.col(j % 6);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
}

void BM_GuidewaySolve(benchmark::State& st) {
  const Eigen::MatrixXd& r = readings();
  const Eigen::VectorXd s = Eigen::VectorXd::LinSpaced(kPositions, 0, 1000);
  const auto l = layout();
  for (auto _ : st) benchmark::DoNotOptimize(guideway::solve(l, s, r));
  st.SetItemsProcessed(st.iterations() * kPositions);
}

}  // namespace

BENCHMARK(BM_CopyReadings)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ReadOnceWriteResult)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GuidewaySolve)->Unit(benchmark::kMillisecond)->UseRealTime();
