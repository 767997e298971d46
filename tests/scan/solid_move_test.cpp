// The part's rigid move in three dimensions from touched points against its solid
// (fit_solid_move), the part of it touch points in one plane tell without ambiguity
// (in_plane_part), and a section cut from the solid so moved (on_moved_solid), on the public
// DaimlerChrysler test part (tests/data/cad). Points are taken on the mesh's own triangles and
// moved by a known map, so the answers are known.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "../../src/scan/section.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/solid/mesh.hpp"

namespace trueaxis {
namespace {

const std::string kPart = std::string(TRUEAXIS_TEST_DATA) + "/cad/DaimlerChryslerTestPartAP214.stp";

// Points on the mesh: the move to the fit's convergence (Gauss–Newton on exact distances, the
// normals by differences 0.1 µm apart).
constexpr double kSameMove = 1e-5;  // mm, at the points
// A section cut from the moved solid lies on the moved mesh within its chord tolerance (the
// mesh is the faces' tessellation within 0.01 mm) and the cut's own.
constexpr double kOnMovedMesh = 0.011;  // mm
// The menu's acceptance: every touch point within this of the corrected design.
constexpr double kAccept = 0.05;  // mm

Eigen::Affine3d fixture_error() {
  Eigen::Affine3d m = Eigen::Affine3d::Identity();
  m.rotate(Eigen::AngleAxisd(0.3 * M_PI / 180, Eigen::Vector3d::UnitZ()));
  m.rotate(Eigen::AngleAxisd(0.1 * M_PI / 180, Eigen::Vector3d::UnitX()));
  m.pretranslate(Eigen::Vector3d(1.8, -1.1, 0.3));
  return m;
}

// The centroids of every k-th triangle: points on the solid's surface, spread over all of it.
Eigen::Matrix3Xd on_surface(const solid::Mesh& mesh, int count) {
  const Eigen::Index k = std::max<Eigen::Index>(1, mesh.triangles() / count);
  Eigen::Matrix3Xd p(3, mesh.triangles() / k);
  for (Eigen::Index i = 0; i < p.cols(); ++i) {
    const auto t = mesh.indices().col(i * k);
    p.col(i) =
        (mesh.vertices().col(t[0]) + mesh.vertices().col(t[1]) + mesh.vertices().col(t[2])) / 3;
  }
  return p;
}

TEST(SolidMove, FitsAKnownMoveOfTheSolidFromPointsOnIt) {
  const auto mesh = solid::load_step(kPart);
  const Eigen::Matrix3Xd p = on_surface(*mesh, 60);
  const Eigen::Affine3d truth = fixture_error();
  const Eigen::Matrix3Xd touched = truth * p;
  const auto c = scan::detail::fit_solid_move(*mesh, touched, kAccept, "test");
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->type, "solid-move");
  EXPECT_TRUE(c->accepted);
  EXPECT_GT(c->residual_before, kAccept);
  EXPECT_LT(c->residual_after, kSameMove);
  for (Eigen::Index i = 0; i < p.cols(); ++i)
    EXPECT_LT((c->transform * p.col(i) - touched.col(i)).norm(), kSameMove) << i;
  // The turn in words is the one applied (0.3° about z, 0.1° about x, as a rotation vector).
  double turn_z = NAN;
  for (const auto& [name, v] : c->parameters)
    if (name == "turn_z_deg") turn_z = v;
  EXPECT_NEAR(turn_z, 0.3, 1e-3);
}

TEST(SolidMove, AScaledPartIsNoMoveOfTheSolid) {
  const auto mesh = solid::load_step(kPart);
  const Eigen::Matrix3Xd p = on_surface(*mesh, 60);
  const Eigen::Vector3d c = mesh->box().center();
  // 1 % larger about its middle: 1 mm at 100 mm from it, which no rigid move takes up.
  const Eigen::Matrix3Xd touched = ((p.colwise() - c) * 1.01).colwise() + c;
  EXPECT_FALSE(scan::detail::fit_solid_move(*mesh, touched, kAccept, "test").has_value());
  // Too few points for any redundancy over six parameters: no move either.
  EXPECT_FALSE(scan::detail::fit_solid_move(*mesh, fixture_error() * p.leftCols(6), kAccept, "test")
                   .has_value());
}

TEST(SolidMove, InPlanePartIsTheSameForAMoveAndItsMirrorImage) {
  const design::Plane plane{Eigen::Vector3d(0, 0, 27), Eigen::Vector3d::UnitX()};
  const Eigen::Affine3d m = fixture_error();
  // The mirror image across the plane x = 0: S·M·S.
  Eigen::Affine3d s = Eigen::Affine3d::Identity();
  s.linear() = Eigen::Vector3d(-1, 1, 1).asDiagonal();
  const Eigen::Affine3d mirrored = s * m * s;
  const Eigen::Affine3d a = scan::detail::in_plane_part(m, plane),
                        b = scan::detail::in_plane_part(mirrored, plane);
  EXPECT_LT((a.matrix() - b.matrix()).norm(), 1e-12);
  // It keeps the plane: turns about its normal and moves in it only.
  design::Section on;
  on.plane = plane;
  EXPECT_TRUE(scan::detail::keeps_plane(on, a));
  // A move that keeps the plane is its own in-plane part.
  Eigen::Affine3d k = Eigen::Affine3d::Identity();
  k.rotate(Eigen::AngleAxisd(0.4 * M_PI / 180, Eigen::Vector3d::UnitX()));
  k.pretranslate(Eigen::Vector3d(0, 2.2, -1.0));
  EXPECT_LT((scan::detail::in_plane_part(k, plane).matrix() - k.matrix()).norm(), 1e-12);
}

TEST(SolidMove, SectionCutFromTheMovedSolid) {
  const design::Plane plane{Eigen::Vector3d(0, 0, 27), Eigen::Vector3d::UnitX()};
  const design::Design d = design::from_step(kPart, {{"x", plane}});
  const auto mesh = solid::load_step(kPart);
  const Eigen::Affine3d m = fixture_error();
  const solid::Mesh moved = mesh->transformed(m);
  for (const auto& s : d.sections) {
    // Unmoved: the section itself.
    const auto same = scan::detail::on_moved_solid(s, kPart, Eigen::Affine3d::Identity());
    ASSERT_TRUE(same.has_value()) << s.name;
    EXPECT_NEAR(design::length(*same), design::length(s), 1e-6) << s.name;
    // Moved: on the moved solid, where the move's part in the plane stands it.
    const auto cut = scan::detail::on_moved_solid(s, kPart, m);
    ASSERT_TRUE(cut.has_value()) << s.name;
    EXPECT_EQ(cut->name, s.name);
    EXPECT_EQ(cut->material, s.material);
    const auto smp = design::sample(*cut, 0.5);
    for (Eigen::Index i = 0; i < smp.points.cols(); ++i)
      EXPECT_LT(moved.distance(smp.points.col(i), 1.0), kOnMovedMesh) << s.name << " " << i;
    EXPECT_LT(
        (cut->solid_placement.matrix() - scan::detail::in_plane_part(m, plane).matrix()).norm(),
        1e-12);
  }
  // A stretch of a section: cut between where its ends moved to, in its direction.
  const auto& whole = d.sections.front();
  const double L = design::length(whole);
  const design::Section stretch = design::piece(whole, 0.2 * L, 0.5 * L, "stretch");
  const auto cut = scan::detail::on_moved_solid(stretch, kPart, m);
  ASSERT_TRUE(cut.has_value());
  EXPECT_FALSE(cut->closed);
  EXPECT_NEAR(design::length(*cut), design::length(stretch), 2.0);  // the move changes its shape
  const auto a = design::sample(stretch, 1.0), b = design::sample(*cut, 1.0);
  auto in_plane = [&](const Eigen::Vector3d& x) {
    const Eigen::Vector3d y = m * x;
    return Eigen::Vector3d(y - (y - plane.origin).dot(plane.normal) * plane.normal);
  };
  // Its ends where the stretch's moved to (within the part's move across the plane).
  EXPECT_LT((b.points.col(0) - in_plane(a.points.col(0))).norm(), 2.0);
  EXPECT_LT(
      (b.points.col(b.points.cols() - 1) - in_plane(a.points.col(a.points.cols() - 1))).norm(),
      2.0);
}

}  // namespace
}  // namespace trueaxis
