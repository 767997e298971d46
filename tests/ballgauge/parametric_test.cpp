// Parametric identification of the 21 rigid-body errors from ball-gauge data (beyond Oya, Hokari
// and Tamura 1988, who map error vectors only), and grid against parametric correction on
// held-out lengths.
#include "trueaxis/ballgauge/parametric.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "../test_util.hpp"
#include "test_machines.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/report/ballgauge.hpp"
#include "trueaxis/sim/ballgauge.hpp"

using namespace trueaxis;
using test::error_of;
using test::temp_dir;
using test::temp_file;

namespace {

std::vector<sim::GaugePose> oya_poses() {
  auto p = sim::stacked_poses(
      sim::frame_gauge(), 3, {150, 120, 60},
      Eigen::AngleAxisd(0.004, Eigen::Vector3d(0.2, -0.1, 1).normalized()).toRotationMatrix());
  p.front().alignment = ballgauge::Alignment::LeastSquares;
  return p;
}

// Probed points that sit exactly on a sphere about the reading of each true centre: the CMM's
// reading of a ball centre without the probing pattern's own small bias (which a gradient of
// the errors across a 28 mm hemisphere causes), so that the identification itself is tested.
std::vector<ballgauge::Placement> exact_placements(const sim::Machine& m,
                                                   const ballgauge::Gauge& g) {
  const auto c = sim::simulate_ballgauge(m, g, oya_poses(), {});
  auto pl = c.placements;
  for (std::size_t p = 0; p < pl.size(); ++p)
    for (std::size_t b = 0; b < pl[p].balls.size(); ++b) {
      const Eigen::Vector3d x = test::reading_of(m, c.true_centres[p][b]);
      auto& pts = pl[p].balls[b].points;
      const Eigen::Vector3d centre =
          pts.rowwise().mean();  // about the ball; only the shape matters
      for (Eigen::Index k = 0; k < pts.cols(); ++k) {
        const Eigen::Vector3d d = (pts.col(k) - centre).normalized();
        pts.col(k) = x + (g.ball_diameter / 2 + pl[p].tip_radius) * d;
      }
    }
  return pl;
}

sim::GaugeBlockCampaign blocks(const sim::Machine& m, const ballgauge::ParametricResult& r,
                               double noise, std::uint64_t seed, double tip_radius = 1.5) {
  sim::GaugeBlockOptions o;
  // The identified span, in true positions (command + offset), a little inside.
  for (int k = 0; k < 3; ++k) {
    o.lo[k] = r.model.range[static_cast<std::size_t>(k)][0] + m.offset[k] + 1;
    o.hi[k] = r.model.range[static_cast<std::size_t>(k)][1] + m.offset[k] - 1;
  }
  o.noise = noise;
  o.seed = seed;
  o.tip_radius = tip_radius;
  return sim::simulate_gauge_blocks(m, o);
}

ballgauge::ParametricOptions options(const sim::Machine& m) {
  ballgauge::ParametricOptions o;
  o.offset = m.offset;
  return o;
}

}  // namespace

TEST(Parametric, NoiseFreeDataOfAPolynomialMachineAreReproducedExactly) {
  const sim::Machine m = test::cubic_machine(3);
  const auto g = sim::frame_gauge();
  const auto r = ballgauge::identify(g, exact_placements(m, g), options(m));
  EXPECT_LT(r.residual_rms, 1e-10);
  EXPECT_EQ(r.balls, 120);
  // A stylus hanging straight down is not moved by the yaw of the ram (ECZ); nor is ECX seen.
  EXPECT_NE(std::find(r.unobservable.begin(), r.unobservable.end(), "ECZ"), r.unobservable.end());
  EXPECT_LT(r.rank, r.unknowns);  // the map's rigid motion is not determined
  // ... and the summary says so in words instead of printing the model's zero for them.
  const std::string summary = r.summary();
  EXPECT_NE(summary.find("n/d µrad"), std::string::npos) << summary;
  EXPECT_NE(summary.find("n/d: not determined by the data"), std::string::npos);
  // Held-out gauge blocks, noise-free: the parametric correction makes them exact (the model
  // family holds the truth, so Gauss–Newton on the exact model converges to it). Tip radius 0:
  // otherwise the end points, which the CMM compensates by r along the block, are corrected
  // r = 1.5 mm away from where the tip centre was, an error of gradient × r ≈ 0.05 µm.
  const auto gb = blocks(m, r, 0, 1, 0.0);
  const auto v = ballgauge::verify_lengths(gb.lengths, ballgauge::parametric_correction(r));
  EXPECT_GT(v.before.rms, 2e-3);
  EXPECT_LT(std::max(-v.after.min, v.after.max), 1e-9);
}

TEST(Parametric, NoisyEstimatesAgreeWithTheirStatedUncertainty) {
  // 0.5 µm probing noise on a machine the model can hold; held-out noise-free lengths, so the
  // only after-error is the model's estimation error, to be compared with its length
  // uncertainty from the parameter covariance.
  double z2 = 0;
  int n = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const sim::Machine m = test::cubic_machine(seed + 10);
    const auto g = sim::frame_gauge();
    sim::BallGaugeOptions bo;
    bo.noise = 0.5e-3;
    bo.seed = seed;
    const auto c = sim::simulate_ballgauge(m, g, oya_poses(), bo);
    const auto r = ballgauge::identify(g, c.placements, options(m));
    EXPECT_NEAR(r.sigma, 0.5e-3 * 0.55, 0.5e-3 * 0.35);  // a centre from 10 points on a hemisphere
    const auto v = ballgauge::verify_lengths(blocks(m, r, 0, seed).lengths,
                                             ballgauge::parametric_correction(r));
    for (const auto& row : v.rows) {
      z2 += std::pow(row.after / row.uncertainty, 2);
      ++n;
    }
  }
  const double z_rms = std::sqrt(z2 / n);
  EXPECT_GT(z_rms, 0.5);
  EXPECT_LT(z_rms, 2.0);
}

TEST(Parametric, GridOrParametricDependsOnWhetherTheModelHoldsTheMachine) {
  // Grid map against parametric model, on held-out noise-free gauge blocks (105 per case), mean
  // over seeds.
  auto compare = [](bool bump, double& grid, double& param, double& u_grid, double& u_param,
                    double& residual) {
    grid = param = u_grid = u_param = residual = 0;
    const int seeds = 3;
    for (int s = 0; s < seeds; ++s) {
      sim::MachineOptions mo;
      mo.seed = static_cast<std::uint64_t>(5 + s);
      sim::Machine m = sim::random_machine(mo);
      if (bump) {  // a local 4 µm positioning error in X over 160 mm (a "bump in a guide")
        auto& f = m.errors[0][0];
        f.table_u = {0, 150, 230, 310, 800};
        f.table_value = {0, 0, 4e-3, 0, 0};
      }
      const auto g = sim::frame_gauge();
      sim::BallGaugeOptions bo;
      bo.noise = 0.5e-3;
      bo.seed = static_cast<std::uint64_t>(s + 1);
      const auto c = sim::simulate_ballgauge(m, g, oya_poses(), bo);
      const auto map = ballgauge::calibrate(g, c.placements);
      const auto r = ballgauge::identify(g, c.placements, options(m));
      const auto L = blocks(m, r, 0, 7).lengths;
      const auto vg = ballgauge::verify_lengths(L, ballgauge::grid_correction(*map.grid));
      const auto vp = ballgauge::verify_lengths(L, ballgauge::parametric_correction(r));
      grid += vg.after.rms / seeds;
      param += vp.after.rms / seeds;
      u_grid += vg.correction_u_rms / seeds;
      u_param += vp.correction_u_rms / seeds;
      residual += r.residual_rms / seeds;
    }
  };
  double g0, p0, ug0, up0, res0, g1, p1, ug1, up1, res1;
  compare(false, g0, p0, ug0, up0, res0);
  compare(true, g1, p1, ug1, up1, res1);
  // Smooth machine: the parametric model averages the noise of all 120 balls over ~57
  // determined parameters; its correction is less uncertain and better.
  EXPECT_LT(up0, 0.5 * ug0);
  EXPECT_LT(p0, g0);
  // A local bump the cubics cannot follow but the 80 mm grid resolves: the grid is better, and
  // the model's ball residual says so (well above the centres' noise, ~0.3 µm here).
  EXPECT_LT(g1, p1);
  EXPECT_GT(res1, 1.3 * res0);
}

TEST(Parametric, RefusalsNameTheProblem) {
  const sim::Machine m = test::cubic_machine(3);
  const auto g = sim::frame_gauge();
  auto pl = sim::simulate_ballgauge(m, g, oya_poses(), {}).placements;
  ballgauge::ParametricOptions o = options(m);
  // One section: z is measured at only 2 positions, too few for cubics.
  const std::vector<ballgauge::Placement> one{pl[0]};
  EXPECT_NE(error_of([&] {
              ballgauge::identify(g, one, o);
            }).find("axis Z is measured at only 2 distinct positions; degree 3 needs at least 4"),
            std::string::npos);
  o.degree = 1;
  EXPECT_NO_THROW(ballgauge::identify(g, one, o));
  o.degree = 0;
  EXPECT_NE(error_of([&] { ballgauge::identify(g, pl, o); }).find("degree must be 1 to 8"),
            std::string::npos);
  o = options(m);
  o.chain = "FXXZ";
  EXPECT_THROW(ballgauge::identify(g, pl, o), Error);
  auto few = pl;
  few[1].balls.resize(2);
  EXPECT_NE(error_of([&] {
              ballgauge::identify(g, few, options(m));
            }).find("placement 2: 2 balls; a placement needs at least 3"),
            std::string::npos);
  few = pl;
  few[0].balls[4].points.conservativeResize(3, 4);
  EXPECT_NE(error_of([&] { ballgauge::identify(g, few, options(m)); }).find("4 points; at least 5"),
            std::string::npos);
  // The correction refuses points outside the identified span.
  const auto r = ballgauge::identify(g, pl, options(m));
  Eigen::Matrix3Xd p(3, 1);
  p << 700, 200, 200;
  EXPECT_NE(error_of([&] {
              ballgauge::parametric_correction(r).apply(p);
            }).find("point 1 (700.000, 200.000, 200.000) is outside the identified span"),
            std::string::npos);
}

TEST(Parametric, TheModelFileRoundTripsAndIsAMachineFile) {
  const sim::Machine m = test::cubic_machine(3);
  const auto g = sim::frame_gauge();
  sim::BallGaugeOptions bo;
  bo.noise = 0.3e-3;
  const auto r =
      ballgauge::identify(g, sim::simulate_ballgauge(m, g, oya_poses(), bo).placements, options(m));
  const std::string path = temp_dir() + "/model.json";
  io::write_parametric(path, r);
  const auto back = io::read_parametric(path);
  const auto L = blocks(m, r, 0.3e-3, 2).lengths;
  const auto v1 = ballgauge::verify_lengths(L, ballgauge::parametric_correction(r));
  const auto v2 = ballgauge::verify_lengths(L, ballgauge::parametric_correction(back));
  for (std::size_t i = 0; i < L.size(); ++i) {
    EXPECT_NEAR(v1.rows[i].after, v2.rows[i].after, 1e-12);
    EXPECT_NEAR(v1.rows[i].uncertainty, v2.rows[i].uncertainty, 1e-12);
  }
  const sim::Machine plain = io::read_machine(path);  // usable by every machine command
  EXPECT_EQ(plain.chain, "FYXZ");
  // A damaged identification is refused at its file:line:col.
  auto damaged = [&](const std::string& name, auto&& change) {
    std::ifstream in(path);
    nlohmann::ordered_json j = nlohmann::ordered_json::parse(in);
    change(j["identification"]);
    const std::string p = temp_dir() + "/" + name;
    io::write_json(p, j);
    return error_of([&] { io::read_parametric(p); });
  };
  auto located = [](const std::string& e, const std::string& file, const std::string& what) {
    return e.rfind(temp_dir() + "/" + file + ":", 0) == 0 && e.find(what) != std::string::npos;
  };
  EXPECT_TRUE(located(damaged("d1.json", [](auto& id) { id["degree"] = 2.5; }), "d1.json",
                      "degree must be a whole number 1..8"));
  EXPECT_TRUE(located(damaged("d2.json", [](auto& id) { id["parameters"].erase(0); }), "d2.json",
                      "74 parameters; degree 3 needs 75"));
  EXPECT_TRUE(located(damaged("d3.json", [](auto& id) { id["covariance"][5].erase(0); }), "d3.json",
                      "covariance row needs 75 numbers"));
  EXPECT_TRUE(located(damaged("d4.json", [](auto& id) { id["half_span"][1] = 0; }), "d4.json",
                      "half spans must be > 0 mm"));
  // A machine file without the identification is not a model.
  const std::string mp = temp_dir() + "/plain.json";
  io::write_machine(mp, m);
  EXPECT_NE(
      error_of([&] { io::read_parametric(mp); }).find("plain.json:1:1: not a parametric model"),
      std::string::npos);
}

TEST(LengthsIo, BadLengthFilesNameFileLineAndColumn) {
  const auto f =
      temp_file("l1.csv", "x1,y1,z1,x2,y2,z2,nominal\n0,0,0,100,0,0,100\n0,0,0,1,0,0,-5\n");
  EXPECT_NE(error_of([&] { io::read_lengths(f); }).find("l1.csv:3:13: nominal length -5 mm"),
            std::string::npos);
  const auto f2 = temp_file("l2.csv", "x1,y1,z1,x2,y2,z2,nominal\n1,2,3,1,2,3,10\n");
  EXPECT_NE(error_of([&] { io::read_lengths(f2); }).find("l2.csv:2:7: the two end points coincide"),
            std::string::npos);
  const auto f3 = temp_file("l3.csv", "x1,y1,z1,x2,y2,z2\n0,0,0,1,0,0\n");
  EXPECT_NE(error_of([&] { io::read_lengths(f3); }).find("nominal"), std::string::npos);
  const auto f4 = temp_file("l4.csv", "x1,y1,z1,x2,y2,z2,nominal\n0,0,zero,1,0,0,1\n");
  EXPECT_NE(error_of([&] { io::read_lengths(f4); }).find("l4.csv:2:5"), std::string::npos);
  const auto f5 = temp_file("l5.csv", "x1,y1,z1,x2,y2,z2,nominal\n");
  EXPECT_NE(error_of([&] { io::read_lengths(f5); }).find("no lengths"), std::string::npos);
  // Round trip.
  std::vector<ballgauge::LengthMeasurement> L{{{0.1, 0.2, 0.3}, {100.25, 0, 1e-9}, 100.125}};
  const std::string p = temp_dir() + "/lengths.csv";
  io::write_lengths(p, L);
  const auto back = io::read_lengths(p);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].a, L[0].a);
  EXPECT_EQ(back[0].b, L[0].b);
  EXPECT_EQ(back[0].nominal, L[0].nominal);
}

// The report's per-axis curves of the identified model: every function the data see, with a
// ±2u band from the parameter covariance; the ones they cannot see are named, not drawn as 0.
TEST(Parametric, TheReportDrawsEachAxisErrorsWithBandsAndNamesTheUnseen) {
  const sim::Machine m = test::cubic_machine(3);
  const auto g = sim::frame_gauge();
  sim::BallGaugeOptions so;
  so.noise = 0.5e-3;
  const auto c = sim::simulate_ballgauge(m, g, oya_poses(), so);
  const auto r = ballgauge::identify(g, c.placements, options(m));
  const auto map = ballgauge::calibrate(g, c.placements);
  const auto s = report::ballgauge_section("map", map, &r);
  ASSERT_EQ(s.plots.size(), 6u);  // per axis: linear and angular
  int series = 0;
  for (const auto& p : s.plots)
    for (const auto& ser : p.series) {
      ++series;
      ASSERT_EQ(ser.band.size(), ser.y.size());
      EXPECT_GT(ser.band.minCoeff(), 0);  // noisy data: a real uncertainty everywhere
    }
  EXPECT_EQ(series, 18 - static_cast<int>(r.unobservable.size()));
  EXPECT_NE(s.plots[5].title.find("not determined by the data: ECZ"), std::string::npos)
      << s.plots[5].title;
  // Squareness in a table of its own, each with U = 2u under the header that says so; the
  // placement table holds placements only.
  for (const auto& row : s.table) EXPECT_EQ(row[0].rfind("squareness", 0), std::string::npos);
  const auto sq = std::find_if(s.more_tables.begin(), s.more_tables.end(),
                               [](const auto& t) { return t.first.rfind("Squareness", 0) == 0; });
  ASSERT_NE(sq, s.more_tables.end());
  ASSERT_EQ(sq->second.size(), 4u);
  EXPECT_EQ(sq->second[0][2], "U (µrad, k = 2)");
  for (std::size_t i = 1; i < 4; ++i) EXPECT_GT(std::stod(sq->second[i][2]), 0) << i;
  // The map's levels share one colour scale, the largest |ez| of the whole map: a colour means
  // the same error on every level.
  ASSERT_GE(s.grids.size(), 2u);
  const double ez = map.grid->error.row(2).cwiseAbs().maxCoeff() * 1e3;
  int below = 0;  // levels whose own scale would have differed
  for (const auto& grid : s.grids) {
    EXPECT_EQ(grid.vmin, -ez);
    EXPECT_EQ(grid.vmax, ez);
    EXPECT_LE(grid.normal.cwiseAbs().maxCoeff(), ez);
    below += grid.normal.cwiseAbs().maxCoeff() < ez;
  }
  EXPECT_GE(below, 1);
}

// The identified error functions drawn against the machine's own: on noise-free data of a
// machine the model family holds, every function the data determine is the machine's once what
// ball-gauge data never fix (constants, straightness slopes) is taken out of both alike; the
// undetermined ones are named, not compared; squareness agrees as ISO 230-1 defines it.
TEST(Parametric, IdentifiedFunctionsMatchTheMachinesUpToWhatTheDataCannotFix) {
  constexpr double kLength = 1e-7, kAngle = 1e-9;  // mm, rad: round-off of the identification
  const sim::Machine m = test::cubic_machine(3);
  const auto g = sim::frame_gauge();
  const auto r = ballgauge::identify(g, exact_placements(m, g), options(m));
  report::Section s;
  const auto d = report::add_error_functions(s, r, m);
  EXPECT_LT(d.translation, kLength);
  EXPECT_LT(d.rotation, kAngle);
  EXPECT_LT(d.squareness, kAngle);
  ASSERT_EQ(s.plots.size(), 6u);  // per axis: translations, rotations
  ASSERT_EQ(s.more_tables.size(), 1u);
  const auto& t = s.more_tables.front().second;
  ASSERT_EQ(t.size(), 1u + 18u + 3u);
  int undetermined = 0, ram_rotations = 0;
  for (const auto& row : t) {
    const bool unseen = row[1] == "not determined by these data";
    const bool confounded = row[1].rfind("not separated", 0) == 0;
    if (unseen) {
      ++undetermined;
      EXPECT_NE(std::find(r.unobservable.begin(), r.unobservable.end(), row[0]),
                r.unobservable.end());
    }
    if (confounded) {
      EXPECT_EQ(row[0].back(), 'Z') << row[0];  // the ram carries the one stylus
    }
    if ((unseen || confounded) && row[0].back() == 'Z') ++ram_rotations;
  }
  EXPECT_EQ(undetermined, static_cast<int>(r.unobservable.size()));
  EXPECT_GE(undetermined, 1);   // ECZ: a vertical stylus does not see the ram's yaw
  EXPECT_EQ(ram_rotations, 3);  // none of the ram's rotations is told from its straightness
  // A machine that is not the one measured differs.
  EXPECT_GT(report::add_error_functions(s, r, test::cubic_machine(4)).translation, 1e-4);
}
