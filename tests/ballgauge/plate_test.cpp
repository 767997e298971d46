// Ball plates: the 2-D gauge, its 3-2-1 frame (ball 0, the end of the first row, the first ball
// of the last row), a plate's map on its plane, and plate campaigns (flat at two heights, upright
// along X and along Y) that identify the 21 rigid-body errors. Golden data: the XZ plate
// measurement published by the Measurement Standards Laboratory of New Zealand with its open CMM
// error-map code.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "../test_util.hpp"
#include "test_machines.hpp"
#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/ballgauge/parametric.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/surface/space.hpp"
#include "trueaxis/map/error_map.hpp"
#include "trueaxis/sim/ballgauge.hpp"

using namespace trueaxis;

namespace {

// One row of MSL's fulldata.csv: the plate's nominal ball centre in the CMM (mm), the CMM's error
// there (mm), the nominal in the plate frame and the deviation in the plate frame (mm).
struct MslBall {
  Eigen::Vector3d cmm_nominal, cmm_deviation, plate_nominal, plate_deviation;
};

std::vector<MslBall> read_msl_plate() {
  std::ifstream in(std::string(TRUEAXIS_TEST_DATA) + "/msl-plate/fulldata.csv");
  EXPECT_TRUE(in.good());
  std::string line;
  while (std::getline(in, line) && line.rfind("id,", 0) != 0) {
  }
  std::vector<MslBall> out;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(s, cell, ',')) v.push_back(std::stod(cell));
    EXPECT_EQ(v.size(), 13u) << line;
    if (v.size() != 13) break;
    EXPECT_EQ(v[0], static_cast<double>(out.size()));
    MslBall b;
    b.cmm_nominal = {v[1], v[2], v[3]};
    b.cmm_deviation = {v[4], v[5], v[6]};
    b.plate_nominal = {v[7], v[8], v[9]};
    b.plate_deviation = {v[10], v[11], v[12]};
    out.push_back(b);
  }
  return out;
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

}  // namespace

TEST(BallPlate, FrameBallsOfAPlateListedRowByRow) {
  // Balls 0, 1, 2 of a plate lie on its first row: the frame is ball 0, the row's far end and
  // the first ball of the last row, whatever the plate's size.
  EXPECT_EQ(sim::plate_gauge(5, 5, 133).frame_balls(), (std::array<int, 3>{0, 4, 20}));
  EXPECT_EQ(sim::plate_gauge(4, 6, 50).frame_balls(), (std::array<int, 3>{0, 5, 18}));
  // A 3-D frame keeps balls 0, 1, 2; a named frame is used as named.
  EXPECT_EQ(sim::frame_gauge().frame_balls(), (std::array<int, 3>{0, 1, 2}));
  auto g = sim::plate_gauge(5, 5, 133);
  g.frame = {24, 20, 0};
  EXPECT_EQ(g.frame_balls(), (std::array<int, 3>{24, 20, 0}));
  g.frame = {0, 1, 3};  // one row: no plane
  EXPECT_NE(test::error_of([&] { g.validate(); }).find("balls 0, 1 and 3 must span a plane"),
            std::string::npos);
  // A ball bar fixes no plane, and says so.
  ballgauge::Gauge bar;
  bar.ball_diameter = 20;
  bar.balls = {{0, 0, 0}, {100, 0, 0}, {200, 0, 0}, {300, 0, 0}};
  EXPECT_NE(test::error_of([&] { bar.validate(); }).find("all the balls lie on one line"),
            std::string::npos);
}

// MSL's XZ plate (a KOBA 5 × 5 plate at 133 mm, standing in the CMM's XZ plane at y = 316 mm):
// the CMM's deviations at each ball, and MSL's deviations of the plate in its own frame (ball 0
// at the origin, ball 4 on its x axis, ball 20 in its xy plane). The ball centres as the CMM
// measured them, given as fitted centres, must map to MSL's plate-frame deviations: the same
// 3-2-1 frame on a vertical plate, to the file's rounding.
TEST(BallPlate, MslXzPlateMatchesItsPublishedPlateFrameDeviations) {
  constexpr double kRounding = 2e-5;  // mm: the file's 1e-5 mm digits, three values per figure
  const auto msl = read_msl_plate();
  ASSERT_EQ(msl.size(), 25u);
  const std::string dir = test::temp_dir();
  write_text(dir + "/gauge.json",
             R"({"ball_diameter": 22, "plate": {"rows": 5, "columns": 5, "pitch": 133}})");
  std::string balls;
  for (std::size_t i = 0; i < msl.size(); ++i) {
    const Eigen::Vector3d x = msl[i].cmm_nominal + msl[i].cmm_deviation;
    balls += fmt::format("{}{{\"index\": {}, \"centre\": [{:.5f}, {:.5f}, {:.5f}]}}", i ? ", " : "",
                         i, x.x(), x.y(), x.z());
  }
  write_text(
      dir + "/measurements.json",
      R"({"placements": [{"name": "Plate XZ", "alignment": "321", "balls": [)" + balls + "]}]}");
  const auto gauge = io::read_gauge(dir + "/gauge.json");
  const auto placements = io::read_measurements(dir + "/measurements.json", &gauge);
  const auto r = ballgauge::calibrate(gauge, placements);
  ASSERT_EQ(r.points.size(), 25u);
  // The plate frame from the measured frame balls: MSL's deviations are the map's error vectors
  // expressed in it.
  auto x = [&](int i) {
    return msl[static_cast<std::size_t>(i)].cmm_nominal +
           msl[static_cast<std::size_t>(i)].cmm_deviation;
  };
  Eigen::Matrix3d C;
  C.col(0) = (x(4) - x(0)).normalized();
  const Eigen::Vector3d d = x(20) - x(0);
  C.col(1) = (d - d.dot(C.col(0)) * C.col(0)).normalized();
  C.col(2) = C.col(0).cross(C.col(1));
  double worst = 0, largest = 0;
  for (const auto& p : r.points) {
    const auto& b = msl[static_cast<std::size_t>(p.ball)];
    const Eigen::Vector3d in_plate = C.transpose() * p.error;
    worst = std::max(worst, (in_plate - b.plate_deviation).cwiseAbs().maxCoeff());
    largest = std::max(largest, b.plate_deviation.cwiseAbs().maxCoeff());
    EXPECT_LT((in_plate - b.plate_deviation).cwiseAbs().maxCoeff(), kRounding) << "ball " << p.ball;
  }
  EXPECT_GT(largest, 1e-2);  // MSL's deviations reach 12 µm: the comparison is not of zeros
  // Centres given without an uncertainty: none is stated, not zero.
  EXPECT_FALSE(r.points[5].uncertainty.allFinite());
  EXPECT_NE(r.summary().find("uncertainty not stated"), std::string::npos) << r.summary();
  // The map holds the plate's plane y = 316 mm: a 5 × 5 grid there, used on that plane.
  ASSERT_TRUE(r.grid);
  EXPECT_EQ(r.grid->plane, 1);
  EXPECT_EQ(r.grid->size(0), 5);
  EXPECT_EQ(r.grid->size(2), 5);
  EXPECT_TRUE(r.grid->uncertainty.size() == 0);
  EXPECT_NE(r.summary().find("5 x 5 grid in the plane y = 316.0"), std::string::npos)
      << r.summary();
  const auto correction = ballgauge::grid_correction(*r.grid);
  Eigen::Matrix3Xd p(3, 2);
  p.col(0) = x(12);
  p.col(1) = x(12) + Eigen::Vector3d(0, 3, 0);  // 3 mm off the plane: within its band
  correction.apply(p);
  // The grid's nodes are the clusters' mean nominal positions, a few µm from the ball, where the
  // error differs by (error gradient, ~2e-5) × (a few µm).
  constexpr double kNodeOffset = 1e-6;  // mm
  const auto& mid = r.points[12];
  EXPECT_LT((p.col(0) - mid.nominal).norm(), kNodeOffset);
  EXPECT_LT((p.col(1) - mid.nominal - Eigen::Vector3d(0, 3, 0)).norm(), kNodeOffset);
  Eigen::Matrix3Xd off(3, 1);
  off.col(0) = x(12) + Eigen::Vector3d(0, 40, 0);
  const std::string e = test::error_of([&] { correction.apply(off); });
  EXPECT_NE(e.find("mm off the plane y = 316.00"), std::string::npos) << e;
  EXPECT_NE(e.find("used within 5 mm of its plane"), std::string::npos) << e;
  // The map file keeps the plane, and reads back as the same map.
  io::write_ballgauge_map(dir + "/map.json", r);
  const auto back = io::read_error_map(dir + "/map.json");
  EXPECT_EQ(back.plane, 1);
  EXPECT_LT((back.error - r.grid->error).cwiseAbs().maxCoeff(), 1e-12);
}

// A plate campaign on the virtual CMM: flat at two heights with the vertical stylus, upright
// along X and along Y probed from both sides with the stylus turned horizontal, each placement
// aligned by itself. Each maps in its own 3-2-1 frame (the machine's errors at its stylus up to
// that frame's rigid motion, to round-off); together they identify the 21 errors, which correct
// held-out gauge blocks anywhere in the box the plates span.
TEST(BallPlate, CampaignOfSixPlacementsIdentifiesTheMachine) {
  constexpr double kRoundOff = 1e-10;  // mm: noise-free, exact rotations
  const sim::Machine m = test::cubic_machine(21);
  const auto plate = sim::plate_gauge(5, 5, 100);
  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(0.003, Eigen::Vector3d(0.3, -0.2, 1).normalized()).toRotationMatrix();
  const auto poses = sim::plate_poses(plate, m, 20, tilt);
  ASSERT_EQ(poses.size(), 6u);
  EXPECT_EQ(poses[2].name, "XZ from -Y");
  EXPECT_EQ(poses[5].name, "YZ from -X");
  EXPECT_EQ(*poses[2].stylus_offset, Eigen::Vector3d(0, m.offset.norm(), 0));
  EXPECT_EQ(poses[2].pole, Eigen::Vector3d(0, -1, 0));
  const auto c = sim::simulate_ballgauge(m, plate, poses, {});
  const auto r = ballgauge::calibrate(plate, c.placements);
  EXPECT_EQ(r.frames, 6);
  EXPECT_FALSE(r.grid);  // six frames: no common map
  EXPECT_NE(r.summary().find("in 6 separate frames"), std::string::npos) << r.summary();
  for (int f = 0; f < 6; ++f) {
    SCOPED_TRACE(poses[static_cast<std::size_t>(f)].name);
    Eigen::MatrixXd truth(3, 25), nominal(3, 25);
    Eigen::Index n = 0;
    for (const auto& p : r.points)
      if (p.frame == f) {
        nominal.col(n) = p.nominal;
        truth.col(n) = c.true_centres[static_cast<std::size_t>(f)][static_cast<std::size_t>(n)];
        ++n;
      }
    ASSERT_EQ(n, 25);
    const Eigen::Matrix4d T = Eigen::umeyama(truth, nominal, false);
    const Eigen::MatrixXd moved =
        (T.topLeftCorner<3, 3>() * truth).colwise() + Eigen::Vector3d(T.topRightCorner<3, 1>());
    EXPECT_LT((moved - nominal).cwiseAbs().maxCoeff(), kRoundOff);
  }
  // The 21 errors from the six placements. From the CMM's readings of the true centres, the
  // identification is exact: noise-free lengths anywhere in the box the plates span are corrected
  // to round-off (the model's cubics hold this machine). The horizontal styli feel the rolls ECX
  // and ECZ, which the vertical one does not.
  auto exact = c.placements;
  for (std::size_t p = 0; p < exact.size(); ++p)
    for (std::size_t b = 0; b < exact[p].balls.size(); ++b) {
      exact[p].balls[b].centre = test::reading_of(m, c.true_centres[p][b], exact[p].stylus_offset);
      exact[p].balls[b].points.resize(3, 0);
    }
  ballgauge::ParametricOptions po;
  po.offset = m.offset;
  const auto model = ballgauge::identify(plate, exact, po);
  EXPECT_EQ(model.placements, 6);
  // mm: Gauss–Newton stops where its step vanishes (~1e-10 mm).
  constexpr double kSolved = 1e-9;
  // mm: directions the data see less than 1e-5 as strongly as the best-seen ones are left
  // undetermined (they would carry 1e5 times the noise); the machine's share of them stays in the
  // straightness figures and the lengths at a few 1e-9 mm.
  constexpr double kUndetermined = 1e-8;
  EXPECT_LT(model.residual_rms, kSolved);
  EXPECT_TRUE(model.unobservable.empty());
  ASSERT_EQ(model.styli.size(), 5u);  // vertical, then ±Y and ±X
  EXPECT_EQ(model.styli[0].placements, (std::vector<std::string>{"XY low", "XY high"}));
  EXPECT_NE(model.summary().find("5 styli: (0, 0, -100) mm in XY low, XY high; (0, 100, 0) mm in "
                                 "XZ from -Y"),
            std::string::npos)
      << model.summary();
  // Its ISO 230-1 figures (straightness about the reference lines, squareness between them) are
  // the machine's own over the same span, whatever split of slopes the identification chose.
  sim::Machine truth = m;
  truth.range = model.model.range;
  const auto expected = sim::reference_lines(truth, model.centre);
  EXPECT_NEAR(model.iso.lines.c0y, expected.c0y, 1e-9);
  EXPECT_NEAR(model.iso.lines.b0z, expected.b0z, 1e-9);
  EXPECT_NEAR(model.iso.lines.a0z, expected.a0z, 1e-9);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 2; ++j)
      EXPECT_NEAR(
          model.iso.lines.straightness[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)],
          expected.straightness[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)],
          kUndetermined);
  sim::GaugeBlockOptions go;
  for (int k = 0; k < 3; ++k) {
    go.lo[k] = model.model.range[static_cast<std::size_t>(k)][0] + m.offset[k] + 1;
    go.hi[k] = model.model.range[static_cast<std::size_t>(k)][1] + m.offset[k] - 1;
  }
  go.tip_radius = 0;  // the end points are where the tip centre was
  const auto blocks = sim::simulate_gauge_blocks(m, go);
  const auto v = ballgauge::verify_lengths(blocks.lengths, ballgauge::parametric_correction(model));
  EXPECT_GT(v.before.rms, 1e-3);
  EXPECT_LT(std::max(-v.after.min, v.after.max), kUndetermined);
  // From the probed points themselves, each centre carries the probing pattern's small bias (the
  // errors' gradient across a ball's hemisphere, ~0.003 µm here): the lengths' errors still drop
  // more than twentyfold.
  const auto probed = ballgauge::identify(plate, c.placements, po);
  const auto w =
      ballgauge::verify_lengths(blocks.lengths, ballgauge::parametric_correction(probed));
  EXPECT_LT(w.after.rms, 0.05 * w.before.rms);
}

// Upright plates probed from one side only: a Z scale error and the ram's pitch and yaw growing
// along Z move every horizontal tip alike, and the flat placements' vertical stylus cannot tell
// them apart either, yet they move the vertical tip the model is for. The identification refuses,
// naming them, instead of correcting Z lengths with a scale the data never saw. Given the
// vertical stylus as the model's, a campaign probed with it alone is accepted as before.
TEST(BallPlate, UprightPlatesProbedFromOneSideCannotGiveTheVerticalStylusModel) {
  const sim::Machine m = test::cubic_machine(22);
  const auto plate = sim::plate_gauge(5, 5, 100);
  auto poses = sim::plate_poses(plate, m, 20);
  poses.erase(std::remove_if(poses.begin(), poses.end(),
                             [](const sim::GaugePose& q) {
                               return q.name == "XZ from +Y" || q.name == "YZ from -X";
                             }),
              poses.end());
  ASSERT_EQ(poses.size(), 4u);
  const auto c = sim::simulate_ballgauge(m, plate, poses, {});
  ballgauge::ParametricOptions po;
  po.offset = m.offset;
  const std::string e = test::error_of([&] { ballgauge::identify(plate, c.placements, po); });
  EXPECT_NE(e.find("cannot tell EZZ"), std::string::npos) << e;
  EXPECT_NE(e.find("EAZ"), std::string::npos) << e;
  EXPECT_NE(e.find("EBZ"), std::string::npos) << e;
  EXPECT_NE(e.find("the stylus the model is for, (0, 0, -100) mm"), std::string::npos) << e;
  EXPECT_NE(e.find("from both sides"), std::string::npos) << e;
  // The same plates probed from above (the vertical stylus throughout) identify the machine.
  const auto above = sim::simulate_ballgauge(
      m, plate, sim::plate_poses(plate, m, 20, Eigen::Matrix3d::Identity(), false), {});
  const auto model = ballgauge::identify(plate, above.placements, po);
  EXPECT_EQ(model.styli.size(), 1u);
  EXPECT_EQ(model.unobservable, (std::vector<std::string>{"ECX", "ECZ"}));
  // A probing pole that is not a direction is refused, naming the placement.
  auto bad = poses;
  bad[1].pole = Eigen::Vector3d(0, 0, 2);
  EXPECT_NE(test::error_of([&] {
              sim::simulate_ballgauge(m, plate, bad, {});
            }).find("XY high: the probing pole must be a unit vector"),
            std::string::npos);
}

// With probing noise, the plate campaign's squareness estimates agree with the machine's ISO
// squareness within their stated uncertainty.
TEST(BallPlate, CampaignSquarenessAgreesWithItsStatedUncertainty) {
  constexpr double kNoise = 0.3e-3;  // mm per coordinate of every probed point
  double z2 = 0;
  int n = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const sim::Machine m = test::cubic_machine(30 + seed);
    const auto plate = sim::plate_gauge(5, 5, 100);
    sim::BallGaugeOptions bo;
    bo.noise = kNoise;
    bo.seed = seed;
    const auto c = sim::simulate_ballgauge(m, plate, sim::plate_poses(plate, m, 20), bo);
    ballgauge::ParametricOptions po;
    po.offset = m.offset;
    const auto model = ballgauge::identify(plate, c.placements, po);
    sim::Machine truth = m;
    truth.range = model.model.range;
    const auto expected = sim::reference_lines(truth, model.centre);
    const double est[3] = {model.iso.lines.c0y, model.iso.lines.b0z, model.iso.lines.a0z};
    const double tru[3] = {expected.c0y, expected.b0z, expected.a0z};
    const double u[3] = {model.iso.u_c0y, model.iso.u_b0z, model.iso.u_a0z};
    for (int i = 0; i < 3; ++i) {
      ASSERT_GT(u[i], 0);
      z2 += std::pow((est[i] - tru[i]) / u[i], 2);
      ++n;
    }
  }
  // The probing pattern's own bias adds a little to the noise; the z-scores' RMS stays near 1.
  const double z_rms = std::sqrt(z2 / n);
  EXPECT_LT(z_rms, 2.0);
  EXPECT_GT(z_rms, 0.3);
}
