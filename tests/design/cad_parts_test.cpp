// Sections of real CAD parts (public STEP files of NIST, tests/data/cad/), checked against an
// independent computation with Open CASCADE's other algorithms: every sampled point of every
// section lies on the part's surface, its material side agrees with a point classification in
// 3-D, and every place where a line in the plane crosses the part's faces lies on a section.
#include <BRepAdaptor_Surface.hxx>
#include <BRepAlgoAPI_Section.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepClass3d_SolidClassifier.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Builder.hxx>
#include <IntCurvesFace_ShapeIntersector.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Lin.hxx>
#include <gp_Pln.hxx>
#include <map>
#include <memory>

#include "../test_util.hpp"
#include "trueaxis/design/design.hpp"

namespace trueaxis {
namespace {

const std::string kCad = std::string(TRUEAXIS_TEST_DATA) + "/cad/";

// The part as Open CASCADE reads it, solid by solid.
struct CadPart {
  std::vector<TopoDS_Shape> solids;
  TopoDS_Compound all;
};

CadPart read_part(const std::string& file) {
  STEPControl_Reader r;
  EXPECT_EQ(r.ReadFile(file.c_str()), IFSelect_RetDone);
  r.TransferRoots();
  CadPart p;
  BRep_Builder b;
  b.MakeCompound(p.all);
  for (TopExp_Explorer e(r.OneShape(), TopAbs_SOLID); e.More(); e.Next()) {
    p.solids.push_back(e.Current());
    b.Add(p.all, e.Current());
  }
  return p;
}

gp_Pnt pt(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

bool inside(std::vector<std::unique_ptr<BRepClass3d_SolidClassifier>>& solids,
            const Eigen::Vector3d& q) {
  for (auto& c : solids) {
    c->Perform(pt(q), 1e-7);
    if (c->State() == TopAbs_IN) return true;
  }
  return false;
}

// Distance of q from the nearest face of the part (mm).
double to_surface(const CadPart& part, const Eigen::Vector3d& q) {
  BRepExtrema_DistShapeShape d(BRepBuilderAPI_MakeVertex(pt(q)).Vertex(), part.all);
  EXPECT_TRUE(d.IsDone());
  return d.Value();
}

// A closed polyline along a section (chords within 0.1²/8R of the curve) and its longest chord.
struct Polyline {
  Eigen::Matrix3Xd p;
  double longest = 0;
};

Polyline polyline(const Eigen::Matrix3Xd& p) {
  double longest = 0;
  for (Eigen::Index i = 0; i < p.cols(); ++i)
    longest = std::max(longest, (p.col((i + 1) % p.cols()) - p.col(i)).norm());
  return {p, longest};
}

// Distance of q from the nearest of closed polylines (mm). Exact: the segment holding the nearest
// point has an end within (nearest vertex's distance + the longest chord) of q, so only segments
// with such an end are measured. Plain loops: the test program is compiled at -O0.
double to_polylines(const std::vector<Polyline>& dense, const Eigen::Vector3d& q) {
  double best = 1e300;
  std::vector<double> to_vertex;
  for (const auto& d : dense) {
    const Eigen::Index m = d.p.cols();
    const double* v = d.p.data();
    to_vertex.resize(m);
    double nearest = 1e300;
    for (Eigen::Index i = 0; i < m; ++i) {
      const double dx = v[3 * i] - q.x(), dy = v[3 * i + 1] - q.y(), dz = v[3 * i + 2] - q.z();
      to_vertex[i] = std::sqrt(dx * dx + dy * dy + dz * dz);
      nearest = std::min(nearest, to_vertex[i]);
    }
    const double reach = nearest + d.longest;
    for (Eigen::Index i = 0; i < m; ++i) {
      if (to_vertex[i] > reach && to_vertex[(i + 1) % m] > reach) continue;
      const Eigen::Vector3d a = d.p.col(i), b = d.p.col((i + 1) % m);
      const double t = std::clamp((q - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      best = std::min(best, (a + t * (b - a) - q).norm());
    }
  }
  return best;
}

struct Check {
  int points = 0, material_right = 0, bspline_faces_cut = 0, crossings = 0;
  double worst_on_surface = 0, worst_crossing = 0;
};

// The independent checks of one plane's accepted sections.
Check check_plane(const CadPart& part, const design::StepCut& cut, const design::Plane& plane,
                  const std::string& name) {
  Check c;
  Eigen::Vector3d n = plane.normal.normalized();
  std::vector<std::unique_ptr<BRepClass3d_SolidClassifier>> solids;
  for (const auto& s : part.solids)
    solids.push_back(std::make_unique<BRepClass3d_SolidClassifier>(s));
  std::vector<Polyline> dense;
  for (const auto& s : cut.design.sections) {
    if (s.name != name && s.name.rfind(name + ".", 0) != 0) continue;
    EXPECT_FALSE(design::check(s)) << s.name;
    const auto smp = design::sample(s, 0.1);
    dense.push_back(polyline(smp.points));
    // About 24 points along the contour, each where the contour is smooth (its normal turns
    // less than 10° within 0.2 mm): beside a corner, a point 0.02 mm off the contour can fall on
    // either side of the part, which proves nothing about the section.
    const Eigen::Index m = smp.points.cols(), step = std::max<Eigen::Index>(1, m / 24);
    for (Eigen::Index i = step / 2; i < m; i += step) {
      bool smooth = true;
      for (Eigen::Index k = -2; k <= 2; ++k)
        smooth =
            smooth && smp.normals.col((i + k + m) % m).dot(smp.normals.col(i)) > std::cos(0.17);
      if (!smooth) continue;
      const Eigen::Vector3d p = smp.points.col(i), away = smp.normals.col(i);
      EXPECT_NEAR((p - plane.origin).dot(n), 0, 1e-9) << s.name;
      c.worst_on_surface = std::max(c.worst_on_surface, to_surface(part, p));
      // 0.02 mm to either side: in the material, and out of it.
      c.material_right += inside(solids, p - 0.02 * away) && !inside(solids, p + 0.02 * away);
      ++c.points;
    }
  }
  // Faces of the part with a B-spline surface that the plane crosses.
  for (TopExp_Explorer f(part.all, TopAbs_FACE); f.More(); f.Next()) {
    if (BRepAdaptor_Surface(TopoDS::Face(f.Current())).GetType() != GeomAbs_BSplineSurface)
      continue;
    BRepAlgoAPI_Section sec(f.Current(), gp_Pln(pt(plane.origin), gp_Dir(n.x(), n.y(), n.z())));
    sec.Build();
    TopExp_Explorer e(sec.Shape(), TopAbs_EDGE);
    c.bspline_faces_cut += e.More();
  }
  // Lines in the plane across the part: where they cross its faces lies on a section, except
  // where a face lies inside the part (two solids that touch: the part is their union).
  IntCurvesFace_ShapeIntersector x;
  x.Load(part.all, 1e-7);
  const Eigen::Vector3d a =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e1 = (a - a.dot(n) * n).normalized(), e2 = n.cross(e1);
  for (const Eigen::Vector3d& dir : {e1, e2})
    for (int k = -12; k <= 12; ++k) {
      const Eigen::Vector3d through = plane.origin + (k * 23.7 + 0.31) * dir.cross(n);
      x.Perform(gp_Lin(pt(through), gp_Dir(dir.x(), dir.y(), dir.z())), -1e4, 1e4);
      for (int j = 1; x.IsDone() && j <= x.NbPnt(); ++j) {
        const Eigen::Vector3d q(x.Pnt(j).X(), x.Pnt(j).Y(), x.Pnt(j).Z());
        if (inside(solids, q - 0.01 * dir) && inside(solids, q + 0.01 * dir)) continue;
        c.worst_crossing = std::max(c.worst_crossing, to_polylines(dense, q));
        ++c.crossings;
      }
    }
  return c;
}

struct Case {
  std::string file;
  std::vector<design::StepSectionRequest> planes;
  int bspline_planes = 0;  // planes that must cross B-spline faces
};

design::StepSectionRequest plane(const std::string& name, Eigen::Vector3d o, Eigen::Vector3d n) {
  return {name, {o, n.normalized()}};
}

// Horizontal, vertical and oblique planes through a part: every one cut, every section right.
void every_plane_agrees(const Case& cs) {
  const CadPart part = read_part(kCad + cs.file);
  const design::StepCut cut = design::cut_step(kCad + cs.file, cs.planes);
  for (const auto& f : cut.failures) ADD_FAILURE() << f.name << ": " << f.reason;
  ASSERT_TRUE(cut.file_tolerance);
  EXPECT_LE(cut.join_tolerance, design::StepCutOptions{}.max_join);
  EXPECT_EQ(cut.solids, static_cast<int>(part.solids.size()));
  int bspline_planes = 0;
  for (const auto& rq : cs.planes) {
    SCOPED_TRACE(rq.name);
    const Check c = check_plane(part, cut, rq.plane, rq.name);
    ASSERT_GT(c.points, 0);
    // On the surface within the join tolerance (and the section's approximation, 1e-4 mm).
    EXPECT_LE(c.worst_on_surface, cut.join_tolerance + 1e-4);
    EXPECT_EQ(c.material_right, c.points);
    EXPECT_GT(c.crossings, 0);
    EXPECT_LE(c.worst_crossing, cut.join_tolerance + 0.05);
    bspline_planes += c.bspline_faces_cut > 0;
  }
  EXPECT_GE(bspline_planes, cs.bspline_planes);
  // Each section's edges met within the join tolerance, and it says what it closed.
  for (const auto& s : cut.design.sections) EXPECT_LE(s.joined_gap, cut.join_tolerance);
}

// A body and six hemispheres, as seven solids (mm, CATIA V5, tolerance 0.005 mm).
TEST(CadParts, DaimlerChryslerSectionsAgreeWithAnIndependentCut) {
  every_plane_agrees({"DaimlerChryslerTestPartAP214.stp",
                      {plane("z15", {0, 0, 15}, {0, 0, 1}), plane("z32", {0, 0, 32}, {0, 0, 1}),
                       plane("y", {0, -25.5687, 27}, {0, 1, 0}), plane("x", {0, 0, 27}, {1, 0, 0}),
                       plane("tilt", {-35, -40, 16}, {1, 1, 1})},
                      0});
}

// Inch units, 27 B-spline faces (tolerance 0.0932 mm).
TEST(CadParts, Ctc05SectionsAgreeWithAnIndependentCut) {
  every_plane_agrees(
      {"nist_ctc_05_asme1_rd.stp",
       {plane("z", {0, 0, 62.7}, {0, 0, 1}), plane("z52", {0, 0, 52}, {0, 0, 1}),
        plane("z300", {0, 0, 300}, {0, 0, 1}), plane("y", {0, -72.67, 241.3}, {0, 1, 0}),
        plane("x", {0, 0, 241.3}, {1, 0, 0}), plane("tilt", {-105.4, -111.8, 144.8}, {1, 0, 2})},
       2});
}

// Tori and a B-spline face, mm (tolerance 0.01 mm).
TEST(CadParts, Ftc10SectionsAgreeWithAnIndependentCut) {
  every_plane_agrees(
      {"nist_ftc_10_asme1_rb.stp",
       {plane("z", {0, 15.8, 0}, {0, 0, 1}), plane("y", {0, 15.83, 0}, {0, 1, 0}),
        plane("x", {33.49, 15.83, 0}, {1, 0, 0}), plane("x21", {21, 15, 0}, {1, 0, 0}),
        plane("tilt", {-31.9, 9.5, -15.3}, {0, 1, 1})},
       2});
}

// The tolerance the file states (ISO 10303-41 uncertainty), converted to mm, joins the edges;
// several solids are one part, and the material side of each contour comes from all of them.
TEST(CadParts, FileToleranceUnitsAndSeveralSolids) {
  const auto ctc = design::cut_step(kCad + "nist_ctc_05_asme1_rd.stp", {});
  ASSERT_TRUE(ctc.file_tolerance);
  EXPECT_NEAR(*ctc.file_tolerance, 3.669172334393e-3 * 25.4, 1e-12);  // inch -> mm
  EXPECT_DOUBLE_EQ(ctc.join_tolerance, *ctc.file_tolerance);
  const auto ftc = design::cut_step(kCad + "nist_ftc_10_asme1_rb.stp", {});
  EXPECT_NEAR(*ftc.file_tolerance, 0.01, 1e-15);
  // A bound on the join: the file's own tolerance, never more than max_join.
  design::StepCutOptions tight;
  tight.max_join = 0.02;
  EXPECT_DOUBLE_EQ(design::cut_step(kCad + "nist_ctc_05_asme1_rd.stp", {}, tight).join_tolerance,
                   0.02);

  // DaimlerChrysler: z = 15 cuts the body and the hemisphere on its +x face (solid 1), which
  // touches the body; z = 32 cuts three hemispheres standing on the body's top at z = 30.
  const auto dc =
      design::cut_step(kCad + "DaimlerChryslerTestPartAP214.stp",
                       {plane("z15", {0, 0, 15}, {0, 0, 1}), plane("z32", {0, 0, 32}, {0, 0, 1})});
  EXPECT_EQ(dc.solids, 7);
  EXPECT_TRUE(dc.ok());
  std::map<std::string, design::Side> side;
  for (const auto& s : dc.design.sections) side[s.name] = s.material;
  // The outline of the body (with the hemisphere merged into it) is the longest contour of z15,
  // material inside; every section's side was checked in 3-D by the test above.
  ASSERT_TRUE(side.count("z15.1"));
  EXPECT_EQ(side["z15.1"], design::Side::Left);
  // The hemisphere on the +x face (centre (79.0, 0, 15), radius 4.75) bulges from the outline:
  // a point 4 mm beyond the face, on the x axis, is in the material of z15.1.
  const auto& outline = dc.design.sections.front();
  const auto smp = design::sample(outline, 0.2);
  double reach = -1e9;
  for (Eigen::Index i = 0; i < smp.points.cols(); ++i)
    if (std::abs(smp.points(1, i)) < 0.5) reach = std::max(reach, smp.points(0, i));
  EXPECT_NEAR(reach, 83.75, 0.01);
}

// Even samples of real B-spline contours lie at their arc lengths, checked against an
// independent measure: a polyline within 1e-9 mm of the curve (chords split where they leave it),
// along which the arc is exact to far below the check. The contour's length is the same one.
TEST(CadParts, EvenSamplesOfBsplineContoursLieAtTheirArcLengths) {
  constexpr double kSameArc = 1e-6;  // mm
  const auto cut = design::cut_step(
      kCad + "nist_ctc_05_asme1_rd.stp",
      {plane("tilt", {-105.4, -111.8, 144.8}, {1, 0, 2}), plane("z52", {0, 0, 52}, {0, 0, 1})});
  int checked = 0;
  for (const auto& s : cut.design.sections) {
    if (!s.nurbs) continue;
    const auto fine = design::sample(s, 0.2, 1e-9);
    const Eigen::Index k = fine.points.cols();
    const double L =
        fine.arc[k - 1] + (s.closed ? (fine.points.col(0) - fine.points.col(k - 1)).norm() : 0.0);
    EXPECT_NEAR(design::length(s), L, kSameArc) << s.name;
    const auto smp = design::sample(s, 0.37);
    const Eigen::Index m = smp.points.cols();
    ASSERT_GE(m, 3) << s.name;
    const double step = design::length(s) / static_cast<double>(s.closed ? m : m - 1);
    Eigen::Index j = 0;
    for (Eigen::Index i = 1; i < m; i += std::max<Eigen::Index>(1, m / 9)) {
      EXPECT_NEAR(smp.arc[i], static_cast<double>(i) * step, 1e-9 * L) << s.name;
      // The polyline's point at the same arc.
      while (j + 2 < k && fine.arc[j + 1] < smp.arc[i]) ++j;
      const double f = (smp.arc[i] - fine.arc[j]) / (fine.arc[j + 1] - fine.arc[j]);
      const Eigen::Vector3d at =
          fine.points.col(j) + f * (fine.points.col(j + 1) - fine.points.col(j));
      EXPECT_LT((at - smp.points.col(i)).norm(), kSameArc)
          << s.name << " at " << smp.arc[i] << " of " << L << " mm";
      ++checked;
    }
    // A piece ends where the sample at its length is.
    const Eigen::Index h = m / 3;
    const auto head = design::sample(design::piece(s, 0, smp.arc[h], "head"), 1e3);
    EXPECT_LT((head.points.col(head.points.cols() - 1) - smp.points.col(h)).norm(), kSameArc);
  }
  EXPECT_GE(checked, 20);
}

// Pieces of a closed contour across its start, and pieces that reach past its end or start by
// less than a micrometre (the DaimlerChrysler part cut at x = 0: the scan's reachable ends once
// asked for such a piece, and Open CASCADE threw "NCollection_Array1::Create" instead of a
// stretch). A piece of no length is refused by name.
TEST(CadParts, PiecesOfAClosedContourAtItsStart) {
  const auto d = design::from_step(kCad + "DaimlerChryslerTestPartAP214.stp",
                                   {{"x0", {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()}}});
  int checked = 0;
  for (const auto& s : d.sections) {
    if (!s.nurbs || !s.closed) continue;
    const double L = design::length(s);
    const Eigen::Vector3d start = design::sample(s, 1e3).points.col(0);
    for (const double sliver : {0.0, 1e-9, 5e-7}) {
      // From a third of the way to just past the end: ends at the contour's start.
      const auto a = design::sample(design::piece(s, L / 3, L + sliver, "a"), 1e3);
      EXPECT_LT((a.points.col(a.points.cols() - 1) - start).norm(), 1e-6) << s.name;
      EXPECT_NEAR(design::length(design::piece(s, L / 3, L + sliver, "a")), 2 * L / 3, 1e-6);
      // From just before the end, round the start, to a third of the way.
      const auto b = design::piece(s, L - sliver, L + L / 3, "b");
      EXPECT_NEAR(design::length(b), L / 3 + sliver, 1e-6) << s.name;
    }
    // Across the start: both sides of it.
    EXPECT_NEAR(design::length(design::piece(s, 0.9 * L, 1.2 * L, "c")), 0.3 * L, 1e-6);
    EXPECT_THROW(design::piece(s, L / 2, L / 2, "none"), Error);
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

}  // namespace
}  // namespace trueaxis
