// Parts shared by the design, simulation and scanning tests.
#pragma once

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <GeomAPI_Interpolate.hxx>
#include <STEPControl_Writer.hxx>
#include <TColgp_HArray1OfPnt.hxx>
#include <TopoDS.hxx>
#include <cmath>
#include <string>

#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::test {

// NIST's I++ test part in its section at z = 25, as polylines: "outer", the 100 mm square
// (counter-clockwise, material inside), and "hole", the Ø50 mm hole as a 72-gon (material
// outside); or the same `k` times larger about the origin.
inline design::Design square_and_hole(double k = 1) {
  design::Design d;
  design::Section sq;
  sq.name = "outer";
  sq.plane = {Eigen::Vector3d(0, 0, 25), Eigen::Vector3d::UnitZ()};
  sq.polyline.resize(3, 5);
  sq.polyline << 0, 100 * k, 100 * k, 0, 0, 0, 0, 100 * k, 100 * k, 0, 25, 25, 25, 25, 25;
  d.sections.push_back(sq);
  design::Section hole;
  hole.name = "hole";
  hole.plane = sq.plane;
  hole.material = design::Side::Right;
  const int n = 73;
  hole.polyline.resize(3, n);
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * (i % (n - 1)) / (n - 1);
    hole.polyline.col(i) << k * (50 + 25 * std::cos(a)), k * (50 + 25 * std::sin(a)), 25;
  }
  d.sections.push_back(hole);
  return d;
}

// The profile of a lobed prism: a periodic B-spline through 12 points at radius 30 + 4 cos 3a
// in the plane z = 0.
inline Handle(Geom_BSplineCurve) lobed_profile() {
  Handle(TColgp_HArray1OfPnt) pts = new TColgp_HArray1OfPnt(1, 12);
  for (int i = 0; i < 12; ++i) {
    const double a = 2 * M_PI * i / 12, r = 30 + 4 * std::cos(3 * a);
    pts->SetValue(i + 1, gp_Pnt(r * std::cos(a), r * std::sin(a), 0));
  }
  GeomAPI_Interpolate interp(pts, Standard_True, 1e-9);
  interp.Perform();
  if (!interp.IsDone()) throw Error("lobed profile: interpolation failed");
  return interp.Curve();
}

// The lobed prism (40 mm high), every face converted to B-spline surfaces, written to `path` as
// STEP. Returns the solid.
inline TopoDS_Shape write_lobed_solid(const std::string& path) {
  const TopoDS_Edge e = BRepBuilderAPI_MakeEdge(lobed_profile()).Edge();
  const TopoDS_Face f = BRepBuilderAPI_MakeFace(BRepBuilderAPI_MakeWire(e).Wire()).Face();
  const TopoDS_Shape solid =
      BRepBuilderAPI_NurbsConvert(BRepPrimAPI_MakePrism(f, gp_Vec(0, 0, 40)).Shape()).Shape();
  STEPControl_Writer w;
  if (w.Transfer(solid, STEPControl_AsIs) != IFSelect_RetDone ||
      w.Write(path.c_str()) != IFSelect_RetDone)
    throw Error(path + ": could not write the lobed solid");
  return solid;
}

}  // namespace trueaxis::test
