// Error-tolerant scanning of a real CAD part (NIST's DaimlerChrysler test part, public STEP file
// in tests/data/cad/): eight contours at z = 19.98 mm around tabs with sloping undersides,
// bosses and a slot the part covers from above. Parts moved off their design and parts with a
// bump: every reachable stretch is scanned, the rest is reported, nothing runs into the part,
// and every point lies on the moved solid as Open CASCADE computes it independently (the STEP
// file read again, moved with gp_Trsf, and each point's distance to its faces).
#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <STEPControl_Reader.hxx>
#include <gp_Trsf.hxx>
#include <string>

#include "../test_util.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/scan/controller.hpp"
#include "trueaxis/sim/part.hpp"

namespace trueaxis {
namespace {

const std::string kPart = std::string(TRUEAXIS_TEST_DATA) + "/cad/DaimlerChryslerTestPartAP214.stp";

// Noise-free points lie on the simulated true contour (the exact cut of the moved solid, its
// chords within 1e-5 mm) to round-off.
constexpr double kOnTrueContour = 1e-6;  // mm
// And on the moved CAD faces within the chord tolerance of that contour.
constexpr double kOnCadFaces = 1e-3;  // mm: the 1 µm the scanning must hold

int count(const scan::Result& r, const std::string& ev) {
  int n = 0;
  for (const auto& e : r.events) n += e.event == ev;
  return n;
}

// Each section scanned or refused as not reachable, never a collision or a planning failure.
void expect_finished(const scan::Result& r, const std::string& label) {
  EXPECT_TRUE(r.stopped.empty()) << label << ": " << r.stopped;
  for (const auto& s : r.sections)
    if (!s.ok) {
      EXPECT_TRUE(s.not_reachable) << label << ": " << s.name << ": " << s.reason;
      EXPECT_NE(s.reason.find("not reachable"), std::string::npos) << s.reason;
    }
}

TEST(CadScan, DaimlerChryslerPartMovedOrBumpedScansWhatTheStylusReaches) {
  const design::Design d = design::from_step(
      kPart, {{"z", {Eigen::Vector3d(0, -9.255, 19.98), Eigen::Vector3d::UnitZ()}}});
  ASSERT_EQ(d.sections.size(), 8u);
  STEPControl_Reader reader;
  ASSERT_EQ(reader.ReadFile(kPart.c_str()), IFSelect_RetDone);
  reader.TransferRoots();
  const TopoDS_Shape shape = reader.OneShape();

  struct Case {
    std::string label;
    sim::PartDeviation dev;
  };
  std::vector<Case> cases(2);
  cases[0].label = "moved 2 mm along y";
  cases[0].dev.translation = Eigen::Vector3d(0, 2, 0);
  cases[1].label = "a 2 mm bump";
  cases[1].dev.bumps = {{"z.1", 20, 2.0, 20}};
  for (const auto& c : cases) {
    sim::Part part{d, c.dev};
    const scan::ControllerOptions o;
    scan::VirtualCmm cmm(part, {}, scan::start_position(d, o));
    const auto r = scan::scan(cmm, d, o);
    expect_finished(r, c.label);
    // The slot (z.4) is covered from above; stretches under the tabs' sloping undersides are
    // left out and reported.
    EXPECT_FALSE(r.unreachable.empty()) << c.label;
    int scanned = 0;
    for (const auto& s : r.sections) scanned += s.ok;
    EXPECT_GE(scanned, 7) << c.label << ": " << r.summary();

    // Every point on the true contour; a sample of them on the moved CAD faces.
    gp_Trsf t;
    const Eigen::Affine3d T = sim::transform(part);
    t.SetValues(T(0, 0), T(0, 1), T(0, 2), T(0, 3), T(1, 0), T(1, 1), T(1, 2), T(1, 3), T(2, 0),
                T(2, 1), T(2, 2), T(2, 3));
    const TopoDS_Shape moved = BRepBuilderAPI_Transform(shape, t, true).Shape();
    double worst = 0, worst_cad = 0;
    for (std::size_t i = 0; i < r.sections.size(); ++i) {
      const auto& pts = r.sections[i].points;
      for (std::size_t k = 0; k < pts.size(); ++k) {
        worst =
            std::max(worst, std::abs(cmm.distance(r.planned.sections[i].plane, pts[k].surface)));
        // The bump is a form deviation the CAD faces do not have.
        if (k % 97 != 0 || !c.dev.bumps.empty()) continue;
        const Eigen::Vector3d& p = pts[k].surface;
        BRepExtrema_DistShapeShape dist(BRepBuilderAPI_MakeVertex(gp_Pnt(p.x(), p.y(), p.z())),
                                        moved);
        ASSERT_TRUE(dist.IsDone());
        worst_cad = std::max(worst_cad, dist.Value());
      }
    }
    EXPECT_LT(worst, kOnTrueContour) << c.label;
    EXPECT_LT(worst_cad, kOnCadFaces) << c.label;

    // The next part of the batch, with the corrected design data: no trajectory error.
    part.deviation.seed = 2;
    scan::VirtualCmm cmm2(part, {}, scan::start_position(r.design, o));
    const auto r2 = scan::scan(cmm2, r.design, o);
    expect_finished(r2, c.label + ", second part");
    EXPECT_EQ(count(r2, "trajectory_error"), 0) << c.label << ": " << r2.summary();
  }
}

}  // namespace
}  // namespace trueaxis
