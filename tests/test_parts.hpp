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

// A spiral over a sphere of radius 50 mm about (50, 50, 0): three turns from 20° to 70° from the
// pole, every ~0.5 mm, with the sphere's outward normals. A scan path that no plane contains.
inline design::Section spiral_on_sphere() {
  design::Section s;
  s.name = "spiral";
  s.closed = false;
  const double R = 50;
  const Eigen::Vector3d c(50, 50, 0);
  const int n = 1301;  // ~ 640 mm of curve
  s.polyline.resize(3, n);
  s.normals.resize(3, n);
  for (int i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / (n - 1);
    const double theta = (20 + 50 * t) * M_PI / 180, phi = 3 * 2 * M_PI * t;
    const Eigen::Vector3d u(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                            std::cos(theta));
    s.polyline.col(i) = c + R * u;
    s.normals.col(i) = u;
  }
  return s;
}

// A Ø60 mm circle in a plane tilted 30° about x through (50, 50, 25), given as a space curve
// (144-gon with its outward normals in the plane): the outline of a boss cut obliquely.
inline design::Section oblique_circle() {
  design::Section s;
  s.name = "oblique";
  s.closed = true;
  const Eigen::Vector3d c(50, 50, 25);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const int n = 145;
  s.polyline.resize(3, n);
  s.normals.resize(3, n);
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * (i % (n - 1)) / (n - 1);
    const Eigen::Vector3d u = R * Eigen::Vector3d(std::cos(a), std::sin(a), 0);
    s.polyline.col(i) = c + 30 * u;
    s.normals.col(i) = u;
  }
  return s;
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
