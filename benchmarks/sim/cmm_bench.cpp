// Simulated machine seconds per wall second of the virtual scanning CMM at 1 kHz: servo ticks
// with a probe reading against a 1571-point section contour (a Ø50 mm hole at 0.1 mm spacing),
// following the hole at 50 mm/s. Baseline in the same run: the servo ticks alone.
#include <benchmark/benchmark.h>

#include <cmath>

#include "trueaxis/scan/controller.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace {

using namespace trueaxis;

constexpr double kR = 25, kV = 50;
constexpr int kTicks = 10000;  // 10 simulated seconds at 1 kHz

sim::Contour hole() {
  const int n = 1571;
  Eigen::Matrix3Xd p(3, n);
  for (int i = 0; i < n; ++i)
    p.col(i) << kR * std::cos(2 * M_PI * i / n), kR * std::sin(2 * M_PI * i / n), 0;
  return sim::Contour(p, Eigen::Vector3d::UnitZ(), true, false);
}

template <bool WithProbe>
void run(benchmark::State& st) {
  const sim::ServoOptions so;
  const sim::Contour c = hole();
  sim::ProbeOptions po;
  po.noise = 0.0005;
  const double rc = kR - po.tip_radius + 0.3, w = kV / rc;
  for (auto _ : st) {
    sim::Servo s(so, Eigen::Vector3d(rc, 0, 0));
    sim::Probe probe(po);
    double sum = 0;
    for (int i = 0; i < kTicks; ++i) {
      const double t = s.time();
      s.step(Eigen::Vector3d(rc * std::cos(w * t), rc * std::sin(w * t), 0),
             Eigen::Vector3d(-kV * std::sin(w * t), kV * std::cos(w * t), 0));
      if constexpr (WithProbe) sum += probe.read(s.position(), c).deflection.x();
    }
    benchmark::DoNotOptimize(sum);
  }
  st.counters["sim_s_per_wall_s"] = benchmark::Counter(
      kTicks * so.dt() * static_cast<double>(st.iterations()), benchmark::Counter::kIsRate);
}

void BM_ServoTicksAlone(benchmark::State& st) {
  run<false>(st);
}
BENCHMARK(BM_ServoTicksAlone)->Unit(benchmark::kMillisecond);
void BM_ServoAndProbeTicks(benchmark::State& st) {
  run<true>(st);
}
BENCHMARK(BM_ServoAndProbeTicks)->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

// The whole controller on the virtual CMM: an error-tolerant scan of NIST's I++ test part in the
// section at z = 25 (the square and the Ø50 hole as polylines), moved 1.8 mm so that each section
// needs touches, a correction and a rescan. Reported per servo tick, against the 1 ms budget of a
// 1 kHz loop.
void BM_ErrorTolerantScanOfAMovedPart(benchmark::State& st) {
  design::Design d;
  design::Section sq;
  sq.name = "outer";
  sq.plane = {Eigen::Vector3d(0, 0, 25), Eigen::Vector3d::UnitZ()};
  sq.polyline.resize(3, 5);
  sq.polyline << 0, 100, 100, 0, 0, 0, 0, 100, 100, 0, 25, 25, 25, 25, 25;
  d.sections.push_back(sq);
  design::Section hole = sq;
  hole.name = "hole";
  hole.material = design::Side::Right;
  hole.polyline.resize(3, 73);
  for (int i = 0; i < 73; ++i) {
    const double a = 2 * M_PI * (i % 72) / 72;
    hole.polyline.col(i) << 50 + 25 * std::cos(a), 50 + 25 * std::sin(a), 25;
  }
  d.sections.push_back(hole);
  sim::Part part{d, {}};
  part.deviation.translation = Eigen::Vector3d(1.8, -1.1, 0);
  double machine_s = 0;
  for (auto _ : st) {
    scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
    const auto r = scan::scan(cmm, d, {});
    machine_s += r.time.total;
    benchmark::DoNotOptimize(r.sections.data());
  }
  st.counters["sim_s_per_wall_s"] = benchmark::Counter(machine_s, benchmark::Counter::kIsRate);
  st.counters["ticks"] = machine_s / static_cast<double>(st.iterations()) * 1000;
}
BENCHMARK(BM_ErrorTolerantScanOfAMovedPart)->Unit(benchmark::kMillisecond);

}  // namespace
