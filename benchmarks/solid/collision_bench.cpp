// The part's solid in the loop of the virtual scanning CMM.
// - The collision check of one servo tick with no guard to skip it: the ball against the faces
//   it does not measure, the stylus and the probe body against every face of NIST's
//   DaimlerChrysler test part (62 000 triangles), at places along a wall it scans. Baseline in
//   the same run: the servo and probe reading of one tick (sim/cmm_bench.cpp's hole, per tick).
// - A whole error-tolerant scan of NIST's I++ test part cut from its STEP file, moved 1.8 mm and
//   turned 0.3°, with the solid (every free move planned against it, every tick checked) and,
//   as the baseline, the same design data without the solid.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

#include "trueaxis/design/design.hpp"
#include "trueaxis/scan/controller.hpp"
#include "trueaxis/solid/mesh.hpp"

namespace {

using namespace trueaxis;

const std::string kData = TRUEAXIS_BENCH_DATA;

void BM_CollisionCheckOfOneTick(benchmark::State& st) {
  const auto part = solid::load_step(kData + "/cad/DaimlerChryslerTestPartAP214.stp");
  // Along the tab wall x = 68 at z = 19.98, the ball 0.7 mm off it (scanning), stylus up.
  const double r = 1, rs = 0.5, rb = 6.5, len = 50, body = 60;
  const Eigen::Vector3d u = Eigen::Vector3d::UnitZ();
  const auto skip = part->faces_crossing(Eigen::Vector3d(0, 0, 19.98), Eigen::Vector3d::UnitZ());
  int i = 0;
  for (auto _ : st) {
    const Eigen::Vector3d ball(68.7, -50 + 0.01 * (i++ % 1000), 19.98);
    double c = part->distance(ball, r + 1, skip);
    c += part->distance(ball + r * u, ball + (len + rb) * u, rs + 1);
    c += part->distance(ball + (len + rb) * u, ball + (len + body) * u, rb + 1);
    benchmark::DoNotOptimize(c);
  }
  st.counters["triangles"] = static_cast<double>(part->triangles());
}
BENCHMARK(BM_CollisionCheckOfOneTick)->Unit(benchmark::kMicrosecond);

template <bool WithSolid>
void scan_ipp(benchmark::State& st) {
  const design::Design cut =
      design::from_step(kData + "/ippdme/ipp_simple.stp",
                        {{"mid", {Eigen::Vector3d(0, 0, 37.5), Eigen::Vector3d::UnitZ()}}});
  design::Design d = cut;
  if (!WithSolid) d.solid.clear();
  sim::Part part{d, {}};
  part.deviation.translation = Eigen::Vector3d(1.8, -1.1, 0);
  part.deviation.rotation_deg = Eigen::Vector3d(0, 0, 0.3);
  const Eigen::Vector3d home = scan::start_position(d, {});
  {
    scan::VirtualCmm warm(part, {}, home);  // the true contours and the mesh, cached once
  }
  double machine_s = 0;
  for (auto _ : st) {
    scan::VirtualCmm cmm(part, {}, home);
    const auto r = scan::scan(cmm, d, {});
    if (!r.ok()) st.SkipWithError(r.summary().c_str());
    machine_s += r.time.total;
    benchmark::DoNotOptimize(r.sections.data());
  }
  st.counters["sim_s_per_wall_s"] = benchmark::Counter(machine_s, benchmark::Counter::kIsRate);
  st.counters["machine_s"] = machine_s / static_cast<double>(st.iterations());
}
void BM_ScanWithoutTheSolid(benchmark::State& st) {
  scan_ipp<false>(st);
}
BENCHMARK(BM_ScanWithoutTheSolid)->Unit(benchmark::kMillisecond);
void BM_ScanWithTheSolid(benchmark::State& st) {
  scan_ipp<true>(st);
}
BENCHMARK(BM_ScanWithTheSolid)->Unit(benchmark::kMillisecond);

}  // namespace
