// The part as a mesh: clearance of points and segments against a hand-made cube (exact answers)
// and a real part's tessellation (against a search of every triangle, and its known shape).
#include "trueaxis/solid/mesh.hpp"

#include <random>

#include "../test_util.hpp"

namespace trueaxis {
namespace {

constexpr double kExact = 1e-12;  // mm: the cube's distances are exact in double precision
const std::string kIpp = std::string(TRUEAXIS_TEST_DATA) + "/ippdme/ipp_simple.stp";

// The cube [0, 10]³ as 12 triangles facing out, one face id per side.
solid::Mesh cube() {
  Eigen::Matrix3Xd v(3, 8);
  for (int i = 0; i < 8; ++i) v.col(i) << 10.0 * (i & 1), 10.0 * ((i >> 1) & 1), 10.0 * (i >> 2);
  Eigen::Matrix3Xi t(3, 12);
  t << 0, 0, 4, 4, 0, 0, 2, 2, 0, 0, 1, 1,  //
      2, 3, 5, 7, 1, 5, 6, 7, 4, 6, 3, 7,   //
      3, 1, 7, 6, 5, 4, 7, 3, 6, 2, 7, 5;
  return solid::Mesh(v, t, {0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5});
}

TEST(SolidMesh, PointAndSegmentClearanceOfACube) {
  const auto m = cube();
  EXPECT_EQ(m.triangles(), 12);
  EXPECT_EQ(m.face_count(), 6);
  EXPECT_NEAR(m.distance(Eigen::Vector3d(5, 5, 13)), 3, kExact);    // above a face
  EXPECT_NEAR(m.distance(Eigen::Vector3d(13, 5, 14)), 5, kExact);   // beyond an edge
  EXPECT_NEAR(m.distance(Eigen::Vector3d(-1, -2, -2)), 3, kExact);  // off a corner
  EXPECT_NEAR(m.distance(Eigen::Vector3d(5, 5, 4)), 4, kExact);     // inside: to the wall
  EXPECT_EQ(m.distance(Eigen::Vector3d(5, 5, 30), 2.0), 2.0);       // nothing within 2
  EXPECT_NEAR(m.distance(Eigen::Vector3d(-5, 5, 5), Eigen::Vector3d(20, 5, 5)), 0, kExact);
  EXPECT_NEAR(m.distance(Eigen::Vector3d(-5, 5, 12), Eigen::Vector3d(20, 5, 12)), 2, kExact);
  EXPECT_NEAR(m.distance(Eigen::Vector3d(12, 12, 20), Eigen::Vector3d(12, 12, -20)), std::sqrt(8.0),
              kExact);  // along a vertical edge
  // Leaving the top face (id 1) out: the nearest is then a side.
  std::vector<char> skip(6, 0);
  skip[1] = 1;
  EXPECT_NEAR(m.distance(Eigen::Vector3d(5, 5, 11), INFINITY, skip), std::sqrt(25.0 + 1), kExact);
  // Only the top face: its distance from a point beside the cube, for point and segment.
  std::vector<char> top(6, 1);
  top[1] = 0;
  EXPECT_NEAR(m.distance(Eigen::Vector3d(13, 5, 5), INFINITY, top), std::sqrt(9.0 + 25), kExact);
  EXPECT_NEAR(m.distance(Eigen::Vector3d(13, 5, 5), Eigen::Vector3d(13, 5, -5), INFINITY, top),
              std::sqrt(9.0 + 25), kExact);
  EXPECT_EQ(m.distance(Eigen::Vector3d(5, 5, 5), 1.0, std::vector<char>(6, 1)), 1.0);
  // The faces a plane crosses: z = 5 meets the four sides.
  EXPECT_EQ(m.faces_crossing(Eigen::Vector3d(0, 0, 5), Eigen::Vector3d::UnitZ()),
            std::vector<char>({0, 0, 1, 1, 1, 1}));
  // Moved and scaled.
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.linear() *= 2;
  t.translation() << 1, 0, 0;
  const auto big = m.transformed(t);
  EXPECT_NEAR(big.distance(Eigen::Vector3d(10, 10, 23)), 3, kExact);
  EXPECT_NEAR(big.highest(Eigen::Vector3d::UnitZ()), 20, kExact);
  EXPECT_NEAR(big.box().min().x(), 1, kExact);
  // The top under a move across it, and beside it.
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(m.highest_near(up, Eigen::Vector3d(-5, 5, 50), Eigen::Vector3d(20, 5, 50), 0.5), 10,
              kExact);
  EXPECT_EQ(m.highest_near(up, Eigen::Vector3d(-5, 15, 50), Eigen::Vector3d(20, 15, 50), 0.5),
            -INFINITY);
  EXPECT_NEAR(m.highest_near(up, Eigen::Vector3d(-5, 15, 50), Eigen::Vector3d(20, 15, 50), 5.5), 10,
              kExact);
}

// A ball touching a face a section plane does not cross is on the wall it scans when the face's
// normal lies near the plane there (a wall the CAD file split at the plane), not when it faces
// across the plane. Faces: 0 bottom, 1 top, 2 y = 0, 3 y = 10, 4 x = 0, 5 x = 10.
TEST(SolidMesh, ABallScansOnAFaceWhoseNormalLiesNearThePlane) {
  const auto m = cube();
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  // The plane y = 10.05 crosses no face; the ball beside the x = 0 side touches its edge, with
  // the contact normal 3° from the plane.
  const auto none = m.faces_crossing(Eigen::Vector3d(0, 10.05, 0), y);
  EXPECT_EQ(none, std::vector<char>(6, 0));
  const Eigen::Vector3d beside(-0.9, 10.05, 5);
  EXPECT_LT(m.distance(beside), 1.0);
  EXPECT_TRUE(solid::scans_on(m, beside, none, y));
  // The plane y = 5: the ball against the y = 10 side touches a face that faces across it.
  const auto mid = m.faces_crossing(Eigen::Vector3d(0, 5, 0), y);
  EXPECT_EQ(mid, std::vector<char>({1, 1, 0, 0, 1, 1}));
  EXPECT_FALSE(solid::scans_on(m, Eigen::Vector3d(5, 10.5, 5), mid, y));
  // Nor does a ball off the top face at 45° (contact normal 45° from the plane).
  EXPECT_FALSE(solid::scans_on(m, Eigen::Vector3d(5, 10.6, 10.6), mid, y));
}

TEST(SolidMesh, BadMeshesAreRefused) {
  Eigen::Matrix3Xd v(3, 3);
  v << 0, 1, 0, 0, 0, 1, 0, 0, 0;
  Eigen::Matrix3Xi t(3, 1);
  t << 0, 1, 3;
  EXPECT_NE(test::error_of([&] { solid::Mesh(v, t); }).find("beyond the 3 given"),
            std::string::npos);
  t << 0, 1, 2;
  EXPECT_NE(test::error_of([&] {
              solid::Mesh(v, t, {0, 1});
            }).find("one face id per triangle"),
            std::string::npos);
  v(0, 0) = NAN;
  EXPECT_NE(test::error_of([&] { solid::Mesh(v, t); }).find("not a finite point"),
            std::string::npos);
  EXPECT_NE(test::error_of([] { solid::load_step(kIpp, 0); }).find("deflection"),
            std::string::npos);
  EXPECT_NE(test::error_of([] { solid::load_step("/nonexistent.stp"); }).find("cannot open"),
            std::string::npos);
}

// NIST's I++ test part: a 100 × 100 × 50 block with a Ø50 hole 25 deep.
TEST(SolidMesh, RealPartAgreesWithEveryTriangleAndItsShape) {
  const auto m = solid::load_step(kIpp, 0.01);
  ASSERT_GT(m->triangles(), 20);
  EXPECT_EQ(m, solid::load_step(kIpp, 0.01));  // read once
  EXPECT_NEAR(m->highest(Eigen::Vector3d::UnitZ()), 50, 1e-9);
  EXPECT_NEAR(m->distance(Eigen::Vector3d(20, 20, 60)), 10, 1e-9);
  // In the hole: 25 from the wall (chords of the cylinder within the deflection), 12.5 above the
  // floor.
  EXPECT_NEAR(m->distance(Eigen::Vector3d(50, 50, 45)), 20, 1e-9);
  EXPECT_NEAR(m->distance(Eigen::Vector3d(50, 50, 37.5)), 12.5, 1e-9);
  EXPECT_NEAR(m->distance(Eigen::Vector3d(50, 74, 37.5)), 1, 0.01);
  // Every query equals the search of all triangles.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-20, 120);
  const auto& v = m->vertices();
  const auto& t = m->indices();
  Eigen::Matrix3Xi one_triangle(3, 1);
  one_triangle << 0, 1, 2;
  // Also with the faces a mid-height plane crosses left out (a ball scanning there), and with
  // only those faces.
  const auto crossing = m->faces_crossing(Eigen::Vector3d(0, 0, 37.5), Eigen::Vector3d::UnitZ());
  std::vector<char> others(crossing.size());
  for (std::size_t f = 0; f < crossing.size(); ++f) others[f] = !crossing[f];
  const auto& without = crossing;
  const auto& only = others;
  const auto& face = m->triangle_faces();
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d p(u(rng), u(rng), 0.5 * u(rng));
    const Eigen::Vector3d q = p + Eigen::Vector3d(u(rng), u(rng), u(rng)) * 0.2;
    double best = INFINITY, best_seg = INFINITY;
    double best_without = INFINITY, best_only = INFINITY, seg_without = INFINITY;
    for (Eigen::Index i = 0; i < t.cols(); ++i) {
      Eigen::Matrix3Xd corners(3, 3);
      corners << v.col(t(0, i)), v.col(t(1, i)), v.col(t(2, i));
      const solid::Mesh one(corners, one_triangle);
      const double d = one.distance(p), ds = one.distance(p, q);
      best = std::min(best, d);
      best_seg = std::min(best_seg, ds);
      const bool crosses = crossing[static_cast<std::size_t>(face[static_cast<std::size_t>(i)])];
      (crosses ? best_only : best_without) = std::min(crosses ? best_only : best_without, d);
      if (!crosses) seg_without = std::min(seg_without, ds);
    }
    EXPECT_NEAR(m->distance(p), best, 1e-12);
    EXPECT_NEAR(m->distance(p, q), best_seg, 1e-12);
    EXPECT_NEAR(m->distance(p, INFINITY, without), best_without, 1e-12);
    EXPECT_NEAR(m->distance(p, q, INFINITY, without), seg_without, 1e-12);
    EXPECT_NEAR(m->distance(p, INFINITY, only), best_only, 1e-12);
  }
  EXPECT_GT(std::count(crossing.begin(), crossing.end(), 1), 0);
}

}  // namespace
}  // namespace trueaxis
