// Conversions between trueaxis design data and Open CASCADE Technology objects.
#include "occt.hpp"

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <Precision.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <vector>

#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {

std::string message(const Standard_Failure& e) {
  const char* m = e.GetMessageString();
  return m && *m ? std::string(m) : std::string(e.DynamicType()->Name());
}

Handle(Geom_BSplineCurve) curve(const Section& s) {
  if (s.nurbs) {
    const Nurbs& n = *s.nurbs;
    const int np = static_cast<int>(n.control_points.cols());
    TColgp_Array1OfPnt poles(1, np);
    TColStd_Array1OfReal weights(1, np);
    for (int i = 0; i < np; ++i) {
      poles(i + 1) = pnt(n.control_points.col(i));
      weights(i + 1) = n.weights[i];
    }
    // Flat knots -> distinct values and multiplicities.
    std::vector<double> k;
    std::vector<int> m;
    for (Eigen::Index i = 0; i < n.knots.size(); ++i) {
      if (!k.empty() && n.knots[i] == k.back())
        ++m.back();
      else {
        k.push_back(n.knots[i]);
        m.push_back(1);
      }
    }
    TColStd_Array1OfReal knots(1, static_cast<int>(k.size()));
    TColStd_Array1OfInteger mults(1, static_cast<int>(k.size()));
    for (std::size_t i = 0; i < k.size(); ++i) {
      knots(static_cast<int>(i) + 1) = k[i];
      mults(static_cast<int>(i) + 1) = m[i];
    }
    try {
      return new Geom_BSplineCurve(poles, weights, knots, mults, n.degree);
    } catch (const Standard_Failure& e) {
      throw Error("the NURBS curve is not valid: " + message(e));
    }
  }
  const int np = static_cast<int>(s.polyline.cols());
  TColgp_Array1OfPnt poles(1, np);
  TColStd_Array1OfReal knots(1, np);
  TColStd_Array1OfInteger mults(1, np);
  double arc = 0;
  for (int i = 0; i < np; ++i) {
    if (i) arc += (s.polyline.col(i) - s.polyline.col(i - 1)).norm();
    poles(i + 1) = pnt(s.polyline.col(i));
    knots(i + 1) = arc;
    mults(i + 1) = (i == 0 || i == np - 1) ? 2 : 1;
  }
  return new Geom_BSplineCurve(poles, knots, mults, 1);
}

namespace {
Eigen::Vector3d unit_tangent(const Geom_BSplineCurve& c, double u, int from, int to) {
  gp_Pnt p;
  gp_Vec v;
  c.LocalD1(u, from, to, p, v);
  const Eigen::Vector3d t = vec(v);
  return t.norm() > 0 ? Eigen::Vector3d(t.normalized()) : t;
}
bool kink(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return a.cross(b).norm() > 1e-7 || a.dot(b) < 0;
}
}  // namespace

std::vector<double> corners(const Geom_BSplineCurve& c, bool closed) {
  std::vector<double> out;
  const int f = c.FirstUKnotIndex(), l = c.LastUKnotIndex();
  const Eigen::Vector3d t0 = unit_tangent(c, c.Knot(f), f, f + 1);
  const Eigen::Vector3d t1 = unit_tangent(c, c.Knot(l), l - 1, l);
  if (!closed || kink(t1, t0)) out.push_back(c.Knot(f));
  for (int i = f + 1; i < l; ++i)
    if (c.Multiplicity(i) >= c.Degree() &&
        kink(unit_tangent(c, c.Knot(i), i - 1, i), unit_tangent(c, c.Knot(i), i, i + 1)))
      out.push_back(c.Knot(i));
  if (!closed) out.push_back(c.Knot(l));
  return out;
}

TopoDS_Wire wire(const Section& s) {
  Handle(Geom_BSplineCurve) c = curve(s);
  // One edge between corners (offsetting needs edges with continuous tangents).
  std::vector<double> cuts{c->FirstParameter()};
  for (int i = c->FirstUKnotIndex() + 1; i < c->LastUKnotIndex(); ++i)
    if (c->Multiplicity(i) >= c->Degree()) cuts.push_back(c->Knot(i));
  cuts.push_back(c->LastParameter());
  // OCCT 7.6 finds no inward offset of a closed wire of one or two edges (a circle): split the
  // pieces until there are at least four.
  while (s.closed && cuts.size() < 5) {
    std::vector<double> finer{cuts.front()};
    for (std::size_t i = 1; i < cuts.size(); ++i) {
      finer.push_back(0.5 * (cuts[i - 1] + cuts[i]));
      finer.push_back(cuts[i]);
    }
    cuts = std::move(finer);
  }
  BRepBuilderAPI_MakeWire mw;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    Handle(Geom_BSplineCurve) piece = Handle(Geom_BSplineCurve)::DownCast(c->Copy());
    if (cuts.size() > 2) piece->Segment(cuts[i], cuts[i + 1]);
    // Straight pieces as lines: OCCT offsets those exactly and fast.
    const bool straight = piece->Degree() == 1 && piece->NbPoles() == 2;
    BRepBuilderAPI_MakeEdge me =
        straight ? BRepBuilderAPI_MakeEdge(piece->StartPoint(), piece->EndPoint())
                 : BRepBuilderAPI_MakeEdge(piece);
    if (!me.IsDone()) throw Error("cannot make an edge of the section curve");
    mw.Add(me.Edge());
    if (!mw.IsDone())
      throw Error("the pieces of the section curve do not join (a gap between its corners)");
  }
  return mw.Wire();
}

double signed_area(const Geom_BSplineCurve& c, const Eigen::Vector3d& normal) {
  const int m = 2000;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d prev = vec(c.Value(c.FirstParameter()));
  for (int i = 1; i <= m; ++i) {
    const double t = c.FirstParameter() + (c.LastParameter() - c.FirstParameter()) * i / m;
    const Eigen::Vector3d p = vec(c.Value(t));
    sum += prev.cross(p);
    prev = p;
  }
  return 0.5 * sum.dot(normal);
}

Nurbs nurbs(const Geom_BSplineCurve& c) {
  Nurbs n;
  n.degree = c.Degree();
  const int np = c.NbPoles();
  n.control_points.resize(3, np);
  n.weights.resize(np);
  for (int i = 1; i <= np; ++i) {
    n.control_points.col(i - 1) = vec(c.Pole(i));
    n.weights[i - 1] = c.Weight(i);
  }
  const TColStd_Array1OfReal& flat = c.KnotSequence();
  n.knots.resize(flat.Length());
  for (int i = flat.Lower(); i <= flat.Upper(); ++i) n.knots[i - flat.Lower()] = flat(i);
  return n;
}

Eigen::Vector3d away_from_material(const Section& s, const Eigen::Vector3d& tangent) {
  const Eigen::Vector3d left = s.plane.normal.cross(tangent);
  const Eigen::Vector3d n = s.material == Side::Left ? -left : left;
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

}  // namespace trueaxis::design::occt
