#include "trueaxis/sim/machine.hpp"

#include <gtest/gtest.h>

#include <random>

#include "trueaxis/error.hpp"
#include "trueaxis/separation/separation.hpp"

namespace trueaxis::sim {
namespace {

constexpr double kRoundOff = 1e-12;  // mm: double round-off on ~1000 mm coordinates

Eigen::Vector3d random_command(const Machine& m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Eigen::Vector3d c;
  for (int k = 0; k < 3; ++k) {
    const auto& r = m.range[static_cast<std::size_t>(k)];
    c[k] = r[0] + (r[1] - r[0]) * U(rng);
  }
  return c;
}

Eigen::Vector3d unit(int k) {
  return Eigen::Vector3d::Unit(k);
}

TEST(ErrorFunction, PolynomialInMetresSinesAndTableAreSummed) {
  ErrorFunction f;
  f.polynomial = {1.0, 2.0, 3.0};  // 1 + 2·(u/1 m) + 3·(u/1 m)²
  EXPECT_NEAR(f(500), 1 + 2 * 0.5 + 3 * 0.25, 1e-15);
  f.polynomial.clear();
  f.sines = {{2.0, 100.0, 0.5}};
  EXPECT_NEAR(f(30), 2 * std::sin(2 * M_PI * 0.3 + 0.5), 1e-15);
  f.sines.clear();
  f.table_u = {0, 100, 300};
  f.table_value = {0, 1, -1};
  EXPECT_NEAR(f(50), 0.5, 1e-15);
  EXPECT_NEAR(f(200), 0.0, 1e-15);
  EXPECT_NEAR(f(300), -1.0, 1e-15);
  EXPECT_NO_THROW(f.validate("EXX", 0, 300));
  EXPECT_THROW(f.validate("EXX", 0, 400), Error);  // does not cover the range
  f.table_u = {0, 100, 100};
  EXPECT_THROW(f.validate("EXX", 0, 100), Error);  // not strictly increasing
  f = {};
  f.sines = {{1.0, 0.0, 0.0}};
  EXPECT_THROW(f.validate("EXX", 0, 100), Error);  // period 0
}

TEST(Machine, PerfectMachineHasNoError) {
  Machine m;
  m.offset = {10, -20, -150};
  std::mt19937_64 rng(1);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d c = random_command(m, rng);
    EXPECT_LT(m.error(c).norm(), kRoundOff);
    EXPECT_LT((m.actual(c) - c - m.offset).norm(), kRoundOff);
  }
}

TEST(Machine, TranslationErrorsAddDirectly) {
  // A straightness or positioning error of any axis moves the tool point by exactly itself.
  std::mt19937_64 rng(2);
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 3; ++c) {
      Machine m;
      m.offset = {5, 7, -120};
      m.errors[k][c].polynomial = {0.001, 0.004, -0.002};  // mm, in (u / 1 m)^j
      for (int i = 0; i < 20; ++i) {
        const Eigen::Vector3d cmd = random_command(m, rng);
        const Eigen::Vector3d expected = m.errors[k][c](cmd[k]) * unit(c);
        EXPECT_LT((m.error(cmd) - expected).norm(), kRoundOff)
            << error_name(k, static_cast<Component>(c));
      }
    }
}

TEST(Machine, RotationsActOnEverythingDownstreamOfTheAxis) {
  // An angular error of the axis at chain position i rotates (exactly) the vector from its
  // carriage to the tool point: the downstream axes' nominal moves plus the stylus offset.
  std::mt19937_64 rng(3);
  for (const std::string chain : {"FYXZ", "FXYZ", "XFYZ", "ZFYX"}) {
    for (int k = 0; k < 3; ++k)
      for (int c = 3; c < 6; ++c) {
        Machine m;
        m.chain = chain;
        m.offset = {15, -25, -140};
        m.errors[k][c].polynomial = {2e-4, -3e-4};  // rad: large, to make round-off irrelevant
        const auto order = m.order();
        const int pos = static_cast<int>(std::find(order.begin(), order.end(), k) - order.begin());
        for (int i = 0; i < 10; ++i) {
          const Eigen::Vector3d cmd = random_command(m, rng);
          Eigen::Vector3d arm = m.offset;
          for (int j = pos + 1; j < 3; ++j) arm += cmd[order[j]] * unit(order[j]);
          const Eigen::Matrix3d R(
              Eigen::AngleAxisd(m.errors[k][c](cmd[k]), unit(c - 3)).toRotationMatrix());
          EXPECT_LT((m.error(cmd) - (R * arm - arm)).norm(), kRoundOff)
              << chain << " " << error_name(k, static_cast<Component>(c));
        }
      }
  }
}

TEST(Machine, SquarenessTiltsTheAxesExactly) {
  Machine m;
  m.squareness_c0y = 50e-6;
  m.squareness_b0z = -30e-6;
  m.squareness_a0z = 40e-6;
  const Eigen::Vector3d c(300, 400, 250);
  const Eigen::Vector3d dy(-std::sin(50e-6), std::cos(50e-6), 0);
  const Eigen::Vector3d dz =
      Eigen::AngleAxisd(40e-6, unit(0)) * Eigen::Vector3d(std::sin(-30e-6), 0, std::cos(-30e-6));
  const Eigen::Vector3d expected = c.y() * (dy - unit(1)) + c.z() * (dz - unit(2));
  EXPECT_LT((m.error(c) - expected).norm(), kRoundOff);
  // First order: the textbook signs (Y leans towards −X for positive EC0Y, Z towards +X for
  // positive EB0Z and towards −Y for positive EA0Z). Second-order terms: 400·(50e-6)²/2 mm.
  const double second_order = 1e-6;
  EXPECT_NEAR(m.error(c).x(), -400 * 50e-6 + 250 * -30e-6, second_order);
  EXPECT_NEAR(m.error(c).y(), -250 * 40e-6, second_order);
}

// ISO 230-1's squareness is the angle between the axes' reference lines: a machine whose only
// errors are squareness errors gives them back, and straightness slopes that amount to a rigid
// rotation of the whole machine (EYX = ω·x, EXY = −ω·y) change neither squareness nor
// straightness, while the error functions' own values do.
TEST(Machine, ReferenceLinesGiveIsoSquarenessWhateverTheSplitOfTheSlopes) {
  constexpr double kSecondOrder = 1e-8;  // rad: products of the 30–50 µrad angles
  Machine m;
  m.squareness_c0y = 50e-6;
  m.squareness_b0z = -30e-6;
  m.squareness_a0z = 40e-6;
  const Eigen::Vector3d mid(400, 300, 250);
  auto r = reference_lines(m, mid);
  EXPECT_NEAR(r.c0y, 50e-6, kSecondOrder);
  EXPECT_NEAR(r.b0z, -30e-6, kSecondOrder);
  EXPECT_NEAR(r.a0z, 40e-6, kSecondOrder);
  for (const auto& axis : r.straightness)
    for (double s : axis) EXPECT_LT(s, kRoundOff);
  // A random machine, then the same turned rigidly about z by ω through its straightness slopes.
  MachineOptions o;
  o.seed = 4;
  Machine a = random_machine(o);
  Machine b = a;
  const double w = 30e-6;
  // Slopes are a rigid rotation to first order only: ω times the machine's µrad angles over
  // ~1 m leaves ~1e-7 mm.
  constexpr double kFirstOrder = 1e-6;  // mm
  b.errors[0][1].polynomial.resize(std::max<std::size_t>(2, b.errors[0][1].polynomial.size()));
  b.errors[1][0].polynomial.resize(std::max<std::size_t>(2, b.errors[1][0].polynomial.size()));
  b.errors[0][1].polynomial[1] += w * 1e3;  // EYX += ω·x (mm, x in m)
  b.errors[1][0].polynomial[1] -= w * 1e3;  // EXY −= ω·y
  const auto ra = reference_lines(a, mid), rb = reference_lines(b, mid);
  EXPECT_NEAR(ra.c0y, rb.c0y, kSecondOrder);
  EXPECT_NEAR(ra.b0z, rb.b0z, kSecondOrder);
  EXPECT_NEAR(ra.a0z, rb.a0z, kSecondOrder);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 2; ++j)
      EXPECT_NEAR(ra.straightness[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)],
                  rb.straightness[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)],
                  kFirstOrder);
  // The straightness is the bow about the reference line, not the slope: a linear EYX has none.
  Machine c;
  c.errors[0][1].polynomial = {0, 20e-3};  // 20 µm per metre
  EXPECT_LT(reference_lines(c, mid).straightness[0][0], kRoundOff);
  c.errors[0][1].polynomial = {0, 0,
                               40e-3};  // a bow: 40 µm/m² · x², over 0.8 m: 6.4 µm about its line
  EXPECT_NEAR(reference_lines(c, mid).straightness[0][0], 40e-3 * 0.8 * 0.8 / 4, 1e-9);
}

// The first-order (linearised) rigid-body model that identification fits, written out
// independently for any chain: Σ δ_k + Σ ε_k × (downstream moves + offset) + squareness terms.
Eigen::Vector3d first_order(const Machine& m, const Eigen::Vector3d& c) {
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  const auto order = m.order();
  for (int i = 0; i < 3; ++i) {
    const int k = order[i];
    const auto& f = m.errors[k];
    Eigen::Vector3d arm = m.offset;
    for (int j = i + 1; j < 3; ++j) arm += c[order[j]] * unit(order[j]);
    const Eigen::Vector3d delta(f[0](c[k]), f[1](c[k]), f[2](c[k]));
    const Eigen::Vector3d eps(f[3](c[k]), f[4](c[k]), f[5](c[k]));
    e += delta + eps.cross(arm);
  }
  e += Eigen::Vector3d(-m.squareness_c0y * c.y() + m.squareness_b0z * c.z(),
                       -m.squareness_a0z * c.z(), 0);
  return e;
}

TEST(Machine, RandomMachineAgreesWithTheFirstOrderModelToSecondOrder) {
  for (const std::string chain : {"FYXZ", "FXYZ", "XFYZ"}) {
    MachineOptions o;
    o.chain = chain;
    o.seed = 11;
    const Machine m = random_machine(o);
    std::mt19937_64 rng(4);
    double worst = 0, largest = 0;
    for (int i = 0; i < 500; ++i) {
      const Eigen::Vector3d c = random_command(m, rng);
      worst = std::max(worst, (m.error(c) - first_order(m, c)).norm());
      largest = std::max(largest, m.error(c).norm());
    }
    // Second-order terms: ε²·arm and ε·δ with ε ≲ 1e-4 rad, arm ≲ 1.5 m, δ ≲ 0.05 mm.
    const double second_order = 1e-8 * 1500 + 1e-4 * 0.05;
    EXPECT_LT(worst, second_order) << chain;
    EXPECT_GT(largest, 1000 * worst) << chain;  // the comparison is not vacuous
    EXPECT_GT(largest, 5e-3) << chain;          // realistic: several µm somewhere
  }
}

TEST(Machine, RandomMachinesAreReproducibleAndRealistic) {
  MachineOptions o;
  o.seed = 5;
  const Machine a = random_machine(o), b = random_machine(o);
  o.seed = 6;
  const Machine c = random_machine(o);
  const Eigen::Vector3d p(123, 456, 78);
  EXPECT_EQ(a.error(p), b.error(p));
  EXPECT_GT((a.error(p) - c.error(p)).norm(), 1e-6);
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    o.seed = seed;
    const Machine m = random_machine(o);
    for (int k = 0; k < 3; ++k) {
      const auto& r = m.range[k];
      for (int comp = 0; comp < 6; ++comp) {
        double lo = 1e300, hi = -1e300;
        for (int i = 0; i <= 100; ++i) {
          const double v = m.errors[k][comp](r[0] + (r[1] - r[0]) * i / 100.0);
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
        const double span = hi - lo;
        if (comp < 3 && comp != k) {  // straightness: a few µm over 500 mm
          EXPECT_GT(span, 0.2e-3);
          EXPECT_LT(span, 15e-3);
        } else if (comp == k) {  // positioning: ~10 µm/m
          EXPECT_LT(span, 60e-6 * (r[1] - r[0]));
        } else {  // angular: ~10 µrad
          EXPECT_GT(span, 0.5e-6);
          EXPECT_LT(span, 100e-6);
        }
      }
    }
    for (double s : {m.squareness_c0y, m.squareness_b0z, m.squareness_a0z})
      EXPECT_LT(std::abs(s), 100e-6);
  }
}

TEST(Machine, BatchErrorsEqualSinglePointErrors) {
  const Machine m = random_machine({});
  std::mt19937_64 rng(8);
  Eigen::Matrix3Xd c(3, 20000);
  for (Eigen::Index i = 0; i < c.cols(); ++i) c.col(i) = random_command(m, rng);
  const Eigen::Matrix3Xd e = m.errors_at(c);
  for (Eigen::Index i = 0; i < c.cols(); i += 997) EXPECT_EQ(e.col(i), m.error(c.col(i)));
}

TEST(Machine, ValidationNamesTheProblem) {
  Machine m;
  m.chain = "FXXZ";
  EXPECT_THROW(m.validate(), Error);
  m.chain = "FYXZ";
  m.range[1] = {600, 0};
  EXPECT_THROW(m.validate(), Error);
  m.range[1] = {0, 600};
  m.errors[2][4].table_u = {0, 100};
  m.errors[2][4].table_value = {0, 1e-6};
  try {
    m.validate();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("EBZ"), std::string::npos) << e.what();
  }
}

// Virtual probe runs -------------------------------------------------------------------------

TEST(ProbeRun, NoiseFreeSeparationRecoversTheMachinesStraightnessAndTheStraightedge) {
  const Machine m = random_machine({});
  struct Case {
    Eigen::Vector3d start, direction, sensing;
  };
  const std::vector<Case> cases = {
      {{0, 300, 250}, {1, 0, 0}, {0, 0, 1}},    // X line, vertical straightness
      {{400, 0, 100}, {0, 1, 0}, {1, 0, 0}},    // Y line, horizontal straightness
      {{200, 300, 0}, {0, 0, 1}, {0, 1, 0}},    // Z line
      {{0, 0, 250}, {0.8, 0.6, 0}, {0, 0, 1}},  // a diagonal of the XY plane
  };
  for (const auto& cs : cases) {
    ProbeRunOptions o;
    o.start = cs.start;
    o.direction = cs.direction;
    o.sensing = cs.sensing;
    o.stations = 21;
    o.step = 20;
    o.offsets = {0, 20, 40};
    o.angle = true;
    const auto run = simulate_probe_run(m, o);
    // The truth is the machine's own error along the sensing direction, at every stop.
    for (long K = 0; K < o.stations; ++K) {
      const Eigen::Vector3d c = cs.start + K * o.step * cs.direction.normalized();
      EXPECT_NEAR(run.truth.guide[run.truth.station_index(K)], cs.sensing.dot(m.error(c)), 1e-15);
    }
    separation::Options so;
    so.method = separation::Method::Lsq;
    so.compute_uncertainty = false;
    const auto r = separation::separate(run.data, so);
    const auto t = run.truth.like(r);
    EXPECT_LT((r.guide.value - t.guide.value).cwiseAbs().maxCoeff(), kRoundOff);
    EXPECT_LT((r.workpiece.value - t.workpiece.value).cwiseAbs().maxCoeff(), kRoundOff);
    EXPECT_LT((r.pitch->value - t.pitch->value).cwiseAbs().maxCoeff(), 1e-13);
    // Three-point with a calibrated zero difference needs no angle channel.
    separation::Options s3;
    s3.method = separation::Method::ThreePoint;
    const auto& po = run.truth.probe_offsets;
    s3.zero_difference = po[0] - 2 * po[1] + po[2];
    s3.compute_uncertainty = false;
    auto d3 = run.data;
    d3.angle.resize(0);
    const auto r3 = separation::separate(d3, s3);
    const auto t3 = run.truth.like(r3, false);
    EXPECT_LT((r3.guide.value - t3.guide.value).cwiseAbs().maxCoeff(), kRoundOff);
  }
}

TEST(ProbeRun, RefusesRunsOutsideTheRangeAndObliqueProbes) {
  const Machine m = random_machine({});
  ProbeRunOptions o;
  o.start = {700, 300, 250};
  o.stations = 21;
  o.step = 20;
  EXPECT_THROW(simulate_probe_run(m, o), Error);  // ends at x = 1100 > 800
  o.start = {0, 300, 250};
  o.sensing = {0.1, 0, 1};
  EXPECT_THROW(simulate_probe_run(m, o), Error);
}

}  // namespace
}  // namespace trueaxis::sim
