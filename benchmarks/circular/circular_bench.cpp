// The circular test's analysis (ISO 230-4 figures and the diagnosis, with the spike decay and
// reversal delay searched) of a 10⁵-sample, two-direction ballbar trace, against one
// least-squares solve of a design matrix of the same size in the same run (see BENCHMARKS.md;
// benchmarks/peers_circular.py compares with numpy's lstsq).
#include <benchmark/benchmark.h>

#include <Eigen/Dense>

#include "trueaxis/circular/circular.hpp"
#include "trueaxis/sim/circular.hpp"

using namespace trueaxis;

namespace {

// 1000 samples/s at 750 mm/min on R 100 mm: 50 265 samples per direction.
const sim::CircularRun& run() {
  static const sim::CircularRun r = [] {
    sim::Machine m;
    m.squareness_c0y = 12e-6;
    sim::CircularOptions o;
    o.feed = 750;
    o.sample_rate = 1000;
    o.servo[0].gain = 40;
    o.servo[1].gain = 36;
    o.servo[0].backlash = 3e-3;
    o.servo[1].backlash = 5e-3;
    o.servo[1].spike = 3e-3;
    o.noise = 0.1e-3;
    return sim::simulate_circular(m, o);
  }();
  return r;
}

void BM_CircularAnalysis(benchmark::State& st) {
  const auto& t = run().trace;
  circular::Options o;
  o.feed = 750;
  for (auto _ : st) benchmark::DoNotOptimize(circular::evaluate(t, o));
  st.counters["samples"] = static_cast<double>(t.angle.size());
}

// The same with the decay and one delay given: the figures and one fit, without the search.
void BM_CircularAnalysisWithoutSearch(benchmark::State& st) {
  const auto& t = run().trace;
  circular::Options o;
  o.feed = 750;
  const auto found = circular::evaluate(t, o);
  o.spike_decay = found.spike_decay;
  o.reversal_delay = found.reversal_delay[0];
  for (auto _ : st) benchmark::DoNotOptimize(circular::evaluate(t, o));
}

// Baseline: one least-squares solve (Householder QR) of a design matrix as large as the
// diagnosis' (16 columns of trigonometric signatures over the same samples).
void BM_LeastSquaresOfTheSameSize(benchmark::State& st) {
  const auto& t = run().trace;
  const Eigen::Index n = t.angle.size();
  Eigen::MatrixXd J(n, 16);
  for (Eigen::Index k = 0; k < n; ++k)
    for (int j = 0; j < 16; ++j) J(k, j) = std::cos((j + 1) * t.angle[k] + 0.3 * j);
  for (auto _ : st)
    benchmark::DoNotOptimize(Eigen::VectorXd(J.householderQr().solve(t.deviation)));
}

}  // namespace

BENCHMARK(BM_CircularAnalysis)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CircularAnalysisWithoutSearch)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LeastSquaresOfTheSameSize)->Unit(benchmark::kMillisecond);
