// NURBS section curves through OCCT: end points, arc length, and samples at even arc spacing.
#include <GCPnts_AbscissaPoint.hxx>
#include <GCPnts_UniformAbscissa.hxx>
#include <GeomAdaptor_Curve.hxx>
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
