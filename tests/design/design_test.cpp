// Design data: STEP sections (NIST's I++ test part and solids built with OCCT here), design.json
// reading and its refusals, and the PCC scanning path (offset distance, chordal error, speeds).
#include "trueaxis/design/design.hpp"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRep_Tool.hxx>
#include <GeomAPI_ProjectPointOnCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <STEPControl_Writer.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <cmath>
#include <filesystem>
#include <gp_Pln.hxx>

#include "../../src/design/occt_api.hpp"
#include "../test_parts.hpp"
#include "../test_util.hpp"
#include "trueaxis/io/design/design.hpp"

namespace trueaxis {
namespace {

constexpr double kLengthTol = 1e-6;  // mm: OCCT's arc length of lines and exact arcs
constexpr double kOffsetTol = 1e-6;  // mm: OCCT's offset of lines and arcs is exact
const std::string kIpp = std::string(TRUEAXIS_TEST_DATA) + "/ippdme/ipp_simple.stp";
// ipp_simple's Ø50 mm hole is 25 mm deep, from the top face (z = 50) down to its floor at z = 25:
// the plane half-way down the hole cuts the block's outline and the hole.
constexpr double kHoleMid = 37.5;

design::Plane z_plane(double z) {
  return {Eigen::Vector3d(0, 0, z), Eigen::Vector3d::UnitZ()};
}

// Distance from p to the outline of an ipp_simple section below its top: the square [0,100]².
double dist_to_square(const Eigen::Vector3d& p) {
  const double dx = std::max({0.0 - p.x(), p.x() - 100, 0.0});
  const double dy = std::max({0.0 - p.y(), p.y() - 100, 0.0});
  if (dx > 0 || dy > 0) return std::hypot(dx, dy);
  return std::min({p.x(), 100 - p.x(), p.y(), 100 - p.y()});
}

TEST(Design, IppSimpleSectionIsFourLinesAndTheHole) {
  const auto d = design::from_step(kIpp, {{"mid", z_plane(kHoleMid)}});
  ASSERT_EQ(d.sections.size(), 2u);
  const auto& outer = d.sections[0];
  const auto& hole = d.sections[1];
  EXPECT_EQ(outer.name, "mid.1");
  EXPECT_EQ(hole.name, "mid.2");
  EXPECT_NEAR(design::length(outer), 400, kLengthTol);
  EXPECT_NEAR(design::length(hole), 50 * M_PI, kLengthTol);
  EXPECT_NEAR(design::length(outer) + design::length(hole), 557.08, 0.005);
  EXPECT_TRUE(outer.closed);
  EXPECT_TRUE(hole.closed);
  EXPECT_FALSE(design::check(outer));
  EXPECT_FALSE(design::check(hole));
  // Counter-clockwise seen from +z: the block's material is inside the outer contour (left) and
  // outside the hole (right).
  EXPECT_EQ(outer.material, design::Side::Left);
  EXPECT_EQ(hole.material, design::Side::Right);
  // Surface normals point away from the material: out of the block, into the hole's axis.
  const auto so = design::sample(outer, 5);
  for (Eigen::Index i = 0; i < so.points.cols(); ++i) {
    EXPECT_NEAR(dist_to_square(so.points.col(i)), 0, 1e-9);
    EXPECT_NEAR(so.points(2, i), kHoleMid, 1e-12);
    const Eigen::Vector3d out = so.points.col(i) + 0.5 * so.normals.col(i);
    EXPECT_TRUE(out.x() < 0 || out.x() > 100 || out.y() < 0 || out.y() > 100) << i;
  }
  const auto sh = design::sample(hole, 5);
  for (Eigen::Index i = 0; i < sh.points.cols(); ++i) {
    const Eigen::Vector3d r = sh.points.col(i) - Eigen::Vector3d(50, 50, kHoleMid);
    EXPECT_NEAR(r.norm(), 25, 1e-9);
    EXPECT_NEAR(sh.normals.col(i).dot(r / 25), -1, 1e-9);
  }
}

TEST(Design, ObliqueSectionOfTheIppPart) {
  // A plane tilted 20° about x through the block's centre: the outer contour is a
  // 100 × 100/cos20 rectangle, the hole an ellipse.
  const double tilt = 20 * M_PI / 180;
  const Eigen::Vector3d n(0, -std::sin(tilt), std::cos(tilt));
  const auto d = design::from_step(kIpp, {{"tilt", {Eigen::Vector3d(50, 50, 25), n}}});
  ASSERT_EQ(d.sections.size(), 2u);
  EXPECT_NEAR(design::length(d.sections[0]), 200 + 200 / std::cos(tilt), 1e-6);
  for (const auto& s : d.sections) {
    const auto smp = design::sample(s, 2);
    for (Eigen::Index i = 0; i < smp.points.cols(); ++i) {
      EXPECT_NEAR((smp.points.col(i) - Eigen::Vector3d(50, 50, 25)).dot(n), 0, 1e-7);
      EXPECT_NEAR(smp.normals.col(i).dot(n), 0, 1e-9);
    }
  }
}

TEST(Design, StepRefusals) {
  EXPECT_NE(test::error_of([] {
              design::from_step("/nonexistent.stp", {{"a", z_plane(25)}});
            }).find("cannot open"),
            std::string::npos);
  const std::string junk = test::temp_file("junk.stp", "hello\n");
  EXPECT_NE(test::error_of([&] {
              design::from_step(junk, {{"a", z_plane(25)}});
            }).find(junk + ":1:1: not a STEP file"),
            std::string::npos);
  EXPECT_NE(test::error_of([] {
              design::from_step(kIpp, {{"above", z_plane(80)}});
            }).find("misses the part"),
            std::string::npos);
  // A valid STEP file with a surface but no solid: no material side to know.
  const std::string face = test::temp_dir() + "/face.stp";
  STEPControl_Writer w;
  ASSERT_EQ(w.Transfer(BRepBuilderAPI_MakeFace(gp_Pln(), 0, 10, 0, 10).Face(), STEPControl_AsIs),
            IFSelect_RetDone);
  ASSERT_EQ(w.Write(face.c_str()), IFSelect_RetDone);
  EXPECT_NE(test::error_of([&] {
              design::from_step(face, {{"a", z_plane(0)}});
            }).find(face + ": the STEP file holds no solid"),
            std::string::npos);
}

// Each plane succeeds or fails on its own, and a refusal says what is the case: a plane on the
// hole's floor keeps the outline and refuses the hole's contour (it runs along the floor, where a
// ball would touch the floor too); a plane on the top face has nothing to scan; a plane beside
// the part misses it, by how much.
TEST(Design, EveryPlaneOnItsOwnWithTheTrueReason) {
  const auto cut =
      design::cut_step(kIpp, {{"floor", z_plane(25)},
                              {"top", z_plane(50)},
                              {"above", z_plane(80)},
                              {"mid", z_plane(kHoleMid)},
                              {"zero", {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}}});
  EXPECT_EQ(cut.solids, 1);
  // The file states 1e-8 mm; edges are joined across at least 1e-4 mm.
  ASSERT_TRUE(cut.file_tolerance);
  EXPECT_NEAR(*cut.file_tolerance, 1e-8, 1e-20);
  EXPECT_DOUBLE_EQ(cut.join_tolerance, design::StepCutOptions{}.min_join);
  std::vector<std::string> names;
  for (const auto& s : cut.design.sections) names.push_back(s.name);
  EXPECT_EQ(names, (std::vector<std::string>{"floor", "mid.1", "mid.2"}));
  EXPECT_NEAR(design::length(cut.design.sections[0]), 400, kLengthTol);
  ASSERT_EQ(cut.failures.size(), 4u);
  EXPECT_EQ(cut.failures[0].name, "floor");
  EXPECT_NE(cut.failures[0].reason.find("runs along the edge of a flat face"), std::string::npos)
      << cut.failures[0].reason;
  EXPECT_NE(cut.failures[0].reason.find("(50.000, 50.000, 25.000)"), std::string::npos);
  EXPECT_EQ(cut.failures[1].name, "top");
  EXPECT_NE(cut.failures[1].reason.find("the plane lies on flat faces"), std::string::npos)
      << cut.failures[1].reason;
  EXPECT_EQ(cut.failures[2].name, "above");
  EXPECT_NE(cut.failures[2].reason.find("misses the part: the part lies -80.000 to -30.000 mm"),
            std::string::npos)
      << cut.failures[2].reason;
  EXPECT_NE(cut.failures[3].reason.find("normal is zero"), std::string::npos);
  EXPECT_FALSE(cut.ok());
  // from_step throws at the first failure, naming the file and the plane.
  EXPECT_NE(test::error_of([] {
              design::from_step(kIpp, {{"floor", z_plane(25)}});
            }).find("ipp_simple.stp: section 'floor': a contour of 157.1 mm"),
            std::string::npos);
  EXPECT_NE(test::error_of([] {
              design::StepCutOptions o;
              o.min_join = 1;
              o.max_join = 0.1;
              design::cut_step(kIpp, {}, o);
            }).find("join tolerances"),
            std::string::npos);
}

// The Open CASCADE part of the library is opened on first use; a missing library, or one without
// its entry point, is an Error that names it (never a crash or a call into the unknown).
TEST(Design, CadLibraryIsOpenedAndOthersRefused) {
  const auto& api = design::detail::load_occt_api(design::detail::kOcctLibrary);
  ASSERT_NE(api.tag, nullptr);
  EXPECT_EQ(std::string(api.tag), design::detail::occt_api_tag());
  EXPECT_TRUE(api.nurbs_ends && api.nurbs_length && api.nurbs_sample && api.plane_path &&
              api.cut_step);
  const std::string missing =
      test::error_of([] { design::detail::load_occt_api("/nonexistent/libtrueaxis_occt.so"); });
  EXPECT_NE(missing.find("cannot load /nonexistent/libtrueaxis_occt.so"), std::string::npos)
      << missing;
  EXPECT_NE(missing.find("installed completely"), std::string::npos) << missing;
  const std::string foreign = test::error_of([] { design::detail::load_occt_api("libm.so.6"); });
  EXPECT_NE(foreign.find("libm.so.6 is from another build of trueaxis"), std::string::npos)
      << foreign;
}

TEST(Design, PathAroundTheIppSectionKeepsTheOffset) {
  const auto d = design::from_step(kIpp, {{"mid", z_plane(kHoleMid)}});
  design::PathOptions o;
  o.tip_radius = 2;
  o.pushing = 0.3;
  o.chordal_tolerance = 1e-4;
  const double off = o.tip_radius - o.pushing;
  const auto outer = design::make_path(d.sections[0], o);
  const auto hole = design::make_path(d.sections[1], o);
  EXPECT_DOUBLE_EQ(outer.offset, off);
  // Around the outside: four sides and a quarter circle of radius `off` at each corner. Cubics
  // within the chordal tolerance t of a full circle of radius R differ in length by less than
  // 2πR·t/R = 2πt.
  const double length_tol = 2 * M_PI * o.chordal_tolerance;
  EXPECT_NEAR(outer.length(), 400 + 2 * M_PI * off, length_tol);
  EXPECT_NEAR(hole.length(), 2 * M_PI * (25 - off), length_tol);
  EXPECT_LE(outer.chordal_error, o.chordal_tolerance);
  EXPECT_LE(hole.chordal_error, o.chordal_tolerance);
  for (const auto& seg : outer.segments)
    for (double u : {0.0, 0.3, 0.7, 1.0})
      EXPECT_NEAR(dist_to_square(seg.point(u)), off, o.chordal_tolerance + kOffsetTol);
  for (const auto& seg : hole.segments)
    for (double u : {0.0, 0.5})
      EXPECT_NEAR((seg.point(u) - Eigen::Vector3d(50, 50, kHoleMid)).norm(), 25 - off,
                  o.chordal_tolerance + kOffsetTol);
  // The path is continuous, closed, starts beside the design curve's start and runs its way.
  for (std::size_t i = 0; i + 1 < outer.segments.size(); ++i)
    EXPECT_LT((outer.segments[i].point(1) - outer.segments[i + 1].point(0)).norm(), 1e-9);
  EXPECT_LT((outer.segments.back().point(1) - outer.segments.front().point(0)).norm(), 1e-9);
  const auto s0 = design::sample(d.sections[0], 1);
  EXPECT_LT((outer.segments.front().point(0) - (s0.points.col(0) + off * s0.normals.col(0))).norm(),
            1e-6);
  const Eigen::Vector3d t_design = s0.points.col(1) - s0.points.col(0);
  EXPECT_GT(outer.segments.front().tangent(0).dot(t_design), 0);
  // Speeds: full speed on the sides, slower round the tight corner arcs: v²/R within the limit
  // for the arc through the corner's tangents that cuts it by a third of the pushing amount,
  // R = off + δ/(1/cos 45° − 1).
  const double R = off + (o.pushing / 3) / (std::sqrt(2.0) - 1);
  double vmin = 1e9, vmax = 0;
  for (const auto& seg : outer.segments) {
    vmin = std::min(vmin, seg.speed);
    vmax = std::max(vmax, seg.speed);
    EXPECT_LE(seg.speed * seg.speed * seg.curvature,
              o.max_normal_acceleration * R / off * (1 + 1e-9));
  }
  EXPECT_DOUBLE_EQ(vmax, o.max_speed);
  EXPECT_NEAR(vmin, std::sqrt(o.max_normal_acceleration * R), 1e-6);
  EXPECT_GT(outer.nominal_time(), outer.length() / o.max_speed);
}

// A measured contour: a wall, a concave 90° fillet of radius 1 mm given as 9 chords of 10°, and
// another wall (material on the left, the ball inside the turn). Each 10° turn of the path is
// harmless alone, but together they turn the ball through 90° within a millimetre: the corner
// speeds keep v²/R within the limit for the radius the turns fit on (once the path ran through
// at 100 mm/s and the probe over-travelled there).
TEST(Design, ConcaveFilletOfShortChordsIsTakenAtTheSpeedOfItsRadius) {
  design::Section s;
  s.name = "fillet";
  s.closed = false;
  s.plane = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()};
  s.material = design::Side::Left;
  std::vector<Eigen::Vector3d> pts{{20, 0, 0}};
  // Travelling in -x along y = 0 (material at y < 0, on the left), then up x = 0 in +y.
  for (int k = 0; k <= 9; ++k) {
    const double a = -M_PI / 2 - k * M_PI / 18;  // about (1, 1): from (1, 0) to (0, 1)
    pts.emplace_back(1 + std::cos(a), 1 + std::sin(a), 0);
  }
  pts.emplace_back(0, 20, 0);
  s.polyline.resize(3, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t i = 0; i < pts.size(); ++i)
    s.polyline.col(static_cast<Eigen::Index>(i)) = pts[i];
  design::PathOptions o;
  const auto path = design::make_path(s, o);
  double slowest = INFINITY;
  for (const auto& g : path.segments) slowest = std::min({slowest, g.speed, g.corner_speed});
  // The offset of a 1 mm concave fillet by 0.7 mm turns on a radius of about 0.3 mm.
  EXPECT_LT(slowest, std::sqrt(o.max_normal_acceleration * 0.5));
  EXPECT_GE(slowest, o.min_speed);
}

// A rounded rectangle (120 × 80 mm, corners of radius 10 mm) given as a polyline, its fillets in
// chords of 3° (a design exported as points, or one overwritten with a measured contour). The
// ball rolls round each chord's end on an arc of 0.7 mm, but all of them together turn it on the
// fillet's radius: the path runs round the fillets at the speed of that radius, not at that of
// 0.7 mm (26 mm/s).
TEST(Design, ConvexFilletOfShortChordsIsTakenAtTheSpeedOfItsRadius) {
  design::Section s;
  s.name = "rounded";
  s.closed = true;
  s.plane = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()};
  s.material = design::Side::Left;  // counter-clockwise round the material
  std::vector<Eigen::Vector3d> pts;
  const double r = 10;
  const Eigen::Vector2d centres[4] = {{50, -30}, {50, 30}, {-50, 30}, {-50, -30}};
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k <= 30; ++k) {
      const double a = -M_PI / 2 + c * M_PI / 2 + k * M_PI / 60;
      pts.emplace_back(centres[c].x() + r * std::cos(a), centres[c].y() + r * std::sin(a), 0);
    }
  pts.push_back(pts.front());
  s.polyline.resize(3, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t i = 0; i < pts.size(); ++i)
    s.polyline.col(static_cast<Eigen::Index>(i)) = pts[i];
  design::PathOptions o;
  const auto path = design::make_path(s, o);
  // The chords' ends turn the path by 3°; the widest arc through their tangents that fits on
  // half of the 0.52 mm chords beside it has a radius of about 10 mm, so v = √(a·R) ≈ 100 mm/s.
  const double chord = 2 * r * std::sin(M_PI / 120);
  const double R = o.tip_radius - o.pushing + 0.5 * chord / std::tan(M_PI / 120);
  const double expected = std::min(o.max_speed, std::sqrt(o.max_normal_acceleration * R));
  double slowest = INFINITY;
  for (const auto& g : path.segments) slowest = std::min({slowest, g.speed, g.corner_speed});
  EXPECT_NEAR(slowest, expected, 1e-6 * expected);
  EXPECT_GT(slowest, 3 * std::sqrt(o.max_normal_acceleration * (o.tip_radius - o.pushing)));
}

// A 50-edge star polygon (concave corners trimmed, convex ones rounded) and an open polyline.
TEST(Design, PolylinePathsStayAtTheOffsetOnTheFreeSide) {
  design::Section s;
  s.name = "star";
  s.polyline.resize(3, 51);
  for (int i = 0; i <= 50; ++i) {
    const double a = 2 * M_PI * (i % 50) / 50, r = (i % 2) ? 40 : 50;
    s.polyline.col(i) << r * std::cos(a), r * std::sin(a), 0;
  }
  s.closed = true;
  s.material = design::Side::Left;
  auto dist = [&](const Eigen::Vector3d& p) {
    double best = 1e9;
    for (Eigen::Index i = 0; i + 1 < s.polyline.cols(); ++i) {
      const Eigen::Vector3d a = s.polyline.col(i), b = s.polyline.col(i + 1);
      const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      best = std::min(best, (a + t * (b - a) - p).norm());
    }
    return best;
  };
  design::PathOptions o;
  const double off = o.tip_radius - o.pushing;
  const auto path = design::make_path(s, o);
  EXPECT_LE(path.chordal_error, o.chordal_tolerance);
  for (const auto& seg : path.segments)
    for (double u : {0.0, 0.5}) {
      EXPECT_NEAR(dist(seg.point(u)), off, o.chordal_tolerance + kOffsetTol);
      EXPECT_GT(seg.point(u).head<2>().norm(), 40 * std::cos(M_PI / 50) - 1e-9);  // outside
    }

  // Open: an L, material on the right; the path must lie on its left.
  design::Section l;
  l.name = "L";
  l.closed = false;
  l.material = design::Side::Right;
  l.polyline.resize(3, 3);
  l.polyline << 0, 50, 50, 0, 0, 50, 0, 0, 0;
  const auto lp = design::make_path(l, o);
  for (const auto& seg : lp.segments) {
    const Eigen::Vector3d p = seg.point(0.5);
    EXPECT_TRUE(p.y() > 0 && p.x() < 50 + 1e-9) << p.transpose();
  }
  EXPECT_NEAR(lp.length(), 100 - 2 * off, 1e-6);  // the inner corner is trimmed
  // A straight open line, too (OCCT cannot find its plane by itself).
  design::Section line = l;
  line.polyline = l.polyline.leftCols(2);
  const auto linep = design::make_path(line, o);
  EXPECT_NEAR(linep.length(), 50, 1e-9);
  EXPECT_NEAR(linep.segments.front().point(0).y(), off, 1e-9);
}

// A measured contour (what an autonomous scan writes over a section): the square sampled every
// 0.6 mm with a smooth sub-micrometre ripple, as a CMM's geometric errors leave on it. Its
// nearly collinear points must not stop the offset; the path keeps the offset from the points.
TEST(Design, MeasuredPolylineWithNanometreRippleGetsAPath) {
  for (double ripple : {1e-6, 1e-5, 1e-4, 1e-3}) {  // mm
    std::vector<Eigen::Vector3d> pts;
    const Eigen::Vector2d c[] = {{0, 0}, {100, 0}, {100, 100}, {0, 100}};
    for (int e = 0; e < 4; ++e)
      for (int k = 0; k < 167; ++k) {
        const Eigen::Vector2d a = c[e], b = c[(e + 1) % 4];
        const Eigen::Vector2d dir = (b - a) / 100, left(-dir.y(), dir.x());
        const double u = 100.0 * k / 167;
        const Eigen::Vector2d q = a + u * dir + ripple * std::sin(u / 7.0) * left;
        pts.emplace_back(q.x(), q.y(), 25);
      }
    design::Section s;
    s.name = "measured";
    s.plane = z_plane(25);
    s.closed = true;
    s.material = design::Side::Left;
    s.polyline.resize(3, static_cast<Eigen::Index>(pts.size() + 1));
    for (std::size_t i = 0; i <= pts.size(); ++i)
      s.polyline.col(static_cast<Eigen::Index>(i)) = pts[i % pts.size()];
    design::PathOptions o;
    const double off = o.tip_radius - o.pushing;
    const auto path = design::make_path(s, o);
    EXPECT_NEAR(path.length(), 400 + 2 * M_PI * off, 0.01) << ripple;
    for (const auto& seg : path.segments)
      EXPECT_NEAR(dist_to_square(seg.point(0.5)), off, ripple + o.chordal_tolerance) << ripple;
  }
}

// A measured contour with a slit far narrower than the tip (a notch of the real part, or a drill
// point's bottom cut off the axis): the offsets of the slit's flanks land in the material beyond
// it, clear of the curve, and once stopped the whole path ("the path breaks off ... the tip does
// not fit"), though the tip only has to pass over the slit's mouth. Now the path keeps the offset
// from the curve, stays out of the material, and crosses the mouth straight.
TEST(Design, ASlitNarrowerThanTheTipIsPassedOver) {
  for (double width : {0.001, 0.01, 0.2, 1.0})  // mm, into the square's bottom side
    for (double depth : {0.3, 1.5, 3.0}) {
      SCOPED_TRACE(testing::Message() << "width " << width << " depth " << depth);
      design::Section s;
      s.name = "slit";
      s.plane = z_plane(0);
      s.closed = true;
      s.material = design::Side::Left;
      s.polyline.resize(3, 8);
      s.polyline << 0, 50 - width / 2, 50, 50 + width / 2, 100, 100, 0, 0,  //
          0, 0, depth, 0, 0, 60, 60, 0,                                     //
          0, 0, 0, 0, 0, 0, 0, 0;
      design::PathOptions o;
      const double off = o.tip_radius - o.pushing;
      design::ScanPath path;
      ASSERT_NO_THROW(path = design::make_path(s, o));
      for (const auto& seg : path.segments)
        for (double t : {0.0, 0.25, 0.5, 0.75, 1.0}) {
          const Eigen::Vector3d p = seg.point(t);
          double near = 1e300;  // from the polyline's sides
          for (Eigen::Index i = 0; i + 1 < s.polyline.cols(); ++i) {
            const Eigen::Vector3d a = s.polyline.col(i), d = s.polyline.col(i + 1) - a;
            const double u = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
            near = std::min(near, (a + u * d - p).norm());
          }
          EXPECT_GT(near, off - o.chordal_tolerance) << p.transpose();
          // Out of the material: below the bottom side, beside or above the square.
          EXPECT_TRUE(p.y() < 0 || p.x() < 0 || p.x() > 100 || p.y() > 60) << p.transpose();
        }
    }
}

// A solid bounded by B-spline surfaces, built here with OCCT, exported to STEP and sectioned.
TEST(Design, BsplineSolidFromStep) {
  const std::string path = test::temp_dir() + "/lobed.stp";
  const TopoDS_Shape nurbs = test::write_lobed_solid(path);
  const Handle(Geom_BSplineCurve) profile = test::lobed_profile();
  int bspline_faces = 0;
  for (TopExp_Explorer x(nurbs, TopAbs_FACE); x.More(); x.Next())
    bspline_faces +=
        !Handle(Geom_BSplineSurface)::DownCast(BRep_Tool::Surface(TopoDS::Face(x.Current())))
             .IsNull();
  ASSERT_GE(bspline_faces, 1);

  const auto d = design::from_step(path, {{"z10", z_plane(10)}});
  ASSERT_EQ(d.sections.size(), 1u);
  const auto& s = d.sections[0];
  EXPECT_EQ(s.material, design::Side::Left);
  // The cut matches the profile curve: every sample within OCCT's section tolerance of it.
  const auto smp = design::sample(s, 1);
  for (Eigen::Index i = 0; i < smp.points.cols(); ++i) {
    GeomAPI_ProjectPointOnCurve pr(gp_Pnt(smp.points(0, i), smp.points(1, i), 0), profile);
    ASSERT_GT(pr.NbPoints(), 0);
    EXPECT_LT(pr.LowerDistance(), 1e-4);
    EXPECT_NEAR(smp.points(2, i), 10, 1e-9);
  }
  const auto p = design::make_path(s);
  EXPECT_LE(p.chordal_error, design::PathOptions{}.chordal_tolerance);
  EXPECT_GT(p.length(), design::length(s));  // outside a convex-ish part: longer
}

TEST(Design, JsonRoundTripAndOptionRefusals) {
  auto d = design::from_step(kIpp, {{"mid", z_plane(kHoleMid)}});
  // What a scan writes back: the solid where the corrected curve says the part stands, and a
  // probe orientation.
  d.sections[0].solid_placement =
      Eigen::Translation3d(1.8, -1.1, 0) * Eigen::AngleAxisd(0.005, Eigen::Vector3d::UnitZ());
  d.sections[1].probe = {30, -90};
  const std::string path = test::temp_dir() + "/design.json";
  io::write_design(path, d);
  const auto back = io::read_design(path);
  ASSERT_EQ(back.sections.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back.sections[i].name, d.sections[i].name);
    EXPECT_EQ(back.sections[i].material, d.sections[i].material);
    EXPECT_NEAR(design::length(back.sections[i]), design::length(d.sections[i]), 1e-12);
    EXPECT_TRUE(back.sections[i].solid_placement.isApprox(d.sections[i].solid_placement, 1e-15));
    EXPECT_EQ(back.sections[i].probe.a_deg, d.sections[i].probe.a_deg);
    EXPECT_EQ(back.sections[i].probe.b_deg, d.sections[i].probe.b_deg);
  }
  EXPECT_EQ(std::filesystem::path(back.solid).filename(), "ipp_simple.stp");
  EXPECT_TRUE(std::filesystem::exists(back.solid)) << back.solid;
  design::PathOptions o;
  o.pushing = 2;
  EXPECT_NE(test::error_of([&] { o.validate(); }).find("less than the tip radius"),
            std::string::npos);
  o = {};
  o.chordal_tolerance = 0;
  EXPECT_NE(test::error_of([&] { o.validate(); }).find("chordal tolerance"), std::string::npos);
  // A tip that does not fit the hole.
  o = {};
  o.tip_radius = 30;
  EXPECT_NE(test::error_of([&] { design::make_path(d.sections[1], o); }).find("does not fit"),
            std::string::npos);
}

// Every refusal names file:line:col of the offending value.
TEST(Design, ReaderRefusesBadDesignsWithTheirPlace) {
  auto err = [](const std::string& curve, const std::string& extra = "",
                const std::string& normal = "[0, 0, 1]") {
    const std::string text =
        "{\"sections\": [{\"name\": \"s\", \"plane\": {\"origin\": [0, 0, 0],"
        " \"normal\": " +
        normal + "}, \"closed\": " + (extra.empty() ? "false" : extra) + ",\n \"curve\": " + curve +
        ",\n \"material\": \"left\"}]}";
    return test::error_of([&] { io::parse_design(text, "d.json"); });
  };
  const std::string ok =
      R"({"nurbs": {"degree": 2, "knots": [0, 0, 0, 1, 1, 1], "weights": [1, 0.7, 1],
          "control_points": [[0, 0, 0], [1, 1, 0], [2, 0, 0]]}})";
  EXPECT_EQ(err(ok), "(no error)");
  // Knots that decrease: the place of the offending knot.
  const std::string e1 = err(
      R"({"nurbs": {"degree": 2, "knots": [0, 0, 0, 1, 0.5, 1], "weights": [1, 1, 1],
          "control_points": [[0, 0, 0], [1, 1, 0], [2, 0, 0]]}})");
  EXPECT_NE(e1.find("d.json:2:57: section 's': knots must not decrease"), std::string::npos) << e1;
  const std::string e2 = err(
      R"({"nurbs": {"degree": 2, "knots": [0, 0, 0, 1, 1, 1], "weights": [1, 0, 1],
          "control_points": [[0, 0, 0], [1, 1, 0], [2, 0, 0]]}})");
  EXPECT_NE(e2.find("d.json:2:79: section 's': weights must be positive"), std::string::npos) << e2;
  const std::string e3 = err(
      R"({"nurbs": {"degree": 3, "knots": [0, 0, 0, 1, 1, 1], "weights": [1, 1, 1],
          "control_points": [[0, 0, 0], [1, 1, 0], [2, 0, 0]]}})");
  EXPECT_NE(e3.find("3 control points are too few for degree 3"), std::string::npos) << e3;
  const std::string e4 = err(
      R"({"nurbs": {"degree": 2, "knots": [0, 0, 0, 1, 1], "weights": [1, 1, 1],
          "control_points": [[0, 0, 0], [1, 1, 0], [2, 0, 0]]}})");
  EXPECT_NE(e4.find("5 knots; a degree-2 curve with 3 control points needs 6"), std::string::npos)
      << e4;
  // Non-planar point: its place in the list.
  const std::string e5 = err(R"({"polyline": [[0, 0, 0], [1, 0, 0], [1, 1, 0.5]]})");
  EXPECT_NE(e5.find("d.json:2:47: section 's': the point is 0.5 mm off the section plane"),
            std::string::npos)
      << e5;
  // An open curve marked closed.
  const std::string e6 = err(R"({"polyline": [[0, 0, 0], [1, 0, 0], [1, 1, 0]]})", "true");
  EXPECT_NE(e6.find("d.json:1:92: section 's': the curve is marked closed but ends 1.414 mm"),
            std::string::npos)
      << e6;
  EXPECT_NE(err(R"({"polyline": [[0, 0, 0]]})").find("a polyline needs at least 2"),
            std::string::npos);
  EXPECT_NE(err(R"({"polyline": [[0, 0, 0], [0, 0, 0]]})").find("repeats the one before"),
            std::string::npos);
  EXPECT_NE(err(R"({"polyline": [[0, 0, 0], [1, 0, 0]]})", "", "[0, 0, 0]").find("no direction"),
            std::string::npos);
  EXPECT_NE(err(R"({"spline": []})").find("unknown key 'spline'"), std::string::npos);
  EXPECT_NE(err(R"({})").find("exactly one of"), std::string::npos);
  EXPECT_NE(err(R"({"polyline": [[0, 0, 1e309], [1, 0, 0]]})").find("d.json:2:"),
            std::string::npos);
  EXPECT_NE(err(R"({"polyline": [[0, 0], [1, 0, 0]]})").find("needs [x, y, z (mm)]"),
            std::string::npos);
  EXPECT_NE(
      test::error_of([] { io::parse_design(R"({"sections": []})", "d.json"); }).find("no sections"),
      std::string::npos);
  // A placement that mirrors the solid, one of the wrong shape, a head angle beyond the head.
  auto with = [](const std::string& key) {
    return test::error_of([&] {
      io::parse_design(R"({"sections": [{"name": "s", "plane": {"origin": [0, 0, 0], "normal": )"
                       R"([0, 0, 1]}, "closed": false, "curve": {"polyline": [[0, 0, 0], )"
                       R"([1, 0, 0]]}, "material": "left",)"
                       "\n" +
                           key + "}]}",
                       "d.json");
    });
  };
  EXPECT_EQ(with(R"("solid_placement": [[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0]])"), "(no error)");
  const std::string m = with(R"("solid_placement": [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]])");
  EXPECT_NE(m.find("d.json:2:20: the placement's 3 × 3 part has determinant -1"), std::string::npos)
      << m;
  EXPECT_NE(with(R"("solid_placement": [[1, 0, 0], [0, 1, 0], [0, 0, 1]])").find("four numbers"),
            std::string::npos);
  EXPECT_NE(with(R"("solid_placement": [1, 0, 0, 0])").find("three rows"), std::string::npos);
  const std::string h = with(R"("probe": {"a_deg": 120, "b_deg": 0})");
  EXPECT_NE(h.find("d.json:2:10: section 's': the probe head cannot take"), std::string::npos) << h;
  EXPECT_NE(with(R"("probe": {"a": 10})").find("unknown key 'a'"), std::string::npos);
  EXPECT_NE(
      test::error_of([] { io::read_design("/nonexistent/design.json"); }).find("no such file"),
      std::string::npos);
}

}  // namespace
}  // namespace trueaxis

namespace trueaxis {
namespace {

// Space curves: a spiral over a sphere fails the 2-D test with how far it leaves its plane; an
// oblique circle given as a space curve passes it and becomes that plane section; the path
// runs along the surface normals; design.json carries the normals and refuses bad ones.
TEST(Design, SpaceCurvesThePlaneTestPathsAndTheirFile) {
  const auto spiral = test::spiral_on_sphere();
  EXPECT_FALSE(design::check(spiral));
  std::string why;
  EXPECT_FALSE(design::as_plane_section(spiral, &why));
  EXPECT_NE(why.find("the path is three-dimensional: its points leave their best-fit plane by"),
            std::string::npos)
      << why;

  const auto circle = test::oblique_circle();
  const auto plane = design::as_plane_section(circle);
  ASSERT_TRUE(plane);
  EXPECT_FALSE(plane->space_curve());
  const Eigen::Vector3d tilted =
      Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitX()) * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(std::abs(plane->plane.normal.dot(tilted)), 1, 1e-12);
  // Its outward normals point out of the circle: the material is inside.
  const auto smp = design::sample(*plane, 1.0);
  for (Eigen::Index i = 0; i < smp.points.cols(); ++i)
    EXPECT_GT(smp.normals.col(i).dot(smp.points.col(i) - Eigen::Vector3d(50, 50, 25)), 29.9);

  // The path: each point at the offset along its normal, on the sphere of radius R + d.
  design::PathOptions o;
  const double off = o.tip_radius - o.pushing;
  const auto path = design::make_path(spiral, o);
  EXPECT_TRUE(path.space());
  EXPECT_EQ(path.segments.size() + 1, static_cast<std::size_t>(spiral.polyline.cols()));
  for (double s = 0; s < path.length(); s += 7.3) {
    const auto p = path.at(s);
    const Eigen::Vector3d radial = (p.p - Eigen::Vector3d(50, 50, 0)).normalized();
    EXPECT_NEAR((p.p - Eigen::Vector3d(50, 50, 0)).norm(), 50 + off, 2e-3) << s;  // chord sag
    EXPECT_NEAR(p.normal.dot(radial), 1, 1e-6) << s;
    EXPECT_NEAR(p.tangent.dot(p.normal), 0, 1e-2) << s;
  }
  for (const auto& g : path.segments) EXPECT_LE(g.speed, o.max_speed);

  // design.json: written and read back, normals and all; bad normals refused at their place.
  design::Design d;
  d.sections.push_back(spiral);
  const std::string file = ::testing::TempDir() + "spiral.json";
  io::write_design(file, d);
  const auto back = io::read_design(file);
  ASSERT_TRUE(back.sections[0].space_curve());
  EXPECT_TRUE(back.sections[0].normals.isApprox(spiral.normals, 1e-12));
  auto err = [](const std::string& section) {
    return test::error_of([&] { io::parse_design("{\"sections\": [" + section + "]}", "s.json"); });
  };
  const std::string pts = R"("curve": {"polyline": [[0, 0, 0], [1, 0, 1], [2, 1, 1]]})";
  EXPECT_EQ(err(R"({"name": "a", "closed": false, )" + pts +
                R"(, "normals": [[0, 0, 1], [0, 0, 1], [0, 1, 0]]})"),
            "(no error)");
  EXPECT_NE(
      err(R"({"name": "a", "closed": false, )" + pts + R"(, "normals": [[0, 0, 1], [0, 0, 1]]})")
          .find("2 normals for 3 points"),
      std::string::npos);
  const std::string zero = err(R"({"name": "a", "closed": false, )" + pts +
                               R"(, "normals": [[0, 0, 1], [0, 0, 0], [0, 1, 0]]})");
  EXPECT_NE(zero.find("s.json:1:127: section 'a': the surface normal has no direction"),
            std::string::npos)
      << zero;
  EXPECT_NE(err(R"({"name": "a", "closed": false, "material": "left", )" + pts +
                R"(, "normals": [[0, 0, 1], [0, 0, 1], [0, 1, 0]]})")
                .find("a space curve (with 'normals') has no 'material'"),
            std::string::npos);
  const std::string noplane = err(R"({"name": "a", "closed": false, )" + pts + "}");
  EXPECT_NE(noplane.find("plane' is missing"), std::string::npos) << noplane;
}

}  // namespace
}  // namespace trueaxis
