// A full ISO 10360-2 E0 test (105 lengths: 210 PtMeas and the planned moves between them) over
// loopback I++ DME against the virtual CMM at --time-scale 0, against the same number of bare
// PtMeas round trips (one face, no moves) on the same server in the same run: what the moves and
// their planning cost beyond the probings themselves.
#include <benchmark/benchmark.h>

#include <memory>
#include <thread>

#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/ippdme/acceptance.hpp"
#include "trueaxis/ippdme/server.hpp"
#include "trueaxis/sim/machine.hpp"

namespace {

using namespace trueaxis;

sim::Machine bench_machine() {
  sim::MachineOptions o;
  o.seed = 3;
  return sim::random_machine(o);
}

struct AcceptanceServer {
  acceptance::Setup setup = acceptance::example_setup(acceptance::Volume::of(bench_machine()));
  std::unique_ptr<ippdme::Server> server;
  std::thread t;
  AcceptanceServer() {
    ippdme::ServerOptions o;
    o.port = 0;
    o.engine.time_scale = 0;
    o.engine.cmm.geometry = bench_machine();
    const auto& g = *o.engine.cmm.geometry;
    o.engine.cmm.home = Eigen::Vector3d(g.range[0][0], g.range[1][1], g.range[2][1]) + g.offset;
    o.engine.boxes = acceptance::artefact_boxes(setup);
    server = std::make_unique<ippdme::Server>(o);
    t = std::thread([this] { server->run(); });
  }
  ~AcceptanceServer() {
    server->stop();
    t.join();
  }
  ippdme::RemoteCmmOptions client() const {
    ippdme::RemoteCmmOptions ro;
    ro.client.port = server->port();
    ro.tip_radius = 0;
    return ro;
  }
};

void BM_AcceptanceE0OverLoopback(benchmark::State& st) {
  AcceptanceServer srv;
  acceptance::E0Options eo;
  eo.mpe = ballgauge::Mpe::parse("2.5+L/250");
  const auto volume = acceptance::Volume::of(bench_machine());
  for (auto _ : st) {
    ippdme::RemoteCmm cmm(srv.client());
    const auto r =
        acceptance::run_e0(srv.setup, volume, ippdme::acceptance_touch(cmm, srv.setup, volume), eo);
    if (!r.complete) st.SkipWithError(r.stopped.c_str());
    benchmark::DoNotOptimize(r.e0_max);
  }
  st.counters["PtMeas"] = static_cast<double>(2 * srv.setup.placements.size() * 3);
}
BENCHMARK(BM_AcceptanceE0OverLoopback)->Unit(benchmark::kMillisecond)->UseRealTime();

// The baseline: 210 PtMeas of one face as they come, no move between them.
void BM_AcceptanceBarePtMeas(benchmark::State& st) {
  AcceptanceServer srv;
  const auto& p = srv.setup.placements.front();
  const Eigen::Vector3d at = p.centre - srv.setup.block(p.block).length / 2 * p.direction;
  for (auto _ : st) {
    ippdme::RemoteCmm cmm(srv.client());
    cmm.move(at - 6 * p.direction, 100);
    for (int i = 0; i < 210; ++i)
      benchmark::DoNotOptimize(cmm.measure(at, -p.direction, srv.setup.approach, 3, 5));
  }
  st.counters["PtMeas"] = 210;
}
BENCHMARK(BM_AcceptanceBarePtMeas)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
