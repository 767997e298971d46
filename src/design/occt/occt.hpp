// Internal to libtrueaxis_occt.so: the design module's Open CASCADE Technology (OCCT) code, and
// conversions between trueaxis design data and OCCT objects. These throw Error or OCCT's
// Standard_Failure; api.cpp turns both into messages at the library's boundary.
#pragma once

#include <Geom_BSplineCurve.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Dir.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>
#include <string>
#include <vector>

#include "trueaxis/design/design.hpp"

namespace trueaxis::design::occt {

inline gp_Pnt pnt(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}
inline gp_Dir dir(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}
inline Eigen::Vector3d vec(const gp_XYZ& p) {
  return {p.X(), p.Y(), p.Z()};
}
inline Eigen::Vector3d vec(const gp_Pnt& p) {
  return vec(p.XYZ());
}
inline Eigen::Vector3d vec(const gp_Vec& p) {
  return vec(p.XYZ());
}

// OCCT's message for a failure it raised ("" if none), for our one-line errors.
std::string message(const Standard_Failure& e);

// The section's curve as one B-spline (a polyline is a degree-1 B-spline with knots at its
// cumulative chord lengths). Precondition: check(s) is empty.
Handle(Geom_BSplineCurve) curve(const Section& s);

// The curve split where it is only C0 (interior knots of multiplicity ≥ degree: corners), as
// edges of one wire, in the curve's direction.
TopoDS_Wire wire(const Section& s);

// Parameters where the curve has a corner: interior knots where the tangent direction jumps
// (more than 1e-7 rad), plus both ends of an open curve and the start of a closed curve whose end
// tangent differs from its start tangent.
std::vector<double> corners(const Geom_BSplineCurve& c, bool closed);

// Signed area enclosed by a closed curve seen from `normal` (positive: counter-clockwise), by the
// shoelace formula on 2000 points (mm²).
double signed_area(const Geom_BSplineCurve& c, const Eigen::Vector3d& normal);

// A B-spline back to our flat-knot NURBS.
Nurbs nurbs(const Geom_BSplineCurve& c);

// Unit normal of the surface at curve parameter t: in the plane, away from the material.
Eigen::Vector3d away_from_material(const Section& s, const Geom_BSplineCurve& c, double t);

// The first and last point of a NURBS section's curve (Error: OCCT rejects the curve).
void ends(const Section& s, Eigen::Vector3d& first, Eigen::Vector3d& last);
// design::length of a NURBS section (mm).
double length(const Section& s);
// design::sample of a NURBS section; spacing > 0 (mm).
Samples sample(const Section& s, double spacing);
// design::make_path of a checked plane section whose plane normal has unit length, with validated
// options.
ScanPath plane_path(const Section& s, const PathOptions& o);
// design::from_step.
Design from_step(const std::string& path, const std::vector<StepSectionRequest>& planes);

}  // namespace trueaxis::design::occt
