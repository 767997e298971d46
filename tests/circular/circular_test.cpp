// The circular test (ISO 230-4) on the virtual machine: its figures against an independent
// computation, and every cause of the diagnosis against the machine's truth, alone and together,
// noise-free and with noise, with its sign convention.
#include "trueaxis/circular/circular.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/circular/circular.hpp"
#include "trueaxis/report/files.hpp"
#include "trueaxis/sim/circular.hpp"

using namespace trueaxis;

namespace {

constexpr double kPi = 3.14159265358979323846;

circular::Options options(const sim::CircularOptions& s) {
  circular::Options o;
  o.radius = s.radius;
  o.feed = s.feed;
  o.plane = s.plane;
  return o;
}

const circular::Cause& cause(const circular::Result& r, const std::string& key) {
  for (const auto& c : r.causes)
    if (c.key == key) return c;
  throw Error("no cause " + key);
}

// The tool's actual position at command c of machine m (mm).
Eigen::Vector3d tool(const sim::Machine& m, const Eigen::Vector3d& c) {
  return c + m.offset + m.error(c);
}

// The machine's squareness of X and Y at c, as the angle between the actual +X and +Y directions
// less 90° (rad), and its scale mismatch, from the tool's actual positions: independent of the
// circular test's model.
double squareness_xy(const sim::Machine& m, const Eigen::Vector3d& c) {
  const double h = 50;
  const Eigen::Vector3d dx =
      tool(m, c + Eigen::Vector3d(h, 0, 0)) - tool(m, c - Eigen::Vector3d(h, 0, 0));
  const Eigen::Vector3d dy =
      tool(m, c + Eigen::Vector3d(0, h, 0)) - tool(m, c - Eigen::Vector3d(0, h, 0));
  const Eigen::Vector2d a = dx.head<2>(), b = dy.head<2>();
  return std::acos(a.dot(b) / (a.norm() * b.norm())) - kPi / 2;
}
double scale_mismatch_xy(const sim::Machine& m, const Eigen::Vector3d& c) {
  const double h = 50;
  const double sx =
      (tool(m, c + Eigen::Vector3d(h, 0, 0)) - tool(m, c - Eigen::Vector3d(h, 0, 0))).x() /
          (2 * h) -
      1;
  const double sy =
      (tool(m, c + Eigen::Vector3d(0, h, 0)) - tool(m, c - Eigen::Vector3d(0, h, 0))).y() /
          (2 * h) -
      1;
  return sx - sy;
}

const Eigen::Vector3d kCentre(400, 300, 250);

sim::CircularOptions test_run() {
  sim::CircularOptions s;
  s.centre = kCentre;
  return s;
}

}  // namespace

// Each cause alone, noise-free: its diagnosed size is the truth to what the first-order model
// leaves (stated per case), and every other cause reads near zero.
TEST(Circular, EachCauseAloneIsDiagnosedAsTheMachineHasIt) {
  // The first-order model δr = e·u leaves |e|²/(2R): below 1e-4 µm here, 0.002 µm/m in a
  // squareness or scale (over R/2).
  constexpr double kExact = 2e-4, kExactPerM = 0.01;
  const sim::Machine perfect;
  {  // squareness: the actual +X and +Y make more than 90° when S > 0
    sim::Machine m;
    m.squareness_c0y = 25e-6;
    const auto s = test_run();
    const auto r = circular::evaluate(sim::simulate_circular(m, s).trace, options(s));
    const double truth = squareness_xy(m, kCentre) * 1e6;
    EXPECT_NEAR(std::abs(truth), 25, 1e-3);
    EXPECT_NEAR(cause(r, "squareness").value, truth, kExactPerM);
    EXPECT_NEAR(cause(r, "scale_mismatch").value, 0, kExactPerM);
    EXPECT_NEAR(cause(r, "backlash.X").value, 0, kExact);
  }
  {  // scale mismatch: X long by 12 µm/m, Y short by 5 µm/m
    sim::Machine m;
    m.errors[0][0].polynomial = {0, 12e-3};  // EXX, mm per (u / 1 m)
    m.errors[1][1].polynomial = {0, -5e-3};  // EYY
    const auto s = test_run();
    const auto r = circular::evaluate(sim::simulate_circular(m, s).trace, options(s));
    EXPECT_NEAR(scale_mismatch_xy(m, kCentre) * 1e6, 17, 1e-6);
    EXPECT_NEAR(cause(r, "scale_mismatch").value, 17, kExactPerM);
    EXPECT_NEAR(cause(r, "squareness").value, 0, kExactPerM);
  }
  {  // backlash: each axis stops short by half of it each way
    auto s = test_run();
    s.servo[0].backlash = 4e-3;
    s.servo[1].backlash = 6e-3;
    const auto r = circular::evaluate(sim::simulate_circular(perfect, s).trace, options(s));
    EXPECT_NEAR(cause(r, "backlash.X").value, 4, kExact);
    EXPECT_NEAR(cause(r, "backlash.Y").value, 6, kExact);
    EXPECT_NEAR(cause(r, "centre_offset.X").value, 0, kExact);
    EXPECT_LT(r.unexplained_rms, 1e-7);
  }
  {  // reversal spikes: outward, decaying over 4° after each reversal; the decay is found
    auto s = test_run();
    s.servo[0].spike = 5e-3;
    s.servo[0].spike_decay = 4 * kPi / 180;
    s.servo[1].spike = 3e-3;
    s.servo[1].spike_decay = 4 * kPi / 180;
    const auto r = circular::evaluate(sim::simulate_circular(perfect, s).trace, options(s));
    EXPECT_NEAR(r.spike_decay * 180 / kPi, 4, 1e-3);
    for (const char* d : {"ccw", "cw"}) {
      EXPECT_NEAR(cause(r, std::string("reversal_spike.X.") + d).value, 5, 1e-3) << d;
      EXPECT_NEAR(cause(r, std::string("reversal_spike.Y.") + d).value, 3, 1e-3) << d;
    }
  }
  {  // servo lag mismatch: τ = 1/K per axis; the fit's sin 2θ term is first order in ωτ, and the
     // axes' different amplitude loss and phase, second order, read as a scale mismatch of
     // −(3/2)·ω²·(τX² − τY²)
    auto s = test_run();
    s.servo[0].gain = 40;
    s.servo[1].gain = 30;
    const auto r = circular::evaluate(sim::simulate_circular(perfect, s).trace, options(s));
    const double tx = 1.0 / 40, ty = 1.0 / 30, w = s.feed / 60 / s.radius;
    EXPECT_NEAR(cause(r, "lag_mismatch").value, (tx - ty) * 1e3, 1e-3 * std::abs(tx - ty) * 1e3);
    EXPECT_NEAR(cause(r, "scale_mismatch").value, -1.5 * w * w * (tx * tx - ty * ty) * 1e6, 0.05);
    EXPECT_NEAR(cause(r, "squareness").value, 0, 0.05);
  }
  {  // the pivot set 10 µm off in +X and 20 µm in −Y: the path's centre is the opposite way
    auto s = test_run();
    s.pivot_offset = Eigen::Vector3d(0.010, -0.020, 0);
    const auto r = circular::evaluate(sim::simulate_circular(perfect, s).trace, options(s));
    EXPECT_NEAR(cause(r, "centre_offset.X").value, -10, kExact);
    EXPECT_NEAR(cause(r, "centre_offset.Y").value, 20, kExact);
    EXPECT_NEAR(r.ccw.centre.x() * 1e3, -10, kExact);
  }
}

// All together, noise-free: squareness, scale, straightness, backlash, spikes, the pivot's
// offset and the ballbar's length error are each given back.
TEST(Circular, AllCausesTogetherAreSeparated) {
  sim::Machine m;
  m.squareness_c0y = -18e-6;
  m.errors[0][0].polynomial = {0, 9e-3};
  m.errors[0][1].polynomial = {0, 0, 40e-3};  // EYX: a bow of Y along X
  auto s = test_run();
  s.servo[0].backlash = 3e-3;
  s.servo[1].backlash = 5e-3;
  s.servo[0].spike = 4e-3;
  s.servo[1].spike = 2e-3;
  s.servo[0].spike_decay = s.servo[1].spike_decay = 5 * kPi / 180;
  s.pivot_offset = Eigen::Vector3d(0.004, 0.007, 0);
  s.length_error = 0.002;
  const auto r = circular::evaluate(sim::simulate_circular(m, s).trace, options(s));
  // The bow's slope at the centre is part of the squareness the test sees; its curvature over
  // ±R is the straightness term: 40 µm·(R / 1 m)² = 0.4 µm.
  // First order in e/R: 0.02 µm/m, 0.001 µm.
  EXPECT_NEAR(cause(r, "squareness").value, squareness_xy(m, kCentre) * 1e6, 0.02);
  EXPECT_NEAR(cause(r, "scale_mismatch").value, scale_mismatch_xy(m, kCentre) * 1e6, 0.02);
  EXPECT_NEAR(cause(r, "straightness.X").value, 40e-3 * 0.01 * 1e3, 1e-3);
  EXPECT_NEAR(cause(r, "backlash.X").value, 3, 1e-3);
  EXPECT_NEAR(cause(r, "backlash.Y").value, 5, 1e-3);
  EXPECT_NEAR(cause(r, "reversal_spike.X.ccw").value, 4, 1e-3);
  EXPECT_NEAR(cause(r, "reversal_spike.Y.cw").value, 2, 1e-3);
  EXPECT_LT(r.unexplained_rms, 1e-6);
  for (const auto& c : r.causes) EXPECT_TRUE(c.separated) << c.name << ": " << c.confused_with;
}

// G, F and H as ISO 230-4 defines them, computed here independently: the least-squares circle by
// Gauss–Newton on the points themselves, the band about it; H from the two paths interpolated
// on a common grid of angles.
TEST(Circular, FiguresAgreeWithAnIndependentComputation) {
  constexpr double kFigure = 1e-7;  // mm
  sim::Machine m;
  m.squareness_c0y = 30e-6;
  auto s = test_run();
  s.servo[0].backlash = 5e-3;
  s.servo[1].gain = 35;
  s.servo[0].gain = 40;
  s.noise = 0.3e-3;
  s.pivot_offset = Eigen::Vector3d(0.01, 0, 0);
  const auto run = sim::simulate_circular(m, s);
  const auto r = circular::evaluate(run.trace, options(s));
  const auto& t = run.trace;
  for (const auto d : {circular::Direction::Ccw, circular::Direction::Cw}) {
    std::vector<Eigen::Vector2d> p;
    std::vector<double> dev;
    for (Eigen::Index k = 0; k < t.angle.size(); ++k)
      if (t.direction[static_cast<std::size_t>(k)] == d) {
        const double rr = s.radius + t.deviation[k];
        p.emplace_back(rr * std::cos(t.angle[k]), rr * std::sin(t.angle[k]));
        dev.push_back(t.deviation[k]);
      }
    Eigen::Vector3d c(0, 0, s.radius);  // centre, radius
    for (int it = 0; it < 20; ++it) {
      Eigen::MatrixXd J(static_cast<Eigen::Index>(p.size()), 3);
      Eigen::VectorXd f(J.rows());
      for (std::size_t i = 0; i < p.size(); ++i) {
        const Eigen::Vector2d q = p[i] - c.head<2>();
        const auto I = static_cast<Eigen::Index>(i);
        f[I] = q.norm() - c[2];
        J.row(I) << -q.x() / q.norm(), -q.y() / q.norm(), -1;
      }
      c -= J.colPivHouseholderQr().solve(f);
    }
    double lo = INFINITY, hi = -INFINITY;
    for (const auto& q : p) {
      lo = std::min(lo, (q - c.head<2>()).norm());
      hi = std::max(hi, (q - c.head<2>()).norm());
    }
    const auto& fig = d == circular::Direction::Ccw ? r.ccw : r.cw;
    EXPECT_NEAR(fig.G, hi - lo, kFigure);
    EXPECT_NEAR(fig.F_min, *std::min_element(dev.begin(), dev.end()), 1e-15);
    EXPECT_NEAR(fig.F_max, *std::max_element(dev.begin(), dev.end()), 1e-15);
  }
  // H: both paths on a fine grid of angles, the largest difference.
  auto path = [&](circular::Direction d) {
    std::vector<std::pair<double, double>> v;
    for (Eigen::Index k = 0; k < t.angle.size(); ++k)
      if (t.direction[static_cast<std::size_t>(k)] == d)
        v.emplace_back(std::fmod(std::fmod(t.angle[k], 2 * kPi) + 2 * kPi, 2 * kPi),
                       t.deviation[k]);
    std::sort(v.begin(), v.end());
    return v;
  };
  const auto ccw = path(circular::Direction::Ccw), cw = path(circular::Direction::Cw);
  double h = 0;
  for (const auto& [th, dv] : ccw) {
    auto it = std::lower_bound(cw.begin(), cw.end(), std::make_pair(th, -HUGE_VAL));
    const auto& hi_pt = it == cw.end() ? cw.front() : *it;
    const auto& lo_pt = it == cw.begin() ? cw.back() : *(it - 1);
    double a0 = lo_pt.first, a1 = hi_pt.first, x = th;
    if (a1 <= a0) a1 += 2 * kPi;
    if (x < a0) x += 2 * kPi;
    const double other = lo_pt.second + (hi_pt.second - lo_pt.second) * (x - a0) / (a1 - a0);
    h = std::max(h, std::abs(dv - other));
  }
  ASSERT_TRUE(r.H);
  EXPECT_NEAR(*r.H, h, 1e-12);
}

// Noisy traces: each estimate within 2u of the truth in about 95 % of the runs.
TEST(Circular, NoisyEstimatesAgreeWithTheirStatedUncertainty) {
  sim::Machine m;
  m.squareness_c0y = 20e-6;
  int inside = 0, total = 0;
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    auto s = test_run();
    s.servo[0].backlash = 3e-3;
    s.servo[1].backlash = 2e-3;
    s.noise = 0.5e-3;
    s.sample_rate = 25;  // fewer samples: a u large enough to test against
    s.seed = seed;
    auto o = options(s);
    o.spike_decay = 5 * kPi / 180;
    const auto r = circular::evaluate(sim::simulate_circular(m, s).trace, o);
    const std::map<std::string, double> truth{{"squareness", squareness_xy(m, kCentre) * 1e6},
                                              {"backlash.X", 3},
                                              {"backlash.Y", 2},
                                              {"scale_mismatch", 0},
                                              {"lag_mismatch", 0}};
    for (const auto& [key, value] : truth) {
      const auto& c = cause(r, key);
      ASSERT_TRUE(c.u) << key;
      inside += std::abs(c.value - value) <= 2 * *c.u;
      ++total;
    }
    EXPECT_NEAR(r.sigma, 0.5e-3, 0.1e-3);
  }
  EXPECT_GE(inside, static_cast<int>(0.88 * total)) << inside << " of " << total;
  EXPECT_LE(inside, total);
}

// One direction only: the lag mismatch and the squareness have one signature, and are named as
// not separated instead of being given numbers.
TEST(Circular, WhatOneDirectionCannotSeparateIsNamed) {
  auto s = test_run();
  s.cw = false;
  s.servo[0].gain = 40;
  s.servo[1].gain = 30;
  const auto r = circular::evaluate(sim::simulate_circular(sim::Machine{}, s).trace, options(s));
  const auto& lag = cause(r, "lag_mismatch");
  const auto& sq = cause(r, "squareness");
  EXPECT_FALSE(lag.separated && sq.separated);
  EXPECT_NE(r.summary().find("not separated from"), std::string::npos) << r.summary();
  EXPECT_FALSE(r.H);
  EXPECT_FALSE(r.warnings.empty());
}

TEST(Circular, WhatCannotBeATestIsRefused) {
  auto s = test_run();
  s.arc = 300 * kPi / 180;  // 60° missing
  const auto run = sim::simulate_circular(sim::Machine{}, s);
  EXPECT_NE(test::error_of([&] { circular::evaluate(run.trace, options(s)); }).find("without data"),
            std::string::npos);
  circular::Trace few;
  few.direction.assign(5, circular::Direction::Ccw);
  few.angle = Eigen::VectorXd::LinSpaced(5, 0, 6);
  few.deviation = Eigen::VectorXd::Zero(5);
  EXPECT_NE(test::error_of([&] { circular::evaluate(few, {}); }).find("at least 36"),
            std::string::npos);
  auto bad = sim::simulate_circular(sim::Machine{}, test_run()).trace;
  bad.deviation[7] = NAN;
  bad.where.assign(static_cast<std::size_t>(bad.angle.size()), "");
  bad.where[7] = "trace.csv:9:3: ";
  EXPECT_EQ(test::error_of([&] {
              circular::evaluate(bad, options(test_run()));
            }).rfind("trace.csv:9:3: ", 0),
            0u);
  EXPECT_NE(test::error_of([] { circular::Plane::parse("XZ"); }).find("XY, YZ or ZX"),
            std::string::npos);
  EXPECT_EQ(circular::Plane::parse("zx").name(), "ZX");
  auto far = test_run();
  far.radius = 450;
  EXPECT_NE(test::error_of([&] { sim::simulate_circular(sim::Machine{}, far); }).find("range"),
            std::string::npos);
}

// The trace and the result as files: the trace reads back to its samples, the result to its
// figures, causes and trace (what `trueaxis report` draws); bad files are refused where they
// are wrong.
TEST(Circular, FilesRoundTripAndBadOnesAreRefused) {
  constexpr double kRound = 1e-12;  // mm: numbers written in the shortest exact form, µm ↔ mm
  sim::Machine m;
  m.squareness_c0y = 12e-6;
  auto s = test_run();
  s.servo[0].backlash = 2e-3;
  s.noise = 0.2e-3;
  const auto run = sim::simulate_circular(m, s);
  const std::string trace_path = test::temp_dir() + "/trace.csv";
  io::write_trace(trace_path, run.trace);
  const auto back = io::read_trace(trace_path);
  ASSERT_EQ(back.angle.size(), run.trace.angle.size());
  EXPECT_LT((back.angle - run.trace.angle).cwiseAbs().maxCoeff(), kRound);
  EXPECT_LT((back.deviation - run.trace.deviation).cwiseAbs().maxCoeff(), kRound);
  EXPECT_EQ(back.direction, run.trace.direction);
  EXPECT_EQ(back.where[3].rfind(trace_path + ":5:", 0), 0u);  // line 5, the deviation's column
  const auto r = circular::evaluate(back, options(s));
  const std::string result_path = test::temp_dir() + "/circular.json";
  io::write_circular_result(result_path, r, &back);
  const auto f = io::read_circular_result(result_path);
  EXPECT_NEAR(f.result.ccw.G, r.ccw.G, kRound);
  EXPECT_NEAR(f.result.cw.F_max, r.cw.F_max, kRound);
  ASSERT_TRUE(f.result.H);
  EXPECT_NEAR(*f.result.H, *r.H, kRound);
  ASSERT_EQ(f.result.causes.size(), r.causes.size());
  for (const auto& c : r.causes) {
    const auto& d = cause(f.result, c.key);
    EXPECT_EQ(d.name, c.name);
    EXPECT_EQ(d.unit, c.unit) << c.key;
    EXPECT_NEAR(d.value, c.value, 1e-9) << c.key;
  }
  EXPECT_EQ(f.trace.angle.size(), back.angle.size());
  EXPECT_LT((f.result.model - r.model).cwiseAbs().maxCoeff(), kRound);
  const auto fr = report::file_report(result_path);
  EXPECT_EQ(fr.kind, "circular");
  EXPECT_EQ(fr.section.planes.size(), 1u);  // the polar plot
  // Bad traces: each refused at its line and column.
  auto refused = [](const std::string& text) {
    return test::error_of([&] { io::parse_trace(text, "t.csv"); });
  };
  EXPECT_EQ(refused("direction,angle_deg,deviation_um\nccw,0,1\nleft,1,2\n")
                .rfind("t.csv:3:1: direction 'left'", 0),
            0u);
  EXPECT_EQ(refused("direction,angle_deg,deviation_um\nccw,x,1\n")
                .rfind("t.csv:2:5: 'x' is not a number", 0),
            0u);
  EXPECT_EQ(refused("direction,angle_deg,deviation_um\nccw,0\n").rfind("t.csv:2:", 0), 0u);
  EXPECT_EQ(refused("direction,angle_deg,speed\n").rfind("t.csv:1:21: unknown column 'speed'", 0),
            0u)
      << refused("direction,angle_deg,speed\n");
  EXPECT_EQ(refused("direction,angle [s],deviation_um\n").rfind("t.csv:1:11:", 0), 0u);
  EXPECT_NE(refused("").find("empty"), std::string::npos);
  // A trace in nm and a spreadsheet's dialect read to the same numbers.
  const auto nm =
      io::parse_trace("sep=;\ndirection;angle_deg;deviation (nm)\ncw;1,5;-250\n", "x.csv");
  EXPECT_NEAR(nm.angle[0], 1.5 * kPi / 180, 1e-15);
  EXPECT_NEAR(nm.deviation[0], -250e-6, 1e-15);
}

// servo.json and a saved result that are not what they claim are refused where they are wrong.
TEST(Circular, BadServoAndResultFilesAreRefusedWhereTheyAreWrong) {
  const auto servo = io::read_servo(test::temp_file(
      "servo.json", "{\"X\": {\"gain_per_s\": 30, \"backlash_um\": 3}, \"Y\": {\"spike_um\": 2}}"));
  EXPECT_EQ(servo[0].gain, 30);
  EXPECT_NEAR(servo[0].backlash, 3e-3, 1e-18);
  EXPECT_NEAR(servo[1].spike, 2e-3, 1e-18);
  auto refused = [](const std::string& name, const std::string& text, auto reader) -> std::string {
    const std::string path = test::temp_file(name, text);
    return test::error_of([&] { reader(path); });
  };
  const auto servo_reader = [](const std::string& p) { io::read_servo(p); };
  EXPECT_NE(
      refused("s1.json", "{\"W\": {}}", servo_reader).find("s1.json:1:7: an axis is X, Y or Z"),
      std::string::npos);
  EXPECT_NE(refused("s2.json", "{\"X\":\n {\"backlash_um\": -1}}", servo_reader)
                .find("s2.json:2:18: must be >= 0"),
            std::string::npos)
      << refused("s2.json", "{\"X\":\n {\"backlash_um\": -1}}", servo_reader);
  EXPECT_NE(refused("s3.json", "{\"X\": {\"pitch_mm\": 0}}", servo_reader).find("s3.json:1:"),
            std::string::npos);
  const auto result_reader = [](const std::string& p) { io::read_circular_result(p); };
  const std::string head =
      "{\"kind\": \"circular\", \"radius_mm\": 100, \"feed_mm_per_min\": 1000,\n";
  EXPECT_NE(refused("r1.json", head + "\"plane\": \"XZ\"}", result_reader)
                .find("r1.json:2:10: plane 'XZ'"),
            std::string::npos)
      << refused("r1.json", head + "\"plane\": \"XZ\"}", result_reader);
  const std::string trace =
      head +
      "\"plane\": \"XY\", \"diagnosis\": {\"unexplained_rms_um\": 0.1},\n\"trace\": "
      "{\"direction\": \"+-\", \"angle_deg\": [0, 1], \"deviation_um\": [0, 1], "
      "\"model_um\": [0]}}";
  EXPECT_NE(refused("r2.json", trace, result_reader).find("r2.json:3:10: direction, angle_deg"),
            std::string::npos)
      << refused("r2.json", trace, result_reader);
}

// A raw time series (t_s, deviation_um) becomes the trace: runs told apart where the time goes
// back, angles from the feed and radius; what cannot be this test's is refused where it is.
TEST(Circular, TimeSeriesBecomesTheTraceAndBadOnesAreRefused) {
  sim::Machine m;
  m.squareness_c0y = 15e-6;
  auto s = test_run();
  s.servo[0].backlash = 3e-3;
  s.sample_rate = 50;
  const auto run = sim::simulate_circular(m, s);
  std::string text = "t_s,deviation_um\n";
  for (Eigen::Index k = 0; k < run.time.size(); ++k)
    text += fmt::format("{:.17g},{:.17g}\n", run.time[k], run.trace.deviation[k] * 1e3);
  io::TimeSeriesOptions ts;
  ts.feed = s.feed;
  ts.radius = s.radius;
  // Each run's first sample is at its first data angle: 0° ccw, 360° cw, within a sample's step.
  const double step = s.feed / 60 / s.radius / s.sample_rate;  // rad per sample
  const circular::Trace t = io::parse_trace(text, "ts.csv", &ts);
  ASSERT_EQ(t.angle.size(), run.trace.angle.size());
  EXPECT_EQ(t.direction, run.trace.direction);
  const auto n_ccw = std::count(t.direction.begin(), t.direction.end(), circular::Direction::Ccw);
  double worst = 0;
  for (Eigen::Index k = 0; k < t.angle.size(); ++k)
    worst = std::max(worst, std::abs(std::remainder(t.angle[k] - run.trace.angle[k], 2 * kPi)));
  EXPECT_LT(worst, step);
  EXPECT_GT(n_ccw, 0);
  const auto a = circular::evaluate(t, options(s)), b = circular::evaluate(run.trace, options(s));
  EXPECT_NEAR(cause(a, "backlash.X").value, cause(b, "backlash.X").value, 0.05);
  EXPECT_NEAR(cause(a, "squareness").value, cause(b, "squareness").value, 0.2);
  // Refusals, each at the line and the time column.
  EXPECT_EQ(test::error_of([&] {
              io::parse_trace(text, "ts.csv");
            }).rfind("ts.csv:1:1: a time series", 0),
            0u);
  io::TimeSeriesOptions one = ts;
  one.order = io::TimeSeriesOptions::order_of("ccw");
  const std::string e1 = test::error_of([&] { io::parse_trace(text, "ts.csv", &one); });
  EXPECT_EQ(e1.rfind(fmt::format("ts.csv:{}:1: run 2 starts here", n_ccw + 2), 0), 0u) << e1;
  io::TimeSeriesOptions slow = ts;
  slow.radius = 10;  // ten times the angle: more than two turns
  EXPECT_NE(
      test::error_of([&] { io::parse_trace(text, "ts.csv", &slow); }).find("more than two turns"),
      std::string::npos);
  io::TimeSeriesOptions three = ts;
  three.order = io::TimeSeriesOptions::order_of("cw,ccw");
  EXPECT_EQ(io::parse_trace(text, "ts.csv", &three).direction.front(), circular::Direction::Cw);
  EXPECT_THROW(io::TimeSeriesOptions::order_of("up,down"), Error);
  EXPECT_EQ(test::error_of([&] { io::parse_trace("t_s,deviation_um\n0,1\n0,2\n", "f", &ts); }),
            "f: a time series needs times that increase");
}

// Each axis reverses its own following lag's phase after the commanded reversal: with lags of 25
// and 33 ms at ω = 0.5 rad/s the delays are 0.72° and 0.95°, found per axis, and the backlash of
// each read at its own reversal.
TEST(Circular, EachAxisReversesAfterItsOwnDelay) {
  const sim::Machine perfect;
  auto s = test_run();
  s.feed = 3000;  // ω = 0.5 rad/s on R 100 mm
  s.sample_rate = 500;
  s.servo_rate = 5000;
  s.servo[0].gain = 40;
  s.servo[1].gain = 30;
  s.servo[0].backlash = 4e-3;
  s.servo[1].backlash = 6e-3;
  const auto run = sim::simulate_circular(perfect, s);
  const auto r = circular::evaluate(run.trace, options(s));
  const double w = s.feed / 60 / s.radius;
  const double spacing = w / s.sample_rate;  // rad between samples
  EXPECT_NEAR(r.reversal_delay[0], std::atan(w / 40), 2 * spacing);
  EXPECT_NEAR(r.reversal_delay[1], std::atan(w / 30), 2 * spacing);
  // One delay for both (their mean) reads the backlash steps at the wrong places.
  auto shared = options(s);
  shared.reversal_delay = (r.reversal_delay[0] + r.reversal_delay[1]) / 2;
  const auto one = circular::evaluate(run.trace, shared);
  EXPECT_GT(one.unexplained_rms, 2 * r.unexplained_rms);
  // Written per axis and read back.
  const std::string path = test::temp_dir() + "/delays.json";
  io::write_circular_result(path, r, &run.trace);
  const auto back = io::read_circular_result(path).result;
  EXPECT_NEAR(back.reversal_delay[0], r.reversal_delay[0], 1e-12);
  EXPECT_NEAR(back.reversal_delay[1], r.reversal_delay[1], 1e-12);
  // A delay that is not a number is refused where it stands; one number (older files) is both.
  std::string text = test::read_file(path);
  const std::string key = "\"reversal_delay_deg\": {";
  const auto at = text.find(key);
  ASSERT_NE(at, std::string::npos);
  const auto close = text.find('}', at);
  const std::string bad =
      text.substr(0, at) + key + "\"X\": \"fast\", \"Y\": 0.1" + text.substr(close);
  EXPECT_NE(test::error_of([&] {
              io::read_circular_result(test::temp_file("bad.json", bad));
            }).find("bad.json:"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] {
              io::read_circular_result(test::temp_file("bad.json", bad));
            }).find("reversal_delay_deg.X"),
            std::string::npos);
  const std::string old_form =
      text.substr(0, at) + "\"reversal_delay_deg\": 0.5" + text.substr(close + 1);
  const auto older = io::read_circular_result(test::temp_file("old.json", old_form)).result;
  EXPECT_NEAR(older.reversal_delay[0], 0.5 * kPi / 180, 1e-15);
  EXPECT_NEAR(older.reversal_delay[1], 0.5 * kPi / 180, 1e-15);
  // At this speed the first-order lag model leaves ~0.06 µm, and a slowly decaying "spike" can
  // take part of a backlash step: the two together are the step.
  for (const char* axis : {"X", "Y"}) {
    const double b = cause(r, std::string("backlash.") + axis).value;
    const double spike = cause(r, std::string("reversal_spike.") + axis + ".ccw").value;
    EXPECT_NEAR(b + spike, axis[0] == 'X' ? 4 : 6, 0.15) << axis;
  }
}

// The decay and each axis' delay searched on noisy traces as users record them, from 25 samples
// a second (a backlash step's place between samples is then a question of 0.4°) to 1000: a spike
// must not be read as a fast-decaying one that hides a misplaced backlash step (the searched
// decay once fell to the grid's 0.7° on such traces and halved the spikes), and the causes come
// back within their stated uncertainty.
TEST(Circular, DecayAndDelaysAreFoundOnSparseNoisyTraces) {
  sim::Machine m;
  m.squareness_c0y = -18e-6;
  m.errors[0][0].polynomial = {0, 9e-3};
  int inside = 0, total = 0;
  for (const double rate : {25.0, 100.0, 1000.0})
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      auto s = test_run();
      s.servo[0].gain = 40;
      s.servo[1].gain = 36;
      s.servo[0].backlash = 3e-3;
      s.servo[1].backlash = 5e-3;
      s.servo[1].spike = 3e-3;
      s.servo[1].spike_decay = 5 * kPi / 180;
      s.pivot_offset = Eigen::Vector3d(0.006, -0.004, 0);
      s.noise = 0.1e-3;
      s.sample_rate = rate;
      s.seed = seed;
      const auto r = circular::evaluate(sim::simulate_circular(m, s).trace, options(s));
      const std::string at = fmt::format("{:g} Hz, seed {}", rate, seed);
      // What the model cannot explain is the noise: a wrong decay or delay leaves 2–3× more.
      EXPECT_LT(r.unexplained_rms, 1.25 * s.noise) << at;
      EXPECT_TRUE(r.warnings.empty()) << at << ": " << r.warnings.front();
      // The virtual machine's spike passes through its position loop, so the exponential that
      // fits it decays up to ~5 % slower than the spike set: 0.3° allowed beside 3u.
      constexpr double kLoopShapeDeg = 0.3;
      ASSERT_TRUE(r.spike_decay_u) << at << ": " << r.spike_decay_note;
      EXPECT_NEAR(r.spike_decay * 180 / kPi, 5, 3 * *r.spike_decay_u * 180 / kPi + kLoopShapeDeg)
          << at;
      const double w = s.feed / 60 / s.radius;
      EXPECT_NEAR(r.reversal_delay_resolution, w / rate, 1e-3 * w / rate) << at;
      for (std::size_t axis = 0; axis < 2; ++axis)
        EXPECT_NEAR(r.reversal_delay[axis], std::atan(w / s.servo[axis].gain),
                    std::max(r.reversal_delay_resolution, 0.1 * kPi / 180))
            << at << ", axis " << axis;
      const std::map<std::string, double> truth{
          {"backlash.X", 3},           {"backlash.Y", 5},
          {"reversal_spike.Y.ccw", 3}, {"reversal_spike.Y.cw", 3},
          {"reversal_spike.X.ccw", 0}, {"squareness", squareness_xy(m, kCentre) * 1e6}};
      for (const auto& [key, value] : truth) {
        const auto& c = cause(r, key);
        ASSERT_TRUE(c.u) << key << ", " << at;
        EXPECT_NEAR(c.value, value, 0.4) << key << ", " << at;  // µm, µm/m
        inside += std::abs(c.value - value) <= 3 * *c.u;
        ++total;
      }
    }
  // The u are those of the sizes at the decay and delays found, which are themselves estimates:
  // most, not all, within 3u.
  EXPECT_GE(inside, static_cast<int>(0.8 * total)) << inside << " of " << total;

  // Without spikes the decay is not resolved, and said so; given, it is said to be given; both
  // written and read back.
  auto s = test_run();
  s.servo[0].backlash = 3e-3;
  s.noise = 0.1e-3;
  const auto run = sim::simulate_circular(m, s);
  const auto none = circular::evaluate(run.trace, options(s));
  EXPECT_FALSE(none.spike_decay_u);
  EXPECT_NE(none.spike_decay_note.find("not resolved"), std::string::npos) << none.spike_decay_note;
  // An error none of the causes models (a waviness of Y along X, 0.5 µm over 40 mm) leaves a
  // correlated residual: the u then understate, and the result says so.
  sim::Machine bowed = m;
  bowed.errors[0][1].sines = {{0.5e-3, 40, 0}};
  const auto warned = circular::evaluate(sim::simulate_circular(bowed, s).trace, options(s));
  ASSERT_FALSE(warned.warnings.empty()) << warned.unexplained_rms * 1e3 << " µm";
  EXPECT_NE(warned.warnings.front().find("understate"), std::string::npos);
  auto o = options(s);
  o.spike_decay = 4 * kPi / 180;
  const auto given = circular::evaluate(run.trace, o);
  EXPECT_FALSE(given.spike_decay_u);
  EXPECT_NE(given.spike_decay_note.find("given"), std::string::npos);
  const std::string path = test::temp_dir() + "/decay.json";
  io::write_circular_result(path, none, &run.trace);
  const auto back = io::read_circular_result(path).result;
  EXPECT_FALSE(back.spike_decay_u);
  EXPECT_EQ(back.spike_decay_note, none.spike_decay_note);
  EXPECT_NEAR(back.reversal_delay_resolution, none.reversal_delay_resolution, 1e-15);
  s.servo[1].spike = 3e-3;
  const auto spiked = sim::simulate_circular(m, s);
  const auto found = circular::evaluate(spiked.trace, options(s));
  ASSERT_TRUE(found.spike_decay_u) << found.spike_decay_note;
  io::write_circular_result(path, found, &spiked.trace);
  const auto again = io::read_circular_result(path).result;
  ASSERT_TRUE(again.spike_decay_u);
  EXPECT_NEAR(*again.spike_decay_u, *found.spike_decay_u, 1e-12);
  // The decay's u and the delays' resolution must be numbers where they stand.
  std::string text = test::read_file(path);
  const auto at = text.find("\"spike_decay_u_deg\": ");
  ASSERT_NE(at, std::string::npos);
  text.insert(at + 21, "\"wide\", \"was\": ");
  const std::string e =
      test::error_of([&] { io::read_circular_result(test::temp_file("bad-decay.json", text)); });
  EXPECT_NE(e.find("bad-decay.json:"), std::string::npos) << e;
  EXPECT_NE(e.find("spike_decay_u_deg"), std::string::npos) << e;
}
