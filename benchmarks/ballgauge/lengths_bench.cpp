// Gauge-block verification with the parametric correction: n lengths, each corrected at both
// ends with its own length uncertainty from the parameter covariance. Baseline in the same run:
// correcting the same 2n end points with the model in one batch (the work that cannot be
// avoided). Complexity is fitted over n, which must come out linear (a scan of every repeat
// group made it quadratic: 8000 rows took 16 s).
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <random>

#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/ballgauge/parametric.hpp"
#include "trueaxis/sim/ballgauge.hpp"
#include "trueaxis/sim/machine.hpp"

using namespace trueaxis;

namespace {

struct Fixture {
  sim::Machine machine;
  ballgauge::ParametricResult model;
  Fixture() {
    sim::MachineOptions mo;
    mo.seed = 3;
    machine = sim::random_machine(mo);
    const auto gauge = sim::frame_gauge();
    auto poses = sim::stacked_poses(gauge, 3, {150, 120, 60}, Eigen::Matrix3d::Identity());
    poses.front().alignment = ballgauge::Alignment::LeastSquares;
    sim::BallGaugeOptions so;
    so.noise = 0.5e-3;
    const auto c = sim::simulate_ballgauge(machine, gauge, poses, so);
    ballgauge::ParametricOptions po;
    po.offset = machine.offset;
    model = ballgauge::identify(gauge, c.placements, po);
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

// n distinct lengths inside the identified span, three repeats of each fifth one.
std::vector<ballgauge::LengthMeasurement> lengths(long n) {
  const auto& r = fixture().model;
  std::mt19937_64 rng(7);
  std::vector<ballgauge::LengthMeasurement> out;
  out.reserve(static_cast<std::size_t>(n));
  Eigen::Vector3d lo, hi;
  for (int k = 0; k < 3; ++k) {
    lo[k] = r.model.range[static_cast<std::size_t>(k)][0] + r.model.offset[k] + 1;
    hi[k] = r.model.range[static_cast<std::size_t>(k)][1] + r.model.offset[k] - 1;
  }
  std::uniform_real_distribution<double> U(0, 1);
  while (static_cast<long>(out.size()) < n) {
    ballgauge::LengthMeasurement m;
    for (int k = 0; k < 3; ++k) {
      m.a[k] = lo[k] + (hi[k] - lo[k]) * U(rng);
      m.b[k] = lo[k] + (hi[k] - lo[k]) * U(rng);
    }
    m.nominal = (m.b - m.a).norm();
    for (int rep = 0; rep < (out.size() % 5 == 0 ? 3 : 1) && static_cast<long>(out.size()) < n;
         ++rep)
      out.push_back(m);
  }
  return out;
}

void BM_VerifyLengthsParametric(benchmark::State& state) {
  const auto rows = lengths(state.range(0));
  const auto corr = ballgauge::parametric_correction(fixture().model);
  for (auto _ : state) benchmark::DoNotOptimize(ballgauge::verify_lengths(rows, corr));
  state.SetComplexityN(state.range(0));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_VerifyLengthsParametric)
    ->RangeMultiplier(10)
    ->Range(1000, 100000)
    ->Complexity(benchmark::oN)
    ->Unit(benchmark::kMillisecond);

// Baseline: the 2n end points through the model's correction in one batch.
void BM_ParametricCorrectionOfTheEndsOnly(benchmark::State& state) {
  const auto rows = lengths(state.range(0));
  const auto corr = ballgauge::parametric_correction(fixture().model);
  Eigen::Matrix3Xd ends(3, 2 * rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    ends.col(static_cast<Eigen::Index>(2 * i)) = rows[i].a;
    ends.col(static_cast<Eigen::Index>(2 * i + 1)) = rows[i].b;
  }
  for (auto _ : state) {
    Eigen::Matrix3Xd p = ends;
    corr.apply(p);
    benchmark::DoNotOptimize(p.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_ParametricCorrectionOfTheEndsOnly)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace
