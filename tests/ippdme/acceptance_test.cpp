// The CMM acceptance tests over I++ DME against the virtual CMM of `trueaxis serve`: the same
// figures as in process, every move clear of the artefacts, and the loop closed: a CMM that fails
// E0 is mapped with a ball gauge through the same server, corrected, and passes.
#include "trueaxis/ippdme/acceptance.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../test_util.hpp"
#include "serving.hpp"
#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/ippdme/ballgauge.hpp"
#include "trueaxis/sim/ballgauge.hpp"

namespace trueaxis {
namespace {

using namespace ippdme;
using test::Running;

// The server's probe meets a face a little aside of the nominal point (by the machine's error,
// micrometres, along a flat face: no change) and latches at its trigger deflection, moved by
// the axes' errors over that 0.2 mm; the protocol rounds points to 0.01 µm.
constexpr double kSameLength = 0.05e-3;  // mm

sim::Machine machine() {
  sim::MachineOptions o;
  o.seed = 3;
  return sim::random_machine(o);
}

ServerOptions serving(const acceptance::Setup& setup, double lobing) {
  ServerOptions o = test::quick();
  o.engine.cmm.geometry = machine();
  const auto& g = *o.engine.cmm.geometry;
  o.engine.cmm.home = Eigen::Vector3d(g.range[0][0], g.range[1][1], g.range[2][1]) + g.offset;
  o.engine.cmm.probe.tip_radius = 1.5;
  o.engine.cmm.probe.lobing = lobing;
  o.engine.boxes = acceptance::artefact_boxes(setup);
  if (setup.sphere) o.engine.balls.push_back({setup.sphere->centre, setup.sphere->diameter / 2});
  return o;
}

struct Run {
  acceptance::E0Result e0;
  acceptance::ProbingResult probing;
};

Run over_ipp(const ServerOptions& o, const acceptance::Setup& setup,
             const acceptance::E0Options& eo) {
  Running server(o);
  RemoteCmmOptions ro;
  ro.client = server.client();
  ro.tip_radius = 0;
  RemoteCmm cmm(ro);
  const auto volume = acceptance::Volume::of(machine());
  const auto touch = acceptance_touch(cmm, setup, volume);
  Run r;
  r.e0 = acceptance::run_e0(setup, volume, touch, eo);
  r.probing = acceptance::run_probing(setup, touch, {});
  return r;
}

}  // namespace

// In process and over loopback: the same lengths, and the probing test the same; every move
// planned clear of the blocks (a collision would stop the run: complete).
TEST(AcceptanceOverIpp, TheSameTestInProcessAndThroughTheServer) {
  const auto volume = acceptance::Volume::of(machine());
  const auto setup = acceptance::example_setup(volume);
  acceptance::E0Options eo;
  eo.mpe = ballgauge::Mpe::parse("2.5+L/250");
  const auto there = over_ipp(serving(setup, 0.5e-3), setup, eo);
  ASSERT_TRUE(there.e0.complete) << there.e0.stopped;
  acceptance::VirtualProbeOptions vp;
  vp.lobing = 0.5e-3;
  const auto here = acceptance::run_e0(setup, volume, acceptance::virtual_touch(machine(), vp), eo);
  ASSERT_EQ(there.e0.lengths.size(), here.lengths.size());
  for (std::size_t i = 0; i < here.lengths.size(); ++i)
    EXPECT_NEAR(there.e0.lengths[i].error, here.lengths[i].error, kSameLength)
        << here.lengths[i].position << " " << here.lengths[i].block;
  EXPECT_EQ(there.e0.verdict, acceptance::Verdict::DoesNotConform);
  const auto probing = acceptance::run_probing(setup, acceptance::virtual_touch(machine(), vp), {});
  EXPECT_NEAR(there.probing.form, probing.form, kSameLength);
  EXPECT_NEAR(there.probing.size, probing.size, kSameLength);
}

// The loop: the CMM fails E0; a ball gauge over the volume is measured through the same server,
// mapped, and the map loaded as the controller's correction; E0 then passes, its worst error at
// least 5 times smaller, and the probing form is what it was (the probe's lobing, which no map
// of the machine removes).
TEST(AcceptanceOverIpp, AFailingCmmIsMappedCorrectedAndPasses) {
  const auto volume = acceptance::Volume::of(machine());
  const auto setup = acceptance::example_setup(volume);
  acceptance::E0Options eo;
  eo.mpe = ballgauge::Mpe::parse("2.5+L/250");
  const double lobing = 0.5e-3;
  const auto before = over_ipp(serving(setup, lobing), setup, eo);
  ASSERT_TRUE(before.e0.complete) << before.e0.stopped;
  ASSERT_EQ(before.e0.verdict, acceptance::Verdict::DoesNotConform);
  // A frame of 5 × 4 × 2 balls at 175 mm, stacked twice: 60 balls over the volume the blocks
  // stand in, measured through a server with the gauge on its table.
  const auto gauge = sim::frame_gauge(5, 4, 2, 175, 25);
  const auto poses = sim::stacked_poses(gauge, 2, {50, 40, -40});
  sim::BallGaugeOptions bo;
  bo.tip_radius = 1.5;
  bo.points_per_ball = 6;
  ballgauge::Result mapped;
  {
    ServerOptions o = serving(setup, lobing);
    o.engine.boxes.clear();
    o.engine.balls = sim::gauge_balls(gauge, poses);
    Running server(o);
    RemoteCmmOptions ro;
    ro.client = server.client();
    ro.tip_radius = 0;
    RemoteCmm cmm(ro);
    const auto campaign =
        sim::measure_ballgauge(gauge, poses, bo, ball_probe(cmm, sim::gauge_balls(gauge, poses)));
    mapped = ballgauge::calibrate(gauge, campaign.placements);
  }
  ASSERT_TRUE(mapped.grid);
  // The controller corrects with the map (held at its edges beyond them).
  map::EvalOptions clamp;
  clamp.outside = map::Outside::Clamp;
  const auto correction =
      std::make_shared<ballgauge::Correction>(ballgauge::grid_correction(*mapped.grid, clamp));
  ServerOptions corrected = serving(setup, lobing);
  corrected.engine.correction = [correction](const Eigen::Vector3d& x) {
    return correction->corrected(x);
  };
  const auto after = over_ipp(corrected, setup, eo);
  ASSERT_TRUE(after.e0.complete) << after.e0.stopped;
  EXPECT_EQ(after.e0.verdict, acceptance::Verdict::Conforms) << after.e0.summary();
  EXPECT_LT(after.e0.e0_max, before.e0.e0_max / 5)
      << before.e0.e0_max * 1e3 << " -> " << after.e0.e0_max * 1e3 << " µm";
  // The probing form after the map is the probe's own (its lobing on a perfect machine, in
  // process) but for what the map leaves of the machine's over the sphere (trilinear between
  // nodes 175 mm apart: ~0.1 µm): the map took the machine's part and cannot take the probe's.
  sim::Machine perfect;
  perfect.range = machine().range;
  perfect.offset = machine().offset;
  acceptance::VirtualProbeOptions vp;
  vp.lobing = lobing;
  const auto probe_only =
      acceptance::run_probing(setup, acceptance::virtual_touch(perfect, vp), {});
  EXPECT_NEAR(after.probing.form, probe_only.form, 0.15e-3);
  EXPECT_GT(after.probing.form, 0.8 * before.probing.form);
  std::printf("E0 over I++ DME: %.2f µm before, %.2f µm after the map; PForm %.2f / %.2f µm\n",
              before.e0.e0_max * 1e3, after.e0.e0_max * 1e3, before.probing.form * 1e3,
              after.probing.form * 1e3);
}

// The planner refuses what it cannot do safely, naming it; a face that is not where the set-up
// says stops the run with what was measured.
TEST(AcceptanceOverIpp, WhatCannotBeDoneSafelyIsNamed) {
  const auto volume = acceptance::Volume::of(machine());
  auto setup = acceptance::example_setup(volume);
  AcceptanceProbingOptions bad;
  bad.clearance = 0;
  EXPECT_NE(test::error_of([&] { bad.validate(); }).find("clearance"), std::string::npos);
  // The server's blocks 8 mm on from where the set-up puts them: face A beyond the search.
  auto moved = setup;
  for (auto& p : moved.placements) p.centre += 8 * p.direction;
  acceptance::E0Options eo;
  eo.mpe = ballgauge::Mpe::parse("2.5+L/250");
  Running server(serving(moved, 0));
  RemoteCmmOptions ro;
  ro.client = server.client();
  ro.tip_radius = 0;
  RemoteCmm cmm(ro);
  const auto r = acceptance::run_e0(setup, volume, acceptance_touch(cmm, setup, volume), eo);
  EXPECT_FALSE(r.complete);
  EXPECT_NE(r.stopped.find("is the artefact where the set-up says"), std::string::npos)
      << r.stopped;
  EXPECT_EQ(r.verdict, acceptance::Verdict::NotProven) << r.summary();  // nothing measured
}

}  // namespace trueaxis
