// Separation hot paths at 1e6 stations, with a same-run memory baseline (see BENCHMARKS.md).
#include <benchmark/benchmark.h>

#include <cstring>

#include "trueaxis/separation/separation.hpp"
#include "trueaxis/sim/straightness.hpp"

using namespace trueaxis;

namespace {

const sim::StraightnessCampaign& campaign(int probes, bool angle) {
  static std::map<std::pair<int, bool>, sim::StraightnessCampaign> cache;
  auto key = std::make_pair(probes, angle);
  auto it = cache.find(key);
  if (it == cache.end()) {
    sim::StraightnessOptions o;
    o.stations = 1000000;
    o.step = 1;
    o.offsets.clear();
    for (int i = 0; i < probes; ++i) o.offsets.push_back(i);
    if (probes == 2 && !angle) o.pitch_amplitude = 0;
    o.angle = angle;
    o.noise = 1e-5;
    it = cache.emplace(key, sim::simulate_straightness(o)).first;
  }
  return it->second;
}

// unc: uncertainties with a given sigma; gain: the options' default (no sigma), which for the
// recurrences reports the layout's noise gain from the least-squares covariance.
void run(benchmark::State& st, separation::Method m, int probes, bool angle, bool unc,
         bool gain = false) {
  const auto& c = campaign(probes, angle);
  separation::Options o;
  o.method = m;
  o.compute_uncertainty = unc || gain;
  if (unc) o.sigma = 1e-5;
  for (auto _ : st) benchmark::DoNotOptimize(separation::separate(c.data, o));
  st.SetItemsProcessed(st.iterations() * c.data.x.size());
  st.SetBytesProcessed(st.iterations() * c.data.readings.size() * 8);
}

// Baseline: copying the readings once (the memory-bandwidth floor of any pass over the data).
void BM_MemcpyReadings(benchmark::State& st) {
  const auto& c = campaign(3, false);
  std::vector<double> dst(static_cast<std::size_t>(c.data.readings.size()));
  for (auto _ : st) {
    std::memcpy(dst.data(), c.data.readings.data(), dst.size() * 8);
    benchmark::ClobberMemory();
  }
  st.SetBytesProcessed(st.iterations() * static_cast<long>(dst.size()) * 8);
}

}  // namespace

BENCHMARK(BM_MemcpyReadings)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run, two_point, separation::Method::TwoPoint, 2, false, false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run, three_point, separation::Method::ThreePoint, 3, false, false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run, two_point_noise_gain, separation::Method::TwoPoint, 2, false, false, true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run, three_point_noise_gain, separation::Method::ThreePoint, 3, false, false,
                  true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run, lsq_3probes, separation::Method::Lsq, 3, false, false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run, lsq_3probes_uncertainty, separation::Method::Lsq, 3, false, true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run, lsq_3probes_level_uncertainty, separation::Method::Lsq, 3, true, true)
    ->Unit(benchmark::kMillisecond);
// Four probes are redundant (4 readings for 3 new unknowns per station): the banded
// least-squares factorisation, which three probes without an angle channel no longer need.
BENCHMARK_CAPTURE(run, lsq_4probes, separation::Method::Lsq, 4, false, false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(run, lsq_4probes_uncertainty, separation::Method::Lsq, 4, false, true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
