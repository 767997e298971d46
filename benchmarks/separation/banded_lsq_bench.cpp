// The least-squares separation's solver alone at 10⁶ stations (three probes): factorised as one
// chain of stations on one core, against the two chains (from both ends towards the middle) on
// two cores that long runs use (see BENCHMARKS.md).
#include <benchmark/benchmark.h>

#include <vector>

#include "../../src/separation/banded_lsq.hpp"
#include "trueaxis/sim/straightness.hpp"

using namespace trueaxis;
using separation::detail::BandedLsq;
using separation::detail::Design;

namespace {

struct Run {
  Design D;
  Eigen::MatrixXd readings;
  Eigen::RowVectorXd mu;
};

// Factorisation, back-substitution, one refinement pass and its back-substitution: what one
// separation asks of the solver.
void solve(const Run& c, long split_stations) {
  BandedLsq s(c.D, split_stations);
  Eigen::VectorXd v(c.D.nvars);
  for (const auto& [id, value] : c.D.pins) v[id] = value;
  const auto u = separation::detail::Unknowns::in(c.D, v);
  const Eigen::VectorXd no_angle;
  s.factor(c.readings, c.mu, no_angle, u, true);
  s.solve_add(u, true);
  s.refactor_rhs(c.readings, c.mu, no_angle, u);
  benchmark::DoNotOptimize(s.solve_add(u));
}

Run run(const Eigen::MatrixXd& readings) {
  return {separation::detail::make_design({0, 1, 2}, readings.rows(), false, std::nullopt, 1.0),
          readings, readings.colwise().mean()};
}

const Eigen::MatrixXd& readings() {
  static const Eigen::MatrixXd r = [] {
    sim::StraightnessOptions o;
    o.stations = 1000000;
    o.step = 1;
    o.offsets = {0, 1, 2};
    o.noise = 1e-5;
    return sim::simulate_straightness(o).data.readings;
  }();
  return r;
}

void BM_LsqSolverOneChain(benchmark::State& st) {
  const Run c = run(readings());
  for (auto _ : st) solve(c, readings().rows() + 1);
}

void BM_LsqSolverTwoChains(benchmark::State& st) {
  const Run c = run(readings());
  for (auto _ : st) solve(c, BandedLsq::kSplitStations);
}

// The factorisation alone, one chain on one core, its buffers reused from the previous
// iteration: the rotations' arithmetic without the kernel's page clearing (thread CPU time).
void BM_LsqFactorOneChainWarm(benchmark::State& st) {
  const Run c = run(readings());
  BandedLsq s(c.D, readings().rows() + 1);
  Eigen::VectorXd v(c.D.nvars);
  for (const auto& [id, value] : c.D.pins) v[id] = value;
  const auto u = separation::detail::Unknowns::in(c.D, v);
  const Eigen::VectorXd no_angle;
  s.factor(c.readings, c.mu, no_angle, u, true);  // commits the buffers
  for (auto _ : st) {
    s.factor(c.readings, c.mu, no_angle, u, true);
    benchmark::DoNotOptimize(s.ssr());
  }
}

// (AᵀA)⁻¹V for six columns of V and diag((AᵀA)⁻¹), two chains on two cores: the row solve of
// the per-point uncertainty, after a factorisation (not timed). V's rows have the sparsity of
// the reference's (lines on the workpiece and the guide, the guide's parabola, pitch's mean).
void BM_LsqNormalRowsTwoChains(benchmark::State& st) {
  const Run c = run(readings());
  const long Q = c.D.Q, n = c.D.n;
  BandedLsq s(c.D, BandedLsq::kSplitStations);
  Eigen::VectorXd v(c.D.nvars);
  for (const auto& [id, value] : c.D.pins) v[id] = value;
  const auto u = separation::detail::Unknowns::in(c.D, v);
  const Eigen::VectorXd no_angle;
  std::vector<double> out(static_cast<std::size_t>(c.D.nvars));
  for (auto _ : st) {
    st.PauseTiming();
    s.factor(c.readings, c.mu, no_angle, u, true);
    st.ResumeTiming();
    double gram[36] = {};
    s.solve_normal_rows<6>(
        [&](int id, double* r) {
          for (int j = 0; j < 6; ++j) r[j] = 0;
          const double x = 1e-6 * static_cast<double>(id < Q ? id - Q / 2 : id - Q - n / 2);
          if (id < Q) {
            r[0] = 1e-3;
            r[1] = x;
          } else if (id < Q + n) {
            r[2] = 1e-3;
            r[3] = x;
            r[4] = x * x;
          } else {
            r[5] = 1;
          }
        },
        [&](int id, const double* z, double d) {
          out[static_cast<std::size_t>(id)] = d - 2 * (z[0] + z[2] + z[4]);
        },
        gram);
    benchmark::DoNotOptimize(gram[7]);
  }
}

}  // namespace

BENCHMARK(BM_LsqSolverOneChain)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LsqSolverTwoChains)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LsqFactorOneChainWarm)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LsqNormalRowsTwoChains)->Unit(benchmark::kMillisecond)->UseRealTime();
