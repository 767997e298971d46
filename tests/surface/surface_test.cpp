// Error surfaces from line networks: Moody's published tables, and noise-free networks on a known
// surface (Moody 1955; two-point networks).
#include "trueaxis/surface/surface.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/surface/surface.hpp"

using namespace trueaxis;
using surface::Line;
using surface::Method;

namespace {

const std::string kMoody = TRUEAXIS_TEST_DATA "/moody";
// Moody's reference program worked in single precision with pi ~ 3.141592: agreement to
// +-0.01 in his units (tens of microinches) is the published precision.
constexpr double kMoodyTol = 0.01;
constexpr double kRoundOff = 1e-12;  // mm, for noise-free networks of ~1 m

struct Published {
  double x, y, h;
};
std::map<std::string, std::vector<Published>> read_gnuplot() {
  std::ifstream in(kMoody + "/gnuplot.dat");
  std::map<std::string, std::vector<Published>> out;
  std::string line, current;
  while (std::getline(in, line)) {
    if (line.rfind("# ", 0) == 0 && line.size() > 6 && line.substr(line.size() - 4) == ".txt") {
      current = line.substr(2, line.size() - 6);
      continue;
    }
    std::istringstream ss(line);
    Published p;
    if (!current.empty() && (ss >> p.x >> p.y >> p.h)) out[current].push_back(p);
  }
  return out;
}

// A smooth "true" plate: heights in mm over x, y in mm.
double truth(double x, double y) {
  return 1e-3 * (2 * std::sin(x / 180) + 1.5 * std::cos(y / 130 + 0.4) +
                 0.8 * std::sin((x + y) / 95) + 3e-6 * x * y);
}

// Samples a line on the true surface and adds an arbitrary offset and tilt (what a straightness
// measurement cannot fix).
Line sample(const std::string& name, Eigen::Vector2d start, Eigen::Vector2d end, long n,
            std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Line l;
  l.name = name;
  l.start = start;
  l.direction = (end - start).normalized();
  l.spacing = (end - start).norm() / static_cast<double>(n - 1);
  l.heights.resize(n);
  const double a = 5e-3 * u(rng), b = 1e-5 * u(rng);
  for (long k = 0; k < n; ++k) {
    const Eigen::Vector2d p = l.station(k);
    l.heights[k] = truth(p.x(), p.y()) + a + b * static_cast<double>(k);
  }
  return l;
}

// Max |result − truth| after removing the LS fit of `modes` (1, x, y and optionally x·y).
double error_after(const surface::Result& r, bool remove_twist) {
  const long m = static_cast<long>(r.points.size());
  Eigen::MatrixXd B(m, remove_twist ? 4 : 3);
  Eigen::VectorXd e(m);
  for (long i = 0; i < m; ++i) {
    const auto& p = r.points[static_cast<std::size_t>(i)];
    const double x = p.xy.x() / 1000, y = p.xy.y() / 1000;
    B(i, 0) = 1;
    B(i, 1) = x;
    B(i, 2) = y;
    if (remove_twist) B(i, 3) = x * y;
    e[i] = p.height - truth(p.xy.x(), p.xy.y());
  }
  const Eigen::VectorXd c = B.colPivHouseholderQr().solve(e);
  return (e - B * c).cwiseAbs().maxCoeff();
}

std::vector<Line> grid_lines(bool diagonal, std::mt19937& rng) {
  // x lines every 100 mm in y over 0..800 x 0..600 (stations every 50 mm), the two boundary
  // y lines and one inner y line (stations every 100 mm), and a 45-degree diagonal whose
  // stations fall on the x lines' stations (crossings between stations would be interpolated).
  std::vector<Line> lines;
  for (int j = 0; j <= 6; ++j)
    lines.push_back(sample(fmt::format("x{}", j), {0, 100.0 * j}, {800, 100.0 * j}, 17, rng));
  lines.push_back(sample("left", {0, 0}, {0, 600}, 7, rng));
  lines.push_back(sample("mid", {400, 0}, {400, 600}, 7, rng));
  lines.push_back(sample("right", {800, 0}, {800, 600}, 7, rng));
  if (diagonal) lines.push_back(sample("diag", {0, 0}, {600, 600}, 13, rng));
  return lines;
}

}  // namespace

TEST(MoodySurface, ReproducesThePublishedTables) {
  const surface::MoodyData d = io::read_moody(kMoody);
  EXPECT_DOUBLE_EQ(d.foot_spacing, 4 * 25.4);
  const auto r = surface::moody(d);
  const auto pub = read_gnuplot();
  ASSERT_EQ(pub.size(), 8u);
  std::size_t compared = 0;
  double worst = 0;
  for (const auto& p : r.points) {
    const std::string& name = r.lines[static_cast<std::size_t>(p.line)];
    const auto& rows = pub.at(name);
    ASSERT_LT(static_cast<std::size_t>(p.station), rows.size()) << name;
    const Published& want = rows[static_cast<std::size_t>(p.station)];
    // Coordinates in station units, heights in tens of microinches.
    EXPECT_NEAR(p.xy.x() / d.foot_spacing, want.x, 1e-9) << name << " " << p.station;
    EXPECT_NEAR(p.xy.y() / d.foot_spacing, want.y, 1e-9) << name << " " << p.station;
    const double h = p.height / 25.4 * 1e5;
    worst = std::max(worst, std::abs(h - want.h));
    EXPECT_NEAR(h, want.h, kMoodyTol) << name << " station " << p.station;
    ++compared;
  }
  std::size_t published = 0;
  for (const auto& [n, rows] : pub) published += rows.size();
  EXPECT_EQ(compared, published);
  std::printf("Moody: %zu heights, worst difference %.4f (tens of microinches)\n", compared, worst);
}

TEST(MoodySurface, LeastSquaresReportsClosureAndAgreesWithTheWorksheet) {
  const auto d = io::read_moody(kMoody);
  const auto classic = surface::moody(d);
  const auto lsq = surface::moody(d, true);
  EXPECT_EQ(lsq.method, "moody-lsq");
  EXPECT_EQ(lsq.crossings.size(), classic.crossings.size());
  // With a diagonal the twist is observable: only the plane is free.
  EXPECT_EQ(lsq.unobservable, std::vector<std::string>{"plane"});
  EXPECT_GT(lsq.closure_rms, 0);
  // Least squares spreads the closure that the worksheet puts at the centre-line ends, so its
  // largest crossing residual is smaller.
  EXPECT_LT(lsq.closure_max, classic.closure_max);
  // The two surfaces differ by about the closure, not more (compare about their LS planes).
  EXPECT_NEAR(lsq.flatness_ls, classic.flatness_ls, 3 * classic.closure_max);
  // The readings' noise is what the lines' disagreement at the 22 crossings shows (9 closure
  // conditions beyond what assembles the lines): both assemblies see the same reading noise, and
  // state the flatness with its U. In the JSON, U_um and resolved, with the basis.
  ASSERT_TRUE(classic.U && lsq.U);
  EXPECT_EQ(lsq.redundancy, 9);
  EXPECT_EQ(classic.redundancy, 9);
  EXPECT_EQ(lsq.sigma_unit, "arc-second");
  EXPECT_NEAR(lsq.sigma, classic.sigma, 0.3 * lsq.sigma);
  EXPECT_GT(lsq.sigma, 0.05);  // arc-second: an autocollimator's, not round-off
  EXPECT_LT(lsq.sigma, 0.5);
  EXPECT_TRUE(*lsq.resolved());
  EXPECT_NE(lsq.summary().find("U = 1.3 µm (95 %)"), std::string::npos) << lsq.summary();
  EXPECT_NE(lsq.summary().find("from the closure at 22 crossings (9 degrees of freedom)"),
            std::string::npos)
      << lsq.summary();
  const std::string out = test::temp_dir() + "/moody-lsq.json";
  io::write_surface(out, lsq);
  const std::string json = test::read_file(out);
  EXPECT_NE(json.find("\"U_um\": 1.25"), std::string::npos);
  EXPECT_NE(json.find("\"resolved\": true"), std::string::npos);
  EXPECT_NE(json.find("\"degrees_of_freedom\": 9"), std::string::npos);
  EXPECT_EQ(json.find("no_uncertainty"), std::string::npos);
  std::printf("Moody closure: worksheet max %.4f µm; least squares RMS %.4f µm, max %.4f µm\n",
              classic.closure_max * 1e3, lsq.closure_rms * 1e3, lsq.closure_max * 1e3);
}

// Lines of an odd number of readings: a middle falls between two stations, and its height is
// interpolated there (the mean of the two beside it), as the worksheet does. Even counts recover
// a known surface exactly (up to the plane the method cannot see); odd counts to the accuracy of
// that interpolation, h²/8·|z''| per middle (h the station spacing), two of them compounding.
TEST(MoodySurface, OddAndEvenReadingCountsRecoverAKnownSurface) {
  constexpr double kArcsec = M_PI / 648000;      // rad
  constexpr double kFoot = 50;                   // mm
  constexpr double kExact = 1e-12;               // mm: round-off of sums of ~20 readings
  constexpr double kCurvature = 2.1e-7;          // 1/mm: bound of z'' along any line, for z below
  constexpr double kMiddles = 2;                 // interpolated middles one height depends on
  const auto z = [](const Eigen::Vector2d& p) {  // mm, a few µm of bow and waviness
    return 2e-3 * std::sin(p.x() / 170) * std::cos(p.y() / 230) + 1e-6 * p.x() * p.y() / 100;
  };
  struct Counts {
    long nw, nh, nd;
  };
  for (const Counts c : {Counts{7, 5, 9}, Counts{8, 6, 10}, Counts{9, 6, 11}, Counts{6, 5, 8}}) {
    SCOPED_TRACE(fmt::format("{} x {} readings, diagonals {}", c.nw, c.nh, c.nd));
    const double W = static_cast<double>(c.nw), H = static_cast<double>(c.nh);
    const Eigen::Vector2d NW(0, H), NE(W, H), SE(W, 0), SW(0, 0);
    const std::map<std::string, std::pair<Eigen::Vector2d, Eigen::Vector2d>> ends{
        {"NW_SE", {NW, SE}},
        {"NE_SW", {NE, SW}},
        {"NE_NW", {NE, NW}},
        {"SE_SW", {SE, SW}},
        {"E_W", {(NE + SE) / 2, (NW + SW) / 2}},
        {"NE_SE", {NE, SE}},
        {"NW_SW", {NW, SW}},
        {"N_S", {(NW + NE) / 2, (SW + SE) / 2}}};
    surface::MoodyData d;
    d.foot_spacing = kFoot;
    for (const auto& [name, ab] : ends) {
      const long n = name == "NW_SE" || name == "NE_SW"                    ? c.nd
                     : name == "NE_SE" || name == "NW_SW" || name == "N_S" ? c.nh
                                                                           : c.nw;
      const Eigen::Vector2d a = ab.first * kFoot, b = ab.second * kFoot;
      Eigen::VectorXd r(n);
      for (long j = 0; j < n; ++j) {
        const Eigen::Vector2d p0 = a + (b - a) * static_cast<double>(j) / static_cast<double>(n);
        const Eigen::Vector2d p1 =
            a + (b - a) * static_cast<double>(j + 1) / static_cast<double>(n);
        r[j] = (z(p1) - z(p0)) / (kArcsec * kFoot);  // the reading as the worksheet scales it
      }
      d.readings[name] = r;
    }
    for (const bool lsq : {false, true}) {
      const auto res = surface::moody(d, lsq);
      // Heights minus the truth, less their least-squares plane: zero.
      const auto m = static_cast<Eigen::Index>(res.points.size());
      Eigen::MatrixXd A(m, 3);
      Eigen::VectorXd e(m);
      for (Eigen::Index i = 0; i < m; ++i) {
        const auto& p = res.points[static_cast<std::size_t>(i)];
        A.row(i) << 1, p.xy.x(), p.xy.y();
        e[i] = p.height - z(p.xy);
      }
      const Eigen::VectorXd plane = A.colPivHouseholderQr().solve(e);
      const bool even = c.nw % 2 == 0 && c.nh % 2 == 0 && c.nd % 2 == 0;
      const double h = kFoot * std::max(1.0, std::hypot(W, H) / static_cast<double>(c.nd));
      const double bound = even ? kExact : kMiddles * h * h / 8 * kCurvature;
      EXPECT_LT((e - A * plane).cwiseAbs().maxCoeff(), bound)
          << (lsq ? "least squares" : "worksheet");
    }
  }
}

TEST(Surface, LsqWithADiagonalRecoversTheSurfaceIncludingTwist) {
  for (int seed = 1; seed <= 3; ++seed) {
    std::mt19937 rng(seed);
    const auto r = surface::build(grid_lines(true, rng));
    EXPECT_EQ(r.unobservable, std::vector<std::string>{"plane"});
    EXPECT_LT(error_after(r, false), kRoundOff) << seed;
    EXPECT_LT(r.closure_max, kRoundOff);
  }
}

TEST(Surface, AxisParallelNetworkLeavesTheTwistFreeAndSaysSo) {
  std::mt19937 rng(4);
  const auto r = surface::build(grid_lines(false, rng));
  EXPECT_EQ(r.unobservable, (std::vector<std::string>{"plane", "twist"}));
  EXPECT_NE(r.gauge.find("twist"), std::string::npos);
  EXPECT_LT(error_after(r, true), kRoundOff);
  EXPECT_GT(error_after(r, false), 1e-4);  // the true surface has a twist the network cannot see
  ASSERT_TRUE(r.grid);
  EXPECT_EQ(r.grid->x.size(), 17);
}

TEST(Surface, SeedConstructionMatchesTheTruthUpToPlaneAndTwist) {
  std::mt19937 rng(5);
  auto lines = grid_lines(false, rng);
  lines.erase(lines.begin() +
              8);  // the two-point patent's layout: x family + two boundaries, no inner line
  ASSERT_EQ(lines[7].name, "left");
  ASSERT_EQ(lines[8].name, "right");
  surface::Options o;
  o.method = Method::Seed;
  const auto r = surface::build(lines, o);
  EXPECT_LT(error_after(r, true), kRoundOff);
  EXPECT_LT(r.closure_max, kRoundOff);
  // Same data by least squares: the same surface up to the twist gauge.
  const auto l = surface::build(lines);
  EXPECT_LT(error_after(l, true), kRoundOff);
}

// Lines with noise: the reading noise estimated from the closure agrees with the true one, and
// the flatness's U covers its error (against the true surface's flatness at the same points) in
// about 95 % of networks. Noise-free lines and a network without a redundant crossing state no
// uncertainty, with the reason.
TEST(Surface, FlatnessUncertaintyFromTheClosureCoversItsError) {
  constexpr double kNoise = 0.5e-3;  // mm per height
  constexpr int kNetworks = 60;
  int covered = 0;
  double sigma2 = 0;
  for (int seed = 1; seed <= kNetworks; ++seed) {
    std::mt19937 rng(100 + seed);
    auto lines = grid_lines(true, rng);
    std::normal_distribution<double> noise(0, kNoise);
    for (auto& l : lines)
      for (auto& h : l.heights) h += noise(rng);
    const auto r = surface::build(lines);
    ASSERT_TRUE(r.U) << r.no_uncertainty();
    sigma2 += std::pow(r.sigma * 1e-3 / kNoise, 2);
    // The true flatness at the same points (minimum zone of the true heights).
    auto exact = lines;
    std::mt19937 again(100 + seed);
    exact = grid_lines(true, again);
    const double truth_mz = surface::build(exact).flatness_min_zone;
    if (std::abs(r.flatness_min_zone - truth_mz) <= *r.U) ++covered;
  }
  std::printf("flatness U: covered %d of %d networks; estimated / true noise RMS %.3f\n", covered,
              kNetworks, std::sqrt(sigma2 / kNetworks));
  // The estimated noise: RMS ratio to the true one near 1 (many closure conditions per network).
  EXPECT_NEAR(std::sqrt(sigma2 / kNetworks), 1.0, 0.1);
  // U is conservative for a peak-to-valley figure (Bonferroni over the points): coverage at
  // least 95 %, allowing for the 60 networks' spread.
  EXPECT_GE(covered, 55) << covered << " of " << kNetworks;
  // Noise-free lines agree to round-off at every crossing: no noise to estimate.
  std::mt19937 rng(7);
  const auto exact = surface::build(grid_lines(true, rng));
  EXPECT_FALSE(exact.U);
  EXPECT_FALSE(exact.resolved());
  EXPECT_NE(exact.no_uncertainty().find("agree at every crossing to round-off"), std::string::npos)
      << exact.no_uncertainty();
  // Two crossing lines: their one crossing assembles them, and nothing is left to show the noise.
  auto two = grid_lines(true, rng);
  two = {two[0], two[7]};
  two[0].heights[3] += 1e-3;
  const auto lone = surface::build(two);
  EXPECT_FALSE(lone.U);
  EXPECT_NE(lone.no_uncertainty().find("every one of the 1 crossings is needed"), std::string::npos)
      << lone.no_uncertainty();
  // Heavy noise on a small form: not resolved, said so.
  std::mt19937 rng2(8);
  auto noisy = grid_lines(true, rng2);
  std::normal_distribution<double> big(0, 20e-3);
  for (auto& l : noisy)
    for (auto& h : l.heights) h += big(rng2);
  const auto lost = surface::build(noisy);
  ASSERT_TRUE(lost.U);
  EXPECT_FALSE(*lost.resolved());
  EXPECT_NE(lost.summary().find("flatness: not resolved (U = "), std::string::npos)
      << lost.summary();
}

TEST(Surface, BadNetworksAreRefused) {
  std::mt19937 rng(6);
  auto lines = grid_lines(true, rng);
  auto far = sample("far", {2000, 0}, {2000, 600}, 5, rng);
  lines.push_back(far);
  try {
    surface::build(lines);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'far' do not cross"), std::string::npos) << e.what();
  }
  lines.pop_back();
  lines[0].spacing = 0;
  EXPECT_THROW(surface::build(lines), Error);
  lines = grid_lines(true, rng);
  lines[1].heights[3] = std::nan("");
  EXPECT_THROW(surface::build(lines), Error);
  lines = grid_lines(true, rng);
  lines[2].name = lines[1].name;
  EXPECT_THROW(surface::build(lines), Error);
  surface::Options seed;
  seed.method = Method::Seed;
  try {
    surface::build(grid_lines(true, rng), seed);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("neither along x nor along y"), std::string::npos);
  }
}

TEST(SurfaceIo, MoodyAndLinesReadersNameFileLineColumn) {
  const std::string dir = test::temp_dir() + "/moody";
  std::filesystem::create_directories(dir);
  for (const char* n : surface::kMoodyLines) {
    std::ifstream src(kMoody + "/" + n + ".txt");
    std::ofstream(dir + "/" + n + ".txt") << src.rdbuf();
  }
  std::ofstream(dir + "/Config.txt") << "# spacing\nX 4\n";
  using test::error_of;
  EXPECT_EQ(error_of([&] { io::read_moody(dir); }),
            dir + "/Config.txt:2:1: expected 'I <inches>' or 'M <mm>' (the foot spacing)");
  std::ofstream(dir + "/Config.txt") << "# only comments\n\n";
  EXPECT_NE(error_of([&] { io::read_moody(dir); }).find("Config.txt: no foot spacing found"),
            std::string::npos);
  std::ofstream(dir + "/Config.txt") << "I -4\n";
  EXPECT_EQ(error_of([&] { io::read_moody(dir); }),
            dir + "/Config.txt:1:3: the foot spacing must be positive");
  std::ofstream(dir + "/Config.txt") << "M 66\nI 4\n";  // the first spacing counts
  EXPECT_DOUBLE_EQ(io::read_moody(dir).foot_spacing, 66);
  std::ofstream(dir + "/E_W.txt") << "11.7\n# note\n  nan\n";
  EXPECT_EQ(error_of([&] { io::read_moody(dir); }), dir + "/E_W.txt:3:3: NaN is not allowed");
  std::ofstream(dir + "/E_W.txt") << "11.7\n12.4\n";
  std::filesystem::remove(dir + "/N_S.txt");
  EXPECT_NE(error_of([&] { io::read_moody(dir); }).find("N_S.txt: no such file"),
            std::string::npos);
  EXPECT_NE(error_of([&] { io::read_moody(dir + "/nope"); }).find("not a directory"),
            std::string::npos);

  const std::string lp = test::temp_file(
      "lines.json",
      "{\"lines\": [\n {\"name\": \"a\", \"start\": [0, 0], \"direction\": [1, 0], \"spacing\": "
      "10, "
      "\"heights\": [0, 1, 2]},\n {\"name\": \"b\", \"start\": [0, 0], \"direction\": [0, 1], "
      "\"spacing\": 10, \"slopes\": [1, \"x\"]}\n]}");
  EXPECT_EQ(error_of([&] { io::read_lines(lp); }),
            lp + ":3:83: 'lines[1].slopes[1]' must be a number");
  const std::string lp2 = test::temp_file(
      "lines2.json",
      "{\"lines\": [{\"name\": \"a\", \"start\": [0, 0], \"direction\": [1, 0], \"spacing\": 10, "
      "\"heights\": [0, 1], \"slopes\": [1]}]}");
  EXPECT_NE(error_of([&] { io::read_lines(lp2); }).find("exactly one of"), std::string::npos);
}

// Found by fuzzing: messages about lines.json and Moody's files with no location, or a
// misleading one.
TEST(SurfaceIo, EveryComplaintAboutAFileNamesItsPlace) {
  using test::error_of;
  auto lines = [](const std::string& second) {
    return test::temp_file(
        "l.json",
        "{\"lines\": [\n {\"name\": \"a\", \"start\": [0, 0], \"direction\": [1, 0], "
        "\"spacing\": 10, \"heights\": [0, 1, 2]},\n " +
            second + "\n]}");
  };
  std::string p = lines(
      R"({"name": "a", "start": [0, 0], "direction": [0, 1], "spacing": 10, "heights": [0, 1]})");
  EXPECT_EQ(error_of([&] { io::read_lines(p); }), p + ":3:11: duplicated line name 'a'");
  p = lines(
      R"({"name": "", "start": [0, 0], "direction": [0, 1], "spacing": 10, "heights": [0, 1]})");
  EXPECT_EQ(error_of([&] { io::read_lines(p); }), p + ":3:11: a line's name must not be empty");
  p = lines(
      R"({"name": "b", "start": [0, 0], "direction": [0, 1], "spacing": 1e-300, "heights": [0, 1]})");
  EXPECT_EQ(error_of([&] { io::read_lines(p); }),
            p + ":3:65: spacing 1e-300 mm: must be at least 1e-6 mm (positive)");
  p = lines(
      R"({"name": "b", "start": [0, 0], "direction": [0, 1], "spacing": 10, "slopes": [5e11, 5e11]})");
  EXPECT_NE(error_of([&] { io::read_lines(p); }).find(":3:79: line 'b': the heights run beyond"),
            std::string::npos)
      << error_of([&] { io::read_lines(p); });

  const std::string dir = test::temp_dir() + "/plate";
  std::filesystem::create_directories(dir);
  for (const char* n : surface::kMoodyLines) {
    std::ifstream src(kMoody + "/" + n + ".txt");
    std::ofstream(dir + "/" + n + ".txt") << src.rdbuf();
  }
  std::filesystem::remove_all(dir + "/Config.txt");
  std::filesystem::create_directories(dir + "/Config.txt");  // a directory, not a file
  EXPECT_EQ(error_of([&] { io::read_moody(dir); }),
            dir + "/Config.txt: not a regular file (a directory)");
  std::filesystem::remove(dir + "/Config.txt");
  std::ofstream(dir + "/Config.txt") << "I 4\n";
  {
    std::ofstream more(dir + "/E_W.txt", std::ios::app);
    more << "1.5\n";  // one reading more than NE_NW
  }
  const std::string m = error_of([&] { io::read_moody(dir); });
  EXPECT_NE(m.find(dir + "/E_W.txt:"), std::string::npos) << m;
  EXPECT_NE(m.find("readings, but NE_NW.txt (the parallel centre line) has"), std::string::npos)
      << m;
}

TEST(SurfaceIo, LinesFromSlopesAndSeparationResults) {
  const std::string lp = test::temp_file(
      "ok.json",
      "{\"lines\": [{\"name\": \"a\", \"start\": [0, 0], \"direction\": [2, 0], \"spacing\": 10, "
      "\"slopes\": [100, -50]}]}");
  const auto lines = io::read_lines(lp);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_DOUBLE_EQ(lines[0].direction.x(), 2);  // normalised by build()
  ASSERT_EQ(lines[0].heights.size(), 3);
  EXPECT_NEAR(lines[0].heights[1], 100e-6 * 10, 1e-18);  // 100 urad over 10 mm = 1 um
  EXPECT_NEAR(lines[0].heights[2], 50e-6 * 10, 1e-18);
}
