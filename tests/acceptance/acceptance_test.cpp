// CMM acceptance tests (ISO 10360-2 E0/R0, ISO 10360-5 PForm/PSize) on the virtual CMM, against
// the machine's own error field computed here.
#include "trueaxis/acceptance/acceptance.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/sim/machine.hpp"

using namespace trueaxis;

namespace {

sim::Machine default_volume_machine(std::uint64_t seed) {
  sim::MachineOptions o;
  o.seed = seed;
  return sim::random_machine(o);
}

// The tip position the CMM reads when its tip really is at P (mm): P less the error at the
// command that puts it there, from the machine's functions directly.
Eigen::Vector3d read_at(const sim::Machine& m, const Eigen::Vector3d& P) {
  Eigen::Vector3d c = P - m.offset;
  for (int it = 0; it < 10; ++it) c = P - m.offset - m.error(c);
  return c + m.offset;
}

}  // namespace

// The example set-up is an ISO 10360-2 test of the volume: 7 positions, 4 of them the space
// diagonals, 5 lengths each, 105 lengths measured.
TEST(Acceptance, TheExampleSetUpIsAStandardTest) {
  const auto m = default_volume_machine(1);
  const auto volume = acceptance::Volume::of(m);
  const auto setup = acceptance::example_setup(volume);
  const auto pos = acceptance::positions(setup, volume);
  ASSERT_EQ(pos.size(), 7u);
  EXPECT_EQ(std::count_if(pos.begin(), pos.end(), [](const auto& p) { return p.space_diagonal; }),
            4);
  acceptance::E0Options o;
  o.mpe = ballgauge::Mpe::parse("1.5+L/300");
  const auto r = acceptance::run_e0(setup, volume, acceptance::virtual_touch(m), o);
  EXPECT_EQ(r.lengths.size(), 105u);
  EXPECT_EQ(r.r0.size(), 35u);
  EXPECT_TRUE(r.complete);
}

// Noise-free, each length error is the machine's error field at the two ends projected on the
// length's direction (the probe's qualified radius cancels), as computed here from the machine.
TEST(Acceptance, EachLengthErrorIsTheErrorFieldAlongIt) {
  const auto m = default_volume_machine(3);
  const auto volume = acceptance::Volume::of(m);
  const auto setup = acceptance::example_setup(volume);
  acceptance::E0Options o;
  o.mpe = ballgauge::Mpe::parse("1.5+L/300");
  const auto r = acceptance::run_e0(setup, volume, acceptance::virtual_touch(m), o);
  ASSERT_EQ(r.lengths.size(), 105u);
  double largest = 0;
  for (const auto& row : r.lengths) {
    const auto& p = *std::find_if(setup.placements.begin(), setup.placements.end(),
                                  [&](const auto& q) { return q.block == row.block; });
    const double L = setup.block(row.block).length;
    const Eigen::Vector3d fa = p.centre - L / 2 * p.direction, fb = p.centre + L / 2 * p.direction;
    // The tip's centre 1 mm (any radius) off each face, on the side it comes from.
    const Eigen::Vector3d ra = read_at(m, fa - p.direction) + p.direction,
                          rb = read_at(m, fb + p.direction) - p.direction;
    const double expected = (rb - ra).dot(p.direction) - L;
    EXPECT_NEAR(row.error, expected, 1e-9) << row.position << " " << row.block;
    largest = std::max(largest, std::abs(expected));
  }
  EXPECT_NEAR(r.e0_max, largest, 1e-12);
  EXPECT_GT(r.e0_max, 5e-3);  // a random machine uncorrected: micrometres, not nothing
  EXPECT_EQ(r.verdict, acceptance::Verdict::DoesNotConform);
  EXPECT_EQ(r.r0_max, 0);  // no noise: repetitions agree
}

// E150: the stylus tip 150 mm across the ram. Each length error is the error field of the machine
// probing with that stylus, computed here in two parts at the commands that bring the tip to the
// faces: the vertical stylus's error e(c) and the Abbe term (R(c) − I)·ℓ, the carriages'
// rotations times the offset, which E0's stylus does not see.
TEST(Acceptance, E150AddsTheCarriagesRotationsTimesTheStylusOffset) {
  const auto m = default_volume_machine(3);
  const Eigen::Vector3d lateral(150, 0, 0);
  const auto m150 = acceptance::with_stylus(m, lateral);
  EXPECT_TRUE(m150.offset.isApprox(m.offset + lateral));
  const auto volume = acceptance::Volume::of(m150);
  EXPECT_NEAR(volume.low.x(), acceptance::Volume::of(m).low.x() + 150, 1e-12);
  const auto setup = acceptance::example_setup(volume);
  acceptance::E0Options o;
  o.mpe = ballgauge::Mpe::parse("1.5+L/300");
  o.stylus_offset = lateral;
  const auto r = acceptance::run_e0(setup, volume, acceptance::virtual_touch(m150), o);
  EXPECT_EQ(r.name(), "E150");
  ASSERT_EQ(r.positions.size(), 2u);  // two positions, by default the first two space diagonals
  EXPECT_TRUE(r.positions[0].space_diagonal && r.positions[1].space_diagonal);
  ASSERT_EQ(r.lengths.size(), 30u);  // 2 positions × 5 lengths × 3 repetitions
  // The command that puts the tip (stylus offset o + ℓ) at P, by fixed-point steps.
  const auto command = [&](const Eigen::Vector3d& P) {
    Eigen::Vector3d c = P - m150.offset;
    for (int it = 0; it < 10; ++it) c = P - m150.offset - m150.error(c);
    return c;
  };
  double largest_abbe = 0;
  for (const auto& row : r.lengths) {
    const auto& p = *std::find_if(setup.placements.begin(), setup.placements.end(),
                                  [&](const auto& q) { return q.block == row.block; });
    const double L = setup.block(row.block).length;
    const Eigen::Vector3d ca = command(p.centre - (L / 2 + 1) * p.direction),
                          cb = command(p.centre + (L / 2 + 1) * p.direction);
    const double vertical = -(m.error(cb) - m.error(ca)).dot(p.direction);
    const double abbe = -((m.pose(cb).linear() - m.pose(ca).linear()) * lateral).dot(p.direction);
    EXPECT_NEAR(row.error, vertical + abbe, 1e-9) << row.position << " " << row.block;
    largest_abbe = std::max(largest_abbe, std::abs(abbe));
  }
  EXPECT_GT(largest_abbe, 1e-3);  // the random machine's rotations: micrometres at 150 mm
  EXPECT_NE(r.rule.find("E150,MPE"), std::string::npos) << r.rule;
  // The set-up made for the vertical stylus does not fit the offset one's volume: refused.
  const auto vertical_setup = acceptance::example_setup(acceptance::Volume::of(m));
  const std::string e = test::error_of(
      [&] { acceptance::run_e0(vertical_setup, volume, acceptance::virtual_touch(m150), o); });
  EXPECT_NE(e.find("outside the volume"), std::string::npos) << e;
  // Positions by name; an unknown one, choosing positions for E0, and an offset along the ram
  // are refused.
  auto named = o;
  named.positions = {"along X", "along Y"};
  const auto rx = acceptance::run_e0(setup, volume, acceptance::virtual_touch(m150), named);
  ASSERT_EQ(rx.positions.size(), 2u);
  EXPECT_EQ(rx.positions[0].name, "along X");
  named.positions = {"along W"};
  EXPECT_NE(test::error_of([&] {
              acceptance::run_e0(setup, volume, acceptance::virtual_touch(m150), named);
            }).find("no position 'along W'"),
            std::string::npos);
  auto e0 = o;
  e0.stylus_offset.reset();
  e0.positions = {"along X"};
  EXPECT_NE(test::error_of([&] {
              acceptance::run_e0(setup, volume, acceptance::virtual_touch(m150), e0);
            }).find("every position"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] {
              acceptance::with_stylus(m, Eigen::Vector3d(0, 0, -150));
            }).find("across the ram"),
            std::string::npos);
  EXPECT_THROW(acceptance::with_stylus(m, Eigen::Vector3d(900, 0, 0)), Error);
}

// ISO 14253-1 at the MPE: conformance proven below MPE − U, non-conformance above MPE + U,
// neither between; R0 is the range of the repetitions.
TEST(Acceptance, TheVerdictFollowsTheDecisionRuleWithTheTestUncertainty) {
  sim::Machine m = default_volume_machine(1);
  for (auto& axis : m.errors)
    for (auto& f : axis) f = {};
  m.squareness_c0y = m.squareness_b0z = m.squareness_a0z = 0;
  m.errors[0][0].polynomial = {0, 4e-3};  // X 4 µm/m long
  const auto volume = acceptance::Volume::of(m);
  auto setup = acceptance::example_setup(volume);
  setup.u_temperature = 0.05;  // K: a temperature-controlled room (0.2 K: U 3.3 µm at 700 mm)
  acceptance::VirtualProbeOptions probe;
  probe.noise = 0.2e-3;
  probe.seed = 5;
  acceptance::E0Options o;
  o.mpe = ballgauge::Mpe::parse("1.5+L/300");
  auto r = acceptance::run_e0(setup, volume, acceptance::virtual_touch(m, probe), o);
  EXPECT_EQ(r.verdict, acceptance::Verdict::Conforms) << r.summary();
  // R0 per position and length from the rows, here.
  std::map<std::pair<std::string, std::string>, std::pair<double, double>> span;
  for (const auto& row : r.lengths) {
    auto [it, fresh] = span.try_emplace({row.position, row.block}, row.measured, row.measured);
    it->second = {std::min(it->second.first, row.measured),
                  std::max(it->second.second, row.measured)};
  }
  double r0 = 0;
  for (const auto& [key, mm] : span) r0 = std::max(r0, mm.second - mm.first);
  EXPECT_NEAR(r.r0_max, r0, 1e-15);
  EXPECT_GT(r.r0_max, 0);
  // A tighter MPE: between MPE − U and MPE + U for the worst length, neither is proven.
  const auto worst = *std::max_element(r.lengths.begin(), r.lengths.end(), [](auto& a, auto& b) {
    return std::abs(a.error) - a.U < std::abs(b.error) - b.U;
  });
  ASSERT_GT(worst.U, 0);
  o.mpe = ballgauge::Mpe::parse(fmt::format("{}", (std::abs(worst.error) + worst.U / 2) * 1e3));
  acceptance::judge_e0(setup, o, r);
  EXPECT_EQ(r.verdict, acceptance::Verdict::NotProven) << r.summary();
  o.mpe = ballgauge::Mpe::parse(fmt::format("{}", (std::abs(worst.error) - 1.5 * worst.U) * 1e3));
  acceptance::judge_e0(setup, o, r);
  EXPECT_EQ(r.verdict, acceptance::Verdict::DoesNotConform) << r.summary();
  EXPECT_NE(r.rule.find("ISO 14253-1"), std::string::npos);
  // U (k = 2) is ISO/TS 23165's budget for each length, computed here: calibration, the
  // temperature's and the expansion coefficient's effects, alignment and fixturing.
  setup.temperature = 21.5;
  setup.u_fixturing = 0.3e-3;
  acceptance::judge_e0(setup, o, r);
  for (const auto& row : r.lengths) {
    const auto& b = setup.block(row.block);
    const double u2 = b.u * b.u + std::pow(b.length * b.alpha * setup.u_temperature, 2) +
                      std::pow(b.length * b.u_alpha * 1.5, 2) + std::pow(setup.u_alignment, 2) +
                      std::pow(0.3e-3, 2);
    EXPECT_NEAR(row.U, 2 * std::sqrt(u2), 1e-15) << row.block;
  }
}

// A CMM that stops answering: what was measured is kept and judged as far as it goes.
TEST(Acceptance, AStoppedRunKeepsWhatWasMeasured) {
  const auto m = default_volume_machine(2);
  const auto volume = acceptance::Volume::of(m);
  const auto setup = acceptance::example_setup(volume);
  const auto inner = acceptance::virtual_touch(m);
  int calls = 0;
  const acceptance::Touch failing = [&](const Eigen::Vector3d& at, const Eigen::Vector3d& d) {
    if (++calls > 20) throw Error("error 1006: surface not found");
    return inner(at, d);
  };
  acceptance::E0Options o;
  o.mpe = ballgauge::Mpe::parse("100");
  const auto r = acceptance::run_e0(setup, volume, failing, o);
  EXPECT_FALSE(r.complete);
  EXPECT_EQ(r.lengths.size(), 10u);
  EXPECT_NE(r.stopped.find("1006"), std::string::npos);
  EXPECT_EQ(r.verdict, acceptance::Verdict::NotProven);  // all within, but not all measured
  // Nothing measured: no figure (not a zero); one repetition: no R0.
  acceptance::E0Result none;
  acceptance::judge_e0(setup, o, none);
  EXPECT_NE(none.summary().find("no length measured"), std::string::npos) << none.summary();
  const std::string empty = test::temp_dir() + "/empty-e0.json";
  io::write_e0_result(empty, none);
  EXPECT_NE(test::read_file(empty).find("\"E0_max_um\": null"), std::string::npos);
  EXPECT_TRUE(io::read_e0_result(empty).lengths.empty());
  auto once = setup;
  once.repetitions = 1;
  const auto single = acceptance::run_e0(once, volume, inner, o);
  EXPECT_TRUE(single.r0.empty());
  EXPECT_NE(single.summary().find("R0 not determined"), std::string::npos) << single.summary();
  const std::string path = test::temp_dir() + "/stopped-e0.json";
  io::write_e0_result(path, r);
  const std::string text = test::read_file(path);
  EXPECT_NE(text.find("\"complete\": false"), std::string::npos);
  EXPECT_NE(text.find("\"endpoints\""), std::string::npos);
}

// ISO 10360-5: the pattern's 25 directions, and the form error that the probe's lobing alone
// gives, computed here by linear least squares of the radial shifts (centre and radius).
TEST(Acceptance, ProbingFormIsTheLobingsEffectOnThe25Points) {
  const auto dirs = acceptance::probing_pattern(Eigen::Vector3d::UnitZ());
  ASSERT_EQ(dirs.size(), 25u);
  int equator = 0;
  for (const auto& d : dirs) {
    EXPECT_NEAR(d.norm(), 1, 1e-15);
    EXPECT_GE(d.z(), -1e-12);  // a hemisphere: all reachable from above
    equator += std::abs(d.z()) < 1e-12;
  }
  EXPECT_EQ(equator, 8);
  sim::Machine perfect;
  perfect.range = {{{0, 800}, {0, 600}, {0, 500}}};
  acceptance::Setup setup;
  acceptance::ReferenceSphere sphere;
  sphere.centre = {200, 200, 100};
  sphere.diameter = 25;
  sphere.u_diameter = 0.1e-3;
  sphere.form = 0.05e-3;
  setup.sphere = sphere;
  acceptance::VirtualProbeOptions probe;
  probe.lobing = 1e-3;
  acceptance::ProbingOptions o;
  o.mpe_form = 1.8e-3;
  o.mpe_size = 1.5e-3;
  const auto r = acceptance::run_probing(setup, acceptance::virtual_touch(perfect, probe), o);
  // Each point moves along its probing direction (−n) by the pre-travel: radially by −δ.
  Eigen::MatrixXd A(25, 4);
  Eigen::VectorXd shift(25);
  for (int i = 0; i < 25; ++i) {
    const Eigen::Vector3d n = dirs[static_cast<std::size_t>(i)], d = -n;
    const double delta = 1e-3 * std::cos(3 * std::atan2(d.y(), d.x())) * (1 - d.z() * d.z());
    shift[i] = -delta;
    A.row(i) << 1, n.x(), n.y(), n.z();
  }
  const Eigen::VectorXd coef = A.colPivHouseholderQr().solve(shift);
  const Eigen::VectorXd radial = shift - A * coef;
  EXPECT_NEAR(r.form, radial.maxCoeff() - radial.minCoeff(), 1e-7);
  EXPECT_NEAR(r.size, 2 * coef[0], 1e-7);
  EXPECT_GT(r.form, 0.5e-3);
  ASSERT_TRUE(r.form_verdict && r.size_verdict);
  EXPECT_EQ(*r.form_verdict, acceptance::Verdict::Conforms);
  // With the machine's geometric errors too: over the sphere they are nearly an affine
  // distortion (an ellipsoid, a few tenths of a µm of form), and the residuals add, so the form
  // lies within the machine's own of the lobing's: the probe's part is not the machine's, and
  // no map of the machine removes it.
  const auto m = default_volume_machine(4);
  const auto with_errors = acceptance::run_probing(setup, acceptance::virtual_touch(m, probe), o);
  const auto machine_only = acceptance::run_probing(setup, acceptance::virtual_touch(m), o);
  EXPECT_LE(std::abs(with_errors.form - r.form), machine_only.form + 1e-8);
  EXPECT_LT(machine_only.form, r.form);
}

// Set-ups that cannot be an ISO 10360-2 test are refused with every reason.
TEST(Acceptance, BadSetUpsAreRefusedWithTheirReasons) {
  const auto m = default_volume_machine(1);
  const auto volume = acceptance::Volume::of(m);
  const auto good = acceptance::example_setup(volume);
  auto refused = [&](const acceptance::Setup& s) {
    return test::error_of([&] { acceptance::positions(s, volume); });
  };
  auto outside = good;
  outside.placements[0].centre.x() += 300;
  EXPECT_NE(refused(outside).find("outside the volume"), std::string::npos) << refused(outside);
  auto overlap = good;
  overlap.placements[1].centre = overlap.placements[0].centre;
  EXPECT_NE(refused(overlap).find("overlap"), std::string::npos);
  auto six = good;
  six.placements.erase(six.placements.begin(), six.placements.begin() + 5);  // diagonal 1
  const std::string e6 = refused(six);
  EXPECT_NE(e6.find("6 positions"), std::string::npos) << e6;
  EXPECT_NE(e6.find("3 of the 4 space diagonals"), std::string::npos) << e6;
  auto four = good;
  four.placements.erase(four.placements.begin() + 4);  // diagonal 1's shortest
  EXPECT_NE(refused(four).find("4 different lengths"), std::string::npos);
  auto short_set = good;
  short_set.blocks[0].length = 300;  // diagonal 1's longest
  EXPECT_NE(refused(short_set).find("below 66 %"), std::string::npos) << refused(short_set);
  auto unknown = good;
  unknown.placements[3].block = "no such block";
  EXPECT_NE(refused(unknown).find("no such block"), std::string::npos);
}

// The set-up file: written and read back; bad ones refused at file:line:col.
TEST(Acceptance, SetUpFilesRoundTripAndBadOnesAreRefused) {
  const auto volume = acceptance::Volume::of(default_volume_machine(1));
  const auto setup = acceptance::example_setup(volume);
  const std::string path = test::temp_dir() + "/acceptance.json";
  io::write_acceptance_setup(path, setup);
  const auto back = io::read_acceptance_setup(path);
  ASSERT_EQ(back.placements.size(), setup.placements.size());
  EXPECT_NEAR((back.placements[7].centre - setup.placements[7].centre).norm(), 0, 1e-12);
  EXPECT_NEAR(back.blocks[2].u, setup.blocks[2].u, 1e-15);
  ASSERT_TRUE(back.sphere);
  EXPECT_NEAR(back.sphere->diameter, setup.sphere->diameter, 1e-12);
  EXPECT_NO_THROW(acceptance::positions(back, volume));
  auto refused = [](const std::string& text) {
    return test::error_of([&] { io::read_acceptance_setup(test::temp_file("bad.json", text)); });
  };
  const std::string block = R"({"id": "A", "length_mm": 100})";
  EXPECT_NE(
      refused(R"({"blocks": [)" + block +
              R"(], "placements": [{"block": "B", "centre": [0, 0, 0], "direction": [1, 0, 0]}]})")
          .find("bad.json:1:"),
      std::string::npos);
  const std::string zero = refused(R"({"blocks": [)" + block +
                                   R"(],
 "placements": [{"block": "A", "centre": [0, 0, 0], "direction": [0, 0, 0]}]})");
  EXPECT_NE(zero.find("bad.json:2:"), std::string::npos) << zero;
  EXPECT_NE(zero.find("not a direction"), std::string::npos) << zero;
  EXPECT_NE(refused(R"({"blocks": [{"id": "A", "length_mm": "long"}], "placements": []})")
                .find("bad.json:1:"),
            std::string::npos);
  EXPECT_NE(refused(R"({"sphere": {"centre": [0, 0], "diameter_mm": 25}})").find("three numbers"),
            std::string::npos);
  EXPECT_NE(refused("{}").find("nothing to test"), std::string::npos);
  EXPECT_NE(refused(R"({"kind": "circular"})").find("acceptance-setup"), std::string::npos);
  EXPECT_NE(refused(R"({"blocks": [)" + block + "," + block + "]}").find("twice"),
            std::string::npos);
}

// The results written and read back, and tampered ones refused where they are wrong.
TEST(Acceptance, ResultFilesRoundTripAndBadOnesAreRefused) {
  const auto m = default_volume_machine(2);
  const auto volume = acceptance::Volume::of(m);
  const auto setup = acceptance::example_setup(volume);
  acceptance::VirtualProbeOptions probe;
  probe.noise = 0.2e-3;
  probe.lobing = 0.5e-3;
  acceptance::E0Options o;
  o.mpe = ballgauge::Mpe::parse("2.5+L/250");
  o.r0 = ballgauge::Mpe::parse("1.5");
  const auto e0 = acceptance::run_e0(setup, volume, acceptance::virtual_touch(m, probe), o);
  const std::string path = test::temp_dir() + "/e0-back.json";
  io::write_e0_result(path, e0);
  const auto back = io::read_e0_result(path);
  ASSERT_EQ(back.lengths.size(), e0.lengths.size());
  EXPECT_EQ(back.verdict, e0.verdict);
  EXPECT_EQ(back.positions.size(), 7u);
  EXPECT_NEAR(back.e0_max, e0.e0_max, 1e-15);
  EXPECT_NEAR(back.r0_max, e0.r0_max, 1e-15);
  EXPECT_NEAR((back.lengths[40].b - e0.lengths[40].b).norm(), 0, 1e-12);
  ASSERT_TRUE(back.r0_pass);
  EXPECT_EQ(*back.r0_pass, *e0.r0_pass);
  const std::string text = test::read_file(path);
  auto tampered = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) t.replace(at, from.size(), to);
    return test::error_of([&] { io::read_e0_result(test::temp_file("bad-e0.json", t)); });
  };
  const std::string verdict = std::string("\"verdict\": \"") + acceptance::to_string(e0.verdict);
  EXPECT_NE(tampered(verdict, "\"verdict\": \"fine").find("bad-e0.json:"), std::string::npos);
  EXPECT_NE(tampered("\"error_um\": ", "\"error_um\": 1000 + ").find("bad-e0.json:"),
            std::string::npos);
  EXPECT_NE(tampered("\"E0_max_um\": ", "\"E0_max_um\": 1").find("E0_max_um is not"),
            std::string::npos);
  EXPECT_NE(tampered("\"acceptance-e0\"", "\"circular\"").find("acceptance-e0"), std::string::npos);
  // Fields missing or of the wrong type are named, never a crash (a fuzzer's finding: a missing
  // "complete" once escaped as a library exception).
  EXPECT_NE(tampered("\"complete\"", "\"finished\"").find("'complete' is missing"),
            std::string::npos);
  EXPECT_NE(tampered("\"space_diagonal\": true", "\"space_diagonal\": 1").find("true or false"),
            std::string::npos);
  // E150's stylus offset: a vector across the ram, or its length alone (along X).
  EXPECT_NE(
      tampered("\"mpe\"", "\"stylus_offset_mm\": [0, 0, 150], \"mpe\"").find("across the ram"),
      std::string::npos);
  EXPECT_NE(tampered("\"mpe\"", "\"stylus_offset_mm\": \"150\", \"mpe\"").find("bad-e0.json:"),
            std::string::npos);
  {
    std::string t = text;
    t.replace(t.find("\"mpe\""), 5, "\"stylus_offset_mm\": 150, \"mpe\"");
    const auto e150 = io::read_e0_result(test::temp_file("e150.json", t));
    ASSERT_TRUE(e150.stylus_offset);
    EXPECT_EQ(e150.name(), "E150");
  }
  // Probing.
  auto ps = setup;
  const auto probing = acceptance::run_probing(ps, acceptance::virtual_touch(m, probe), {});
  const std::string pp = test::temp_dir() + "/probing-back.json";
  io::write_probing_result(pp, probing);
  const auto pb = io::read_probing_result(pp);
  EXPECT_NEAR(pb.form, probing.form, 1e-15);
  EXPECT_EQ(pb.points.cols(), 25);
  EXPECT_FALSE(pb.form_verdict);
  std::string pt = test::read_file(pp);
  pt.replace(pt.find("\"PForm_um\": "), 12, "\"PForm_um\": 9");
  EXPECT_NE(test::error_of([&] {
              io::read_probing_result(test::temp_file("bad-p.json", pt));
            }).find("PForm_um is not the range"),
            std::string::npos);
}
