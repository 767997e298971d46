// The least-squares separation's solver alone at 10⁶ stations (three probes): factorised as one
// chain of stations on one core, against the two chains (from both ends towards the middle) on
// two cores that long runs use (see BENCHMARKS.md).
#include <benchmark/benchmark.h>

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

}  // namespace

BENCHMARK(BM_LsqSolverOneChain)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LsqSolverTwoChains)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LsqFactorOneChainWarm)->Unit(benchmark::kMillisecond);
