// Straightness separation against the virtual carriage's truth (noise-free) and the seed.
#include "trueaxis/separation/separation.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "../../src/separation/design.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/sim/straightness.hpp"

using namespace trueaxis;
using separation::Method;
using separation::Options;
using separation::Profile;
using separation::Reference;
using separation::Result;

namespace {

// Round-off tolerance for a profile of amplitude ~5 µm (5e-3 mm) recovered from n stations:
// the separation integrates once (two-point) or twice (three-point), so rounding grows like
// n^1.5 ulps of the readings. Measured: 2e-16 mm at 200 stations, 1.3e-9 mm at 1e6 (three-point).
double round_off(long n) {
  return 1e-15 + 1e-17 * std::pow(static_cast<double>(n), 1.5);
}

#if defined(__SANITIZE_ADDRESS__)
constexpr long kLongest = 100000;  // sanitizer builds are ~20x slower
#else
constexpr long kLongest = 1000000;
#endif

struct Truth {
  Profile w, g, t;
};

// The simulator's truth on the result's grids, in the same reference, with the parabola
// convention given explicitly (some tests compare deliberately against the wrong one).
Truth truth_for(const Result& r, const sim::StraightnessTruth& T, bool parabola_free) {
  const Result t = T.like(r, parabola_free);
  return {t.workpiece, t.guide, t.pitch ? *t.pitch : Profile{}};
}

double maxdiff(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

sim::StraightnessOptions carriage(long n, std::vector<double> offsets, std::uint64_t seed) {
  sim::StraightnessOptions o;
  o.stations = n;
  o.step = 10;
  o.offsets = std::move(offsets);
  o.seed = seed;
  return o;
}

bool has(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

}  // namespace

TEST(Separation, NoiseFreeEveryMethodRecoversTruthToRoundOff) {
  for (long n : {5L, 57L, 1000L, kLongest}) {
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      if (n == kLongest && seed > 1) continue;  // one long run per method keeps the suite short
      struct Case {
        Method m;
        std::vector<double> off;
        bool pitch;
      };
      for (const Case& c :
           {Case{Method::TwoPoint, {0, 10}, false}, Case{Method::ThreePoint, {0, 10, 20}, true},
            Case{Method::Lsq, {0, 10, 20}, true}, Case{Method::Lsq, {0, 10, 20, 30, 40}, true}}) {
        auto so = carriage(n, c.off, seed);
        if (!c.pitch) so.pitch_amplitude = 0;
        const auto camp = sim::simulate_straightness(so);
        Options o;
        o.method = c.m;
        o.compute_uncertainty = false;
        const Result r = separation::separate(camp.data, o);
        const Truth t = truth_for(r, camp.truth, has(r.unobservable, "parabola"));
        const double tol = round_off(n);
        EXPECT_LT(maxdiff(r.workpiece.value, t.w.value), tol)
            << to_string(c.m) << " n=" << n << " seed=" << seed;
        EXPECT_LT(maxdiff(r.guide.value, t.g.value), tol)
            << to_string(c.m) << " n=" << n << " seed=" << seed;
        if (r.pitch) {
          EXPECT_LT(maxdiff(r.pitch->value, t.t.value), tol / so.step)
              << to_string(c.m) << " n=" << n;
        }
      }
    }
  }
}

TEST(Separation, AngleChannelRecoversCurvatureThreePointCannot) {
  auto so = carriage(300, {0, 10, 20}, 5);
  so.angle = true;
  const auto camp = sim::simulate_straightness(so);
  Options o;
  o.compute_uncertainty = false;
  const Result lsq = separation::separate(camp.data, o);
  EXPECT_FALSE(has(lsq.unobservable, "parabola"));
  // Truth without any parabola convention: only the LS lines removed.
  const Truth t = truth_for(lsq, camp.truth, /*parabola_free=*/false);
  EXPECT_LT(maxdiff(lsq.workpiece.value, t.w.value), round_off(300));
  EXPECT_LT(maxdiff(lsq.guide.value, t.g.value), round_off(300));

  // Three-point on the same probes: right up to a parabola, which it cannot see.
  auto d3 = camp.data;
  d3.angle.resize(0);
  o.method = Method::ThreePoint;
  const Result b = separation::separate(d3, o);
  EXPECT_TRUE(has(b.unobservable, "parabola"));
  const Truth tb = truth_for(b, camp.truth, false);
  EXPECT_GT(maxdiff(b.guide.value, tb.g.value), 1e-4);  // the simulated guide has a real bow
}

TEST(Separation, KnownZeroDifferenceFixesTheParabola) {
  const auto so = carriage(400, {0, 10, 20}, 9);
  const auto camp = sim::simulate_straightness(so);
  const auto& o3 = camp.truth.probe_offsets;
  Options o;
  o.zero_difference = o3[0] - 2 * o3[1] + o3[2];
  o.compute_uncertainty = false;
  for (Method m : {Method::ThreePoint, Method::Lsq}) {
    o.method = m;
    const Result r = separation::separate(camp.data, o);
    EXPECT_FALSE(has(r.unobservable, "parabola"));
    const Truth t = truth_for(r, camp.truth, false);
    EXPECT_LT(maxdiff(r.workpiece.value, t.w.value), 1e-13) << to_string(m);
    EXPECT_LT(maxdiff(r.guide.value, t.g.value), 1e-13) << to_string(m);
  }
}

namespace {

// Three-point (b) and lsq (c) on the same data, and the largest differences of their workpiece
// and guide. Three-point reports the workpiece at probe A's positions, lsq also at the two beyond:
// compared on three-point's grid after the same reference.
struct LsqAndThreePoint {
  Result b, c;
  double dw = 0, dg = 0;
};
LsqAndThreePoint lsq_and_three_point(const separation::ProbeData& data) {
  LsqAndThreePoint r;
  Options o;
  o.compute_uncertainty = false;
  o.method = Method::ThreePoint;
  r.b = separation::separate(data, o);
  o.method = Method::Lsq;
  r.c = separation::separate(data, o);
  const Eigen::Index nw = r.b.workpiece.x.size();
  Profile cw{r.c.workpiece.x.head(nw), r.c.workpiece.value.head(nw), {}};
  Profile cg = r.c.guide;
  separation::express_in_reference(cw, cg, nullptr, Reference::LeastSquares, false);
  r.dw = maxdiff(cw.value, r.b.workpiece.value);
  r.dg = maxdiff(r.c.guide.value, r.b.guide.value);
  return r;
}

}  // namespace

TEST(Separation, LsqEqualsSeedMethodsWhereTheyApply) {
  const auto camp = sim::simulate_straightness(carriage(250, {0, 10, 20}, 11));
  const LsqAndThreePoint r = lsq_and_three_point(camp.data);
  const Result &b = r.b, &c = r.c;
  EXPECT_LT(r.dw, 1e-14);
  EXPECT_LT(r.dg, 1e-14);
  EXPECT_LT(maxdiff(c.pitch->value.head(b.pitch->value.size()).array() -
                        c.pitch->value.head(b.pitch->value.size()).mean(),
                    b.pitch->value.array() - b.pitch->value.mean()),
            1e-15);
}

// Three probes at equal spacing without an angle channel leave no redundancy: least squares
// solves the same equations as the three-point recurrence, which is exact to the readings'
// rounding. On a long noisy run the chain amplifies whatever the least-squares solve leaves in
// its right-hand sides by up to n² (10¹⁰ here), so this checks the refinement's residual. Formed
// as readings − workpiece − guide − pitch term − offset it agrees to 2e-10 of the guide; with
// the offsets subtracted before the guide and pitch (a rounding at the guide's size) it left
// 1.2e-8 (both measured).
TEST(Separation, LsqEqualsThreePointOnALongNoisyRun) {
  constexpr double kRelative = 1e-9;  // of the largest |guide|
  auto so = carriage(100000, {0, 10, 20}, 13);
  so.noise = 1e-4;
  const LsqAndThreePoint r = lsq_and_three_point(sim::simulate_straightness(so).data);
  const double size = r.b.guide.value.cwiseAbs().maxCoeff();
  EXPECT_LT(r.dg, kRelative * size);
  EXPECT_LT(r.dw, kRelative * size);
}

// The layout without redundancy (three probes at 0, 1, 2 steps, no angle channel) is solved
// directly, without the banded factorisation: both must give the same profiles and the same
// stated uncertainties, with the parabola by convention and with a known zero difference, from
// the shortest run to a long noisy one. Values to round-off of the profile. Variances to a part in
// 10⁹ of the largest on short runs (both exact there); at 10⁵ stations the banded covariance
// carries its own conditioning (measured: 3e-5 of the largest uncertainty), while the direct
// propagation agrees with the three-point recurrence's, on the grid they share (the guide's), to
// 3e-8 (measured).
TEST(Separation, DirectLsqEqualsTheBandedSolve) {
  ASSERT_TRUE(separation::detail::direct_layout({0, 1, 2}, false));
  ASSERT_FALSE(separation::detail::direct_layout({0, 1, 2}, true));
  ASSERT_FALSE(separation::detail::direct_layout({0, 1, 3}, false));
  struct Run {
    long n;
    double value_tol, unc_tol;  // relative to the largest |value| / |uncertainty|
  };
  // 513 stations: the uncertainty propagation's blocks of 256 stations end one station short
  // of the last, with the profile's end effects split across two blocks.
  for (const Run run : {Run{3, 1e-12, 1e-9}, Run{250, 1e-12, 1e-9}, Run{513, 1e-12, 1e-9},
                        Run{100000, 1e-9, 1e-4}}) {
    auto so = carriage(run.n, {0, 10, 20}, 17);
    so.noise = 1e-4;
    const auto camp = sim::simulate_straightness(so);
    for (const std::optional<double> e : {std::optional<double>(), std::optional<double>(0.002)})
      for (const bool sigma : {false, true}) {
        Options o;
        o.zero_difference = e;
        if (sigma) o.sigma = 1e-4;
        const double noise = sigma ? *o.sigma : 1.0;  // (unit noise for the noise gain)
        const std::string what =
            fmt::format("n {}, {}, {}", run.n, e ? "zero difference" : "parabola free",
                        sigma ? "sigma given" : "noise gain");
        const Result a =
            separation::detail::separate(camp.data, o, separation::detail::LsqSolver::Automatic);
        const Result b =
            separation::detail::separate(camp.data, o, separation::detail::LsqSolver::Banded);
        EXPECT_EQ(a.dof, 0) << what;
        EXPECT_EQ(b.dof, 0) << what;
        auto same = [&](const Profile& x, const Profile& y, const char* name) {
          ASSERT_EQ(x.value.size(), y.value.size()) << name << ", " << what;
          const double size = y.value.cwiseAbs().maxCoeff();
          EXPECT_LT(maxdiff(x.value, y.value), run.value_tol * size) << name << ", " << what;
          ASSERT_EQ(x.uncertainty.size(), y.uncertainty.size()) << name << ", " << what;
          if (y.uncertainty.size()) {
            // (at least the readings' noise: a profile of three stations has a guide of zero
            // uncertainty, found as round-off)
            const double largest = std::max(y.uncertainty.cwiseAbs().maxCoeff(), noise);
            EXPECT_LT(maxdiff(x.uncertainty.array().square(), y.uncertainty.array().square()),
                      run.unc_tol * largest * largest)
                << name << ", " << what;
          }
        };
        same(a.workpiece, b.workpiece, "workpiece");
        same(a.guide, b.guide, "guide");
        ASSERT_TRUE(a.pitch && b.pitch) << what;
        same(*a.pitch, *b.pitch, "pitch");
        ASSERT_EQ(a.noise_gain.has_value(), b.noise_gain.has_value()) << what;
        if (b.noise_gain) {
          EXPECT_NEAR(*a.noise_gain, *b.noise_gain, run.unc_tol * *b.noise_gain) << what;
        }
        EXPECT_EQ(a.gauge, b.gauge) << what;
        if (sigma && run.n > 1000) {
          // Relative to the largest. This bounds the three-point propagation's own round-off
          // (its guide's uncertainty is mirror-symmetric only to ~1e-7 of the largest here).
          constexpr double kAgainstThreePoint = 2e-7;
          o.method = Method::ThreePoint;
          const Result c = separation::separate(camp.data, o);
          const double largest = c.guide.uncertainty.maxCoeff();
          EXPECT_LT(maxdiff(a.guide.uncertainty, c.guide.uncertainty), kAgainstThreePoint * largest)
              << what;
          // The layout is its own mirror image (probes at 0, 1, 2 steps, evenly spaced stations),
          // and so is the guide's uncertainty: how far it is from symmetric measures the
          // propagation's round-off, far below the three-point propagation's (measured 6e-12
          // against 1.2e-7).
          constexpr double kMirror = 1e-9;  // relative to the largest
          const Eigen::VectorXd& u = a.guide.uncertainty;
          EXPECT_LT(maxdiff(u, u.reverse()), kMirror * u.maxCoeff()) << what;
        }
      }
  }
}

// An independent implementation of the patent's equations (JPH0464003B2 eqs. 12–17), written
// straight from the text in one pass with Cramer's rule on the γ/δ sums.
TEST(Separation, SeedReferenceMatchesAnIndependentImplementation) {
  const auto so = carriage(60, {0, 10, 20}, 4);
  const auto camp = sim::simulate_straightness(so);
  const auto& D = camp.data.readings;
  const long n = D.rows();
  const double l = so.step;
  std::vector<double> C(n, 0.0), X(n), Y(n), th(n - 1);
  auto d = [&](long K, int i) { return D(K, i) - D(0, i); };
  for (long K = 0; K + 2 < n; ++K)
    C[K + 2] = 2 * C[K + 1] - C[K] - 2 * d(K + 1, 0) + d(K + 2, 0) + 2 * d(K, 1) - d(K, 2);
  double g2 = 0, g3 = 0, g4 = 0, d1 = 0, d2 = 0;  // over K = 2..n-1 with basis K and K(K-1)/2
  for (long K = 2; K < n; ++K) {
    const double k = static_cast<double>(K), q = k * (k - 1) / 2;
    g2 += k * k;
    g3 += k * q;
    g4 += q * q;
    d1 += k * C[K];
    d2 += q * C[K];
  }
  const double det = g2 * g4 - g3 * g3;
  const double alpha = (-d1 * g4 + d2 * g3) / det;
  const double beta = (-d2 * g2 + d1 * g3) / det;
  for (long K = 0; K < n; ++K) {
    const double k = static_cast<double>(K);
    X[K] = k * alpha + k * (k - 1) / 2 * beta + C[K];
    Y[K] = d(K, 0) - X[K];
  }
  for (long K = 0; K + 1 < n; ++K) th[K] = (d(K, 1) - Y[K + 1] - X[K] + Y[1]) / l;

  Options o;
  o.method = Method::ThreePoint;
  o.reference = Reference::Seed;
  const Result r = separation::separate(camp.data, o);
  ASSERT_EQ(r.guide.value.size(), n);
  ASSERT_TRUE(r.pitch);
  ASSERT_EQ(r.pitch->value.size(), n - 1);
  // The one-pass reference cancels C_K ~ K²β against the fit, so it carries ~1e-15 mm of
  // rounding itself; agreement to 1e-13 mm (1e-10 µm) is agreement to round-off.
  constexpr double kSeedRoundOff = 1e-13;
  for (long K = 0; K < n; ++K) {
    EXPECT_NEAR(r.guide.value[K], X[K], kSeedRoundOff) << K;
    EXPECT_NEAR(r.workpiece.value[K], Y[K], kSeedRoundOff) << K;
  }
  for (long K = 0; K + 1 < n; ++K) EXPECT_NEAR(r.pitch->value[K], th[K], kSeedRoundOff / l) << K;
  EXPECT_EQ(r.pitch->value[0], 0.0);  // relative to the first station
  EXPECT_TRUE(r.workpiece.uncertainty.size() == 0);
}

TEST(Separation, PitchingCarriageTwoPointIntegratesPitchThreePointRemovesIt) {
  auto so = carriage(200, {0, 10, 20}, 21);
  so.pitch_amplitude = 5e-6;
  const auto camp = sim::simulate_straightness(so);
  Options o;
  o.compute_uncertainty = false;
  o.method = Method::TwoPoint;
  separation::ProbeData d2 = camp.data;
  d2.readings = camp.data.readings.leftCols(2);
  d2.offsets = {0, 10};
  const Result a = separation::separate(d2, o);
  o.method = Method::ThreePoint;
  const Result b = separation::separate(camp.data, o);

  // Two-point: its workpiece = truth + the integrated pitch term Σ s_B·θ (up to the LS line).
  const Truth ta = truth_for(a, camp.truth, false);
  Eigen::VectorXd integ = Eigen::VectorXd::Zero(a.workpiece.x.size());
  for (long K = 0; K + 1 < integ.size(); ++K)
    integ[K + 1] = integ[K] + so.offsets[1] * (camp.truth.pitch[K] - camp.truth.pitch[0]);
  Profile expect{a.workpiece.x, ta.w.value + integ, {}}, dummy = ta.g;
  separation::express_in_reference(expect, dummy, nullptr, Reference::LeastSquares, false);
  EXPECT_LT(maxdiff(a.workpiece.value, expect.value), 1e-14);
  EXPECT_GT(maxdiff(a.workpiece.value, ta.w.value), 1e-4);  // the pitch error is visible (>0.1 µm)

  const Truth tb = truth_for(b, camp.truth, true);
  EXPECT_LT(maxdiff(b.workpiece.value, tb.w.value), 1e-14);  // three-point removes it
}

TEST(Separation, UnobservableLayoutsAreRefusedWithTheirModes) {
  auto so = carriage(100, {0, 20, 40}, 1);
  const auto camp = sim::simulate_straightness(so);
  Options o;
  try {
    separation::separate(camp.data, o);
    FAIL() << "chains not tied together must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("chain offsets (2 chains)"), std::string::npos)
        << e.what();
  }
  const auto la = separation::analyze_layout({0, 2, 4}, false, false, 100);
  EXPECT_FALSE(la.observable);
  EXPECT_GT(la.extra_null_modes, 0);
  // Three probes with uneven spacing: an edge mode of root -1/2.
  const auto lb = separation::analyze_layout({0, 2, 3}, false, false, 100);
  EXPECT_FALSE(lb.observable);
  EXPECT_TRUE(has(lb.unobservable, "1 blind or edge mode(s)"));
  // Observable layouts name only the line (and the parabola when no angle or e is given).
  const auto lc = separation::analyze_layout({0, 1, 2}, false, false, 100);
  EXPECT_TRUE(lc.observable);
  EXPECT_EQ(lc.unobservable, (std::vector<std::string>{"line", "parabola"}));
  EXPECT_TRUE(separation::analyze_layout({0, 1, 2}, true, false, 100).unobservable ==
              std::vector<std::string>{"line"});
}

TEST(Separation, BadInputsGiveClearErrors) {
  const auto camp = sim::simulate_straightness(carriage(50, {0, 10, 20}, 1));
  auto expect_error = [&](separation::ProbeData d, Options o, const std::string& what) {
    try {
      separation::separate(d, o);
      ADD_FAILURE() << "expected: " << what;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  Options o;
  auto d = camp.data;
  d.x[7] = d.x[6];
  expect_error(d, o, "station 7 does not increase");
  d = camp.data;
  d.x[7] += 1;
  expect_error(d, o, "uneven step at station 7");
  d = camp.data;
  d.readings(3, 1) = NAN;
  expect_error(d, o, "non-finite");
  d = camp.data;
  d.offsets = {0, 10, 25};
  expect_error(d, o, "not a whole multiple of the step");
  d = camp.data;
  d.x.conservativeResize(2);
  d.readings.conservativeResize(2, 3);
  expect_error(d, o, "too few stations");
  o.method = Method::TwoPoint;
  expect_error(camp.data, o, "method two-point needs probes at offsets 0, 10 mm");
  o.method = Method::Lsq;
  o.reference = Reference::Seed;
  expect_error(camp.data, o, "reference 'patent' is defined for the three-point method only");
  o.reference = Reference::LeastSquares;
  o.zero_difference = 1e-3;
  d = camp.data;
  d.readings = camp.data.readings.leftCols(2);
  d.offsets = {0, 10};
  expect_error(d, o, "zero difference is defined for three-probe layouts only");
}

// Long data have their values checked on another core while the method runs: a bad value is
// still the error reported, before any error the method or the options would give, and for
// every method.
TEST(Separation, LongDataReportBadValuesFirst) {
  const auto camp = sim::simulate_straightness(carriage(60000, {0, 10, 20}, 4));
  auto message = [](const separation::ProbeData& d, const Options& o) -> std::string {
    try {
      separation::separate(d, o);
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  for (Method m : {Method::TwoPoint, Method::ThreePoint, Method::Lsq}) {
    Options o;
    o.method = m;
    auto d = camp.data;
    d.readings(59990, 2) = INFINITY;
    EXPECT_NE(message(d, o).find("non-finite"), std::string::npos) << to_string(m);
    // A non-finite station position, inside or at either end (x's check shares the steps' pass).
    for (Eigen::Index i : {Eigen::Index{0}, Eigen::Index{31337}, d.x.size() - 1}) {
      d = camp.data;
      d.x[i] = i == 0 ? -INFINITY : NAN;
      EXPECT_NE(message(d, o).find("non-finite"), std::string::npos) << to_string(m) << " " << i;
    }
    d = camp.data;
    d.x[40000] += 1;
    EXPECT_NE(message(d, o).find("uneven step at station 40000"), std::string::npos)
        << to_string(m);
    // The values' error also comes before the options' own.
    o.filter_cutoff = -1;
    EXPECT_NE(message(d, o).find("uneven step at station 40000"), std::string::npos)
        << to_string(m);
    // A broken x that makes the probe offsets an absurd number of steps: nothing is sized by
    // them, the values' error is reported.
    o.filter_cutoff = 0;
    d = camp.data;
    d.x.setZero();
    d.x[d.x.size() - 1] = 1e-300;
    EXPECT_NE(message(d, o).find("station 1 does not increase"), std::string::npos) << to_string(m);
  }
}

TEST(Separation, MinZoneReferenceCentresTheZone) {
  const auto camp = sim::simulate_straightness(carriage(120, {0, 10, 20}, 3));
  Options o;
  o.reference = Reference::MinZone;
  o.compute_uncertainty = false;
  const Result r = separation::separate(camp.data, o);
  EXPECT_NEAR(r.workpiece.value.maxCoeff(), -r.workpiece.value.minCoeff(), 1e-15);
  EXPECT_NEAR(r.workpiece.value.maxCoeff() - r.workpiece.value.minCoeff(),
              r.workpiece_straightness.min_zone, 1e-12);
  EXPECT_LE(r.workpiece_straightness.min_zone, r.workpiece_straightness.ls);
}

// Readings written in millimetres where micrometres are expected are 1000 times too small and
// give figures 1000 times too small that look resolved; the result says what they look like.
// Offsets nobody stated are said to be assumed.
TEST(Separation, MillimetreReadingsAndAssumedOffsetsAreSaid) {
  sim::StraightnessOptions so;
  so.stations = 120;
  so.noise = 0.02e-3;
  so.angle = true;
  auto camp = sim::simulate_straightness(so);
  auto says = [](const separation::Result& r, const std::string& what) {
    for (const auto& w : r.warnings())
      if (w.find(what) != std::string::npos) return true;
    return false;
  };
  const auto right = separation::separate(camp.data);
  EXPECT_FALSE(says(right, "1000 times too small"));
  EXPECT_FALSE(says(right, "offsets were not stated"));
  camp.data.readings *= 1e-3;  // µm values read in mm, then taken as µm
  camp.data.offsets_assumed = true;
  const auto wrong = separation::separate(camp.data);
  EXPECT_TRUE(says(wrong, "all probe readings lie within"));
  EXPECT_TRUE(says(wrong, "1000 times too small"));
  EXPECT_TRUE(says(wrong, "offsets were not stated, so they were taken as 0, 10, 20 mm"));
}
