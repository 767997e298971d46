// Internal to libtrueaxis_occt.so: the design module's Open CASCADE Technology (OCCT) code, and
// conversions between trueaxis design data and OCCT objects. These throw Error or OCCT's
// Standard_Failure; api.cpp turns both into messages at the library's boundary.
#pragma once

#include <Bnd_Box.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Dir.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>
#include <string>
#include <vector>

#include "../occt_api.hpp"
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

// A stretch of a curve, walked from parameter a to b (a < b).
struct OffsetSpan {
  Handle(Geom_Curve) curve;
  double a = 0, b = 0;
};

// The planar offset of a plane section's curve (`c`, as curve(s)) by d ≥ 0 mm away from the
// material: the path of a ball centre of radius d rolling along it, in the curve's direction,
// starting beside its start (or where the ball first fits). Throws Error naming where the ball
// does not fit (offset.cpp).
std::vector<OffsetSpan> offset_curve(const Section& s, const Handle(Geom_BSplineCurve) & c,
                                     double d);

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

// Unit normal of the surface where the curve's first derivative is `tangent` (any length): in
// the plane, away from the material.
Eigen::Vector3d away_from_material(const Section& s, const Eigen::Vector3d& tangent);

// The first and last point of a NURBS section's curve (Error: OCCT rejects the curve).
void ends(const Section& s, Eigen::Vector3d& first, Eigen::Vector3d& last);
// design::length of a NURBS section (mm).
double length(const Section& s);
// design::piece of a NURBS section (0 ≤ from < to ≤ from + length, to ≤ length if open).
Section piece(const Section& s, double from, double to);
// design::sample of a NURBS section with a chord tolerance (> 0, mm).
Samples sample_fine(const Section& s, double spacing, double tolerance);
// design::sample of a NURBS section; spacing > 0 (mm).
Samples sample(const Section& s, double spacing);
// design::make_path of a checked plane section whose plane normal has unit length, with validated
// options.
ScanPath plane_path(const Section& s, const PathOptions& o);
// A STEP file's part: the union of its solids, with what was learnt reading it (the counts,
// tolerances and notes of StepCut).
struct StepPart {
  TopoDS_Shape shape;
  double join = 0;  // mm: cut edges closer than this are joined
  Bnd_Box box;
};
StepPart read_step(const std::string& path, const StepCutOptions& o, StepCut& info);

// The sections of the part of a STEP file (read once per process) moved by the row-major 3 × 4
// affine map, in `plane`.
Design moved_sections(const std::string& path, const double (&map)[12], const Plane& plane);

// design::cut_step.
StepCut cut_step(const std::string& path, const std::vector<StepSectionRequest>& planes,
                 const StepCutOptions& options);
// The part of a STEP file as triangles within `deflection` of its faces (mesh.cpp).
void step_mesh(const std::string& path, double deflection, detail::MeshData& out);

}  // namespace trueaxis::design::occt
