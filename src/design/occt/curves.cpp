// NURBS section curves through OCCT: end points, arc length, and samples at even arc spacing.
#include <GCPnts_AbscissaPoint.hxx>
#include <GCPnts_UniformAbscissa.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <GeomConvert_CompCurveToBSplineCurve.hxx>
#include <algorithm>
#include <cmath>

#include "occt.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {

void ends(const Section& s, Eigen::Vector3d& first, Eigen::Vector3d& last) {
  Handle(Geom_BSplineCurve) c = curve(s);
  first = vec(c->StartPoint());
  last = vec(c->EndPoint());
}

double length(const Section& s) {
  GeomAdaptor_Curve a(curve(s));
  return GCPnts_AbscissaPoint::Length(a);
}

Section piece(const Section& s, double from, double to) {
  Handle(Geom_BSplineCurve) c = curve(s);
  GeomAdaptor_Curve a(c);
  const double total = GCPnts_AbscissaPoint::Length(a);
  auto param = [&](double arc) {
    GCPnts_AbscissaPoint ap(a, arc, c->FirstParameter());
    if (!ap.IsDone()) throw Error("cannot find arc length " + std::to_string(arc) + " mm");
    return ap.Parameter();
  };
  Handle(Geom_BSplineCurve) out;
  if (to <= total + 1e-9) {
    out = Handle(Geom_BSplineCurve)::DownCast(c->Copy());
    out->Segment(param(from), param(std::min(to, total)));
  } else {  // across the start of a closed curve
    Handle(Geom_BSplineCurve) tail = Handle(Geom_BSplineCurve)::DownCast(c->Copy());
    tail->Segment(param(from), c->LastParameter());
    Handle(Geom_BSplineCurve) head = Handle(Geom_BSplineCurve)::DownCast(c->Copy());
    head->Segment(c->FirstParameter(), param(to - total));
    GeomConvert_CompCurveToBSplineCurve joined(tail);
    if (!joined.Add(head, 1e-6, Standard_True))
      throw Error("the stretch across the curve's start does not join");
    out = joined.BSplineCurve();
  }
  Section p = s;
  p.closed = false;
  p.nurbs = nurbs(*out);
  return p;
}

Samples sample(const Section& s, double spacing) {
  Handle(Geom_BSplineCurve) c = curve(s);
  GeomAdaptor_Curve a(c);
  const double total = GCPnts_AbscissaPoint::Length(a);
  const int n = std::max(2, static_cast<int>(std::ceil(total / spacing)) + 1);
  GCPnts_UniformAbscissa ua(a, n);
  if (!ua.IsDone()) throw Error("cannot sample the section curve '" + s.name + "'");
  const int m = s.closed ? ua.NbPoints() - 1 : ua.NbPoints();
  Samples out;
  out.points.resize(3, m);
  out.normals.resize(3, m);
  out.arc.resize(m);
  Section unit = s;
  unit.plane.normal.normalize();
  for (int i = 0; i < m; ++i) {
    const double t = ua.Parameter(i + 1);
    out.points.col(i) = vec(c->Value(t));
    out.normals.col(i) = away_from_material(unit, *c, t);
    out.arc[i] = total * i / (ua.NbPoints() - 1);
  }
  return out;
}

}  // namespace trueaxis::design::occt
