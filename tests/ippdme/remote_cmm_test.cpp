// The error-tolerant scanning controller over I++ DME: the same part scanned in process and
// through the server (loopback TCP) gives the same decisions and points within the probe noise.
#include "trueaxis/ippdme/remote_cmm.hpp"

#include <gtest/gtest.h>

#include "../test_parts.hpp"
#include "../test_util.hpp"
#include "serving.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/scan/controller.hpp"

namespace trueaxis {
namespace {

using namespace ippdme;
using test::Running;

constexpr double kNoise = 0.5e-3;  // probe noise, standard deviation (mm), on both sides
// The probe's noise is on its 3-D deflection, whose direction is the measured normal: across
// it the surface point moves by the tip radius over the deflection times the noise. The server
// reports scan points at 0.1 mm of deflection or more (its scans hold 0.2 mm), its single points
// at 0.2 mm. A measured point lies within 5σ of that of the true part (plus the round-off of the
// protocol's 5 decimals).
constexpr double kTipRadius = 1, kLeastDeflection = 0.1;                                  // mm
constexpr double kWithinNoise = 5 * kNoise * (1 + kTipRadius / kLeastDeflection) + 5e-6;  // mm
// Corrections fitted from touch points of either run agree within a few σ of the noise.
constexpr double kSameCorrection = 10 * kNoise;  // mm, °, or factor

const Eigen::Vector3d kHome(50, -20, 40);

ServerOptions serving(const sim::Part& part) {
  ServerOptions o = test::quick();
  o.engine.part = part;
  o.engine.cmm.home = kHome;
  o.engine.cmm.probe.noise = kNoise;
  return o;
}

RemoteCmmOptions remote(const Running& r) {
  RemoteCmmOptions o;
  o.client = r.client();
  return o;
}

std::vector<std::string> decisions(const scan::Result& r) {
  std::vector<std::string> v;
  for (const auto& e : r.events) v.push_back(e.section + " " + e.mode + " " + e.event);
  return v;
}

void expect_same_flow(const scan::Result& here, const scan::Result& there) {
  ASSERT_EQ(here.ok(), there.ok()) << here.summary() << "\n" << there.summary();
  EXPECT_EQ(decisions(here), decisions(there));
  ASSERT_EQ(here.sections.size(), there.sections.size());
  for (std::size_t i = 0; i < here.sections.size(); ++i) {
    const auto &a = here.sections[i], &b = there.sections[i];
    EXPECT_EQ(a.ok, b.ok) << a.name;
    EXPECT_EQ(a.trajectory_errors, b.trajectory_errors) << a.name;
    EXPECT_EQ(a.autonomous_count, b.autonomous_count) << a.name;
    ASSERT_EQ(a.corrections.size(), b.corrections.size()) << a.name;
    for (std::size_t k = 0; k < a.corrections.size(); ++k) {
      EXPECT_EQ(a.corrections[k].type, b.corrections[k].type) << a.name;
      EXPECT_EQ(a.corrections[k].accepted, b.corrections[k].accepted) << a.name;
      ASSERT_EQ(a.corrections[k].parameters.size(), b.corrections[k].parameters.size());
      for (std::size_t j = 0; j < a.corrections[k].parameters.size(); ++j)
        EXPECT_NEAR(a.corrections[k].parameters[j].second, b.corrections[k].parameters[j].second,
                    kSameCorrection)
            << a.name << " " << a.corrections[k].parameters[j].first;
    }
    // Both record a point about every 0.2 mm of the same contour.
    EXPECT_NEAR(static_cast<double>(a.points.size()), static_cast<double>(b.points.size()),
                0.02 * static_cast<double>(a.points.size()) + 5)
        << a.name;
  }
}

// Both runs, and the truth to check the points against.
struct Both {
  scan::Result here, there;
  double worst_there = 0;
  long commands = 0;
};

Both scan_both(const sim::Part& part, const design::Design& d) {
  Both out;
  scan::VirtualCmmOptions vo;
  vo.probe.noise = kNoise;
  scan::VirtualCmm virt(part, vo, kHome);
  out.here = scan::scan(virt, d, {});
  Running r(serving(part));
  RemoteCmm cmm(remote(r));
  out.there = scan::scan(cmm, d, {});
  out.commands = cmm.commands();
  for (std::size_t i = 0; i < out.there.sections.size(); ++i)
    for (const auto& p : out.there.sections[i].points)
      out.worst_there =
          std::max(out.worst_there, std::abs(virt.distance(d.sections[i], p.surface)));
  return out;
}

TEST(RemoteCmm, TranslatedPartGetsTheSameCorrectionOverTheProtocol) {
  const auto d = test::square_and_hole();
  sim::Part part{d, {}};
  part.deviation.translation = Eigen::Vector3d(1.8, -1.1, 0);
  const auto b = scan_both(part, d);
  ASSERT_TRUE(b.there.ok()) << b.there.summary();
  expect_same_flow(b.here, b.there);
  EXPECT_EQ(b.there.sections[0].corrections.back().type, "translation");
  EXPECT_LT(b.worst_there, kWithinNoise);
  EXPECT_GT(b.commands, 20);  // it really went through the protocol
}

TEST(RemoteCmm, LocalBumpFallsBackToAutonomousScanningOverTheProtocol) {
  const auto d = test::square_and_hole();
  sim::Part part{d, {}};
  part.deviation.bumps = {{"outer", 150, 2.0, 30}};
  const auto b = scan_both(part, d);
  ASSERT_TRUE(b.there.ok()) << b.there.summary();
  expect_same_flow(b.here, b.there);
  EXPECT_EQ(b.there.sections[0].autonomous_count, 1);
  EXPECT_LT(b.worst_there, kWithinNoise);
  // The next part of the batch, scanned over the protocol with the corrected design data, has
  // no trajectory error.
  Running r(serving(part));
  RemoteCmm cmm(remote(r));
  const auto next = scan::scan(cmm, b.there.design, {});
  ASSERT_TRUE(next.ok()) << next.summary();
  for (const auto& s : next.sections) EXPECT_EQ(s.trajectory_errors, 0) << s.name;
}

TEST(RemoteCmm, CollisionsAndMissedSurfacesAreReportedAsTheControllerExpects) {
  const auto d = test::square_and_hole();
  Running r(serving(sim::Part{d, {}}));
  RemoteCmm cmm(remote(r));
  EXPECT_NEAR((cmm.position() - kHome).norm(), 0, 1e-3);
  // Down through the part's outline: a collision, as an Error naming it.
  const auto& s = d.sections[0];
  const Eigen::Vector3d on = s.plane.origin;
  try {
    cmm.move(Eigen::Vector3d(kHome.x(), kHome.y(), on.z()), 100);
    cmm.move(Eigen::Vector3d(kHome.x(), 200, on.z()), 100);
    ADD_FAILURE() << "a move through the part was not refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("collision"), std::string::npos) << e.what();
  }
  // Slowly, the server's probe stops the move within its overtravel (1001): an unexpected
  // touch, where the machine stopped, that the controller backs off from.
  cmm.move(kHome, 100);
  try {
    cmm.move(Eigen::Vector3d(kHome.x(), kHome.y(), on.z()), 20);
    cmm.move(Eigen::Vector3d(kHome.x(), 200, on.z()), 20);
    ADD_FAILURE() << "a slow move through the part was not stopped";
  } catch (const scan::UnexpectedTouch& e) {
    EXPECT_NE(std::string(e.what()).find("1001"), std::string::npos) << e.what();
    EXPECT_NEAR((e.at - cmm.position()).norm(), 0, 1e-3);
  }
  // After the error the session goes on: a touch into empty space finds nothing (1006).
  cmm.move(Eigen::Vector3d(kHome.x(), kHome.y(), on.z()), 20);
  cmm.move(kHome, 100);
  const auto none = cmm.touch(s.plane, kHome, Eigen::Vector3d::UnitZ(), 5, 10, 0.3);
  EXPECT_FALSE(none.has_value());
  EXPECT_NEAR((cmm.position() - kHome).norm(), 0, 1e-3);
}

// A real CMM keeps its position between sessions: the second scan on the same server starts
// where the first ended (down in NIST's part's hole), and its first move must rise clear of the
// part's solid before it goes across.
TEST(RemoteCmm, TwoSessionsInARowOnOneServer) {
  const std::string step = std::string(TRUEAXIS_TEST_DATA) + "/ippdme/ipp_simple.stp";
  const auto d =
      design::from_step(step, {{"mid", {Eigen::Vector3d(0, 0, 37.5), Eigen::Vector3d::UnitZ()}}});
  sim::Part part{d, {}};
  part.deviation.translation = Eigen::Vector3d(1.8, -1.1, 0);
  ServerOptions so = serving(part);
  so.engine.cmm.home = scan::start_position(d, {});
  Running r(so);
  for (int session = 1; session <= 2; ++session) {
    RemoteCmm cmm(remote(r));
    const auto res = scan::scan(cmm, d, {});
    ASSERT_TRUE(res.ok()) << session << ": " << res.summary();
    if (session == 1) {
      // It ended in the hole, below the part's top.
      EXPECT_LT(cmm.position().z(), 50) << cmm.position().transpose();
    }
  }
}

// A server older than I++ DME 1.4.2 has no ScanOnCurve (nor Tool.ScanPar, Tool.AvrRadius): the
// server double refuses them (0501), and the client scans point by point instead. The part
// moved in its fixture is corrected by the same flow as over ScanOnCurve, every point lies on the
// true part within the probe's noise, and no ScanOnCurve was sent.
TEST(RemoteCmm, AServerBefore142IsScannedPointByPoint) {
  const auto d = test::square_and_hole();
  sim::Part part{d, {}};
  part.deviation.translation = Eigen::Vector3d(1.8, -1.1, 0);
  ServerOptions so = serving(part);
  so.engine.version = "1.4.1";
  Running r(so);
  {
    // What the server does not have, it refuses: nothing runs that a 1.4.1 server would not.
    Client raw(r.client());
    ASSERT_TRUE(raw.call("StartSession()").errors.empty());
    for (const char* newer : {"GetProp(Tool.AvrRadius())", "SetProp(Tool.ScanPar.Speed(10))",
                              "ScanOnCurveDensity(Dis(0.2))"}) {
      const auto tr = raw.call(newer);
      ASSERT_FALSE(tr.errors.empty()) << newer;
      EXPECT_EQ(tr.errors.front().items.at(0).args.at(1).number(), 501) << newer;
      raw.call("ClearAllErrors()");
    }
    raw.call("EndSession()");
  }
  // Without a tip radius the client cannot ask a 1.4.1 server for one: refused by name.
  RemoteCmmOptions o = remote(r);
  o.tip_radius = 0;
  const auto err = test::error_of([&] { RemoteCmm{o}; });
  EXPECT_NE(err.find("speaks I++ DME 1.4.1, which has no Tool.AvrRadius"), std::string::npos)
      << err;

  o.tip_radius = kTipRadius;
  o.point_step = 2;  // mm: enough points to judge, in a test's time
  RemoteCmm cmm(o);
  EXPECT_EQ(cmm.version(), "1.4.1");
  EXPECT_TRUE(cmm.scans_by_points());
  const auto res = scan::scan(cmm, d, {});
  ASSERT_TRUE(res.ok()) << res.summary();
  scan::VirtualCmmOptions vo;
  scan::VirtualCmm truth(part, vo, kHome);
  double worst = 0;
  std::size_t points = 0;
  for (std::size_t i = 0; i < res.sections.size(); ++i) {
    EXPECT_TRUE(res.sections[i].ok) << res.sections[i].name << ": " << res.sections[i].reason;
    for (const auto& p : res.sections[i].points)
      worst = std::max(worst, std::abs(truth.distance(d.sections[i], p.surface)));
    points += res.sections[i].points.size();
  }
  EXPECT_LT(worst, kWithinNoise);
  EXPECT_GT(static_cast<double>(points), 0.8 * 557 / o.point_step);  // a point every step
  EXPECT_EQ(res.sections[0].corrections.back().type, "translation");
  EXPECT_TRUE(res.sections[0].corrections.back().accepted);
}

// A server whose version is no version is not guessed at: refused, with what it said.
TEST(RemoteCmm, AServerThatGivesNoVersionIsRefused) {
  ServerOptions so = serving(sim::Part{test::square_and_hole(), {}});
  so.engine.version = "unknown";
  Running r(so);
  const auto err = test::error_of([&] { RemoteCmm cmm(remote(r)); });
  EXPECT_NE(err.find("does not say which I++ DME it speaks ('unknown' is not a version)"),
            std::string::npos)
      << err;
}

// A 1.4.2 server scans along the design, but has no 1.4.3 ScanInPlaneEndIsSphere: a section that
// needs an autonomous scan ends with the reason, the others are scanned.
TEST(RemoteCmm, AnAutonomousScanOnA142ServerEndsItsSectionWithTheReason) {
  const auto d = test::square_and_hole();
  sim::Part part{d, {}};
  part.deviation.bumps = {{"outer", 150, 2.0, 30}};  // needs an autonomous scan
  ServerOptions so = serving(part);
  so.engine.version = "1.4.2";
  Running r(so);
  RemoteCmm cmm(remote(r));
  EXPECT_EQ(cmm.version(), "1.4.2");
  EXPECT_FALSE(cmm.scans_by_points());
  const auto res = scan::scan(cmm, d, {});
  EXPECT_FALSE(res.sections[0].ok);
  EXPECT_NE(res.sections[0].reason.find("needs ScanInPlaneEndIsSphere of I++ DME 1.4.3"),
            std::string::npos)
      << res.sections[0].reason;
  EXPECT_TRUE(res.sections[1].ok) << res.sections[1].reason;  // the hole needs none
  // The head is not turned over I++ DME: a section with a probe orientation is refused, the
  // run goes on.
  EXPECT_NE(test::error_of([&] { cmm.orient(Eigen::Vector3d(1, 0, 0)); }).find("not supported"),
            std::string::npos);
}

TEST(RemoteCmm, ABadAddressOrOptionIsNamed) {
  RemoteCmmOptions o;
  o.tip_radius = -1;
  EXPECT_NE(test::error_of([&] { RemoteCmm{o}; }).find("tip radius"), std::string::npos);
  RemoteCmmOptions step;
  step.point_step = 0;
  EXPECT_NE(test::error_of([&] { RemoteCmm{step}; }).find("point step"), std::string::npos);
  RemoteCmmOptions speed;
  speed.point_speed = -10;
  EXPECT_NE(test::error_of([&] { RemoteCmm{speed}; }).find("point speed"), std::string::npos);
  RemoteCmmOptions closed;
  closed.client.port = 1;  // nothing listens there
  const auto err = test::error_of([&] { RemoteCmm{closed}; });
  EXPECT_NE(err.find("127.0.0.1:1"), std::string::npos) << err;
}

}  // namespace
}  // namespace trueaxis
