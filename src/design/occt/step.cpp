// Sections of a STEP solid: OCCT reads the file, cuts the shape with each plane, and the cut's
// edges are chained into closed contours, each joined into one B-spline.
#include <fmt/format.h>

#include <BRepAlgoAPI_Section.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <GCPnts_AbscissaPoint.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <GeomConvert.hxx>
#include <GeomConvert_CompCurveToBSplineCurve.hxx>
#include <GeomLProp_SLProps.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <STEPControl_Reader.hxx>
#include <ShapeAnalysis_FreeBounds.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_HSequenceOfShape.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <gp_Pln.hxx>
#include <optional>

#include "occt.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {
namespace {

constexpr double kJoinTolerance = 1e-4;  // mm: cut edges closer than this are one contour

// One closed contour of a cut as a single B-spline in the wire's order.
Handle(Geom_BSplineCurve) join(const TopoDS_Wire& w) {
  GeomConvert_CompCurveToBSplineCurve joined;
  bool any = false;
  for (BRepTools_WireExplorer ex(w); ex.More(); ex.Next()) {
    const TopoDS_Edge& e = ex.Current();
    double a = 0, b = 0;
    Handle(Geom_Curve) g = BRep_Tool::Curve(e, a, b);
    if (g.IsNull()) continue;
    Handle(Geom_BSplineCurve) bs =
        GeomConvert::CurveToBSplineCurve(new Geom_TrimmedCurve(g, a, b), Convert_TgtThetaOver2);
    if (bs->IsPeriodic()) bs->SetNotPeriodic();
    if (e.Orientation() == TopAbs_REVERSED) bs->Reverse();
    if (!joined.Add(bs, kJoinTolerance, Standard_True))
      throw Error("the cut edges do not join into one contour");
    any = true;
  }
  if (!any) throw Error("a contour of the cut has no curve");
  return joined.BSplineCurve();
}

// The outward unit normal of the face of the solid that passes through p (within 1e-4 mm), or
// nothing if none does.
std::optional<Eigen::Vector3d> outward_normal(const std::vector<TopoDS_Face>& faces,
                                              const gp_Pnt& p) {
  for (const TopoDS_Face& f : faces) {
    BRepExtrema_DistShapeShape dist(BRepBuilderAPI_MakeVertex(p).Vertex(), f);
    if (!dist.IsDone() || dist.Value() > kJoinTolerance) continue;
    Handle(Geom_Surface) surf = BRep_Tool::Surface(f);
    GeomAPI_ProjectPointOnSurf pr(p, surf);
    if (pr.NbPoints() == 0) continue;
    double u = 0, v = 0;
    pr.LowerDistanceParameters(u, v);
    GeomLProp_SLProps props(surf, u, v, 1, 1e-9);
    if (!props.IsNormalDefined()) continue;
    Eigen::Vector3d n = vec(props.Normal().XYZ());
    if (f.Orientation() == TopAbs_REVERSED) n = -n;
    return n;
  }
  return std::nullopt;
}

}  // namespace

Design from_step(const std::string& path, const std::vector<StepSectionRequest>& planes) {
  {
    std::ifstream probe(path);
    if (!probe) throw Error(path + ": cannot open the STEP file");
    std::string head(64, '\0');
    probe.read(head.data(), 64);
    head.resize(static_cast<std::size_t>(probe.gcount()));
    if (head.rfind("ISO-10303-21", 0) != 0)
      throw Error(path + ":1:1: not a STEP file (it must start with ISO-10303-21;)");
  }
  STEPControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
    throw Error(path + ": the STEP file could not be read (syntax or unsupported schema)");
  if (reader.TransferRoots() == 0) throw Error(path + ": the STEP file holds no shape");
  const TopoDS_Shape shape = reader.OneShape();
  TopExp_Explorer solids(shape, TopAbs_SOLID);
  if (!solids.More())
    throw Error(path +
                ": the STEP file holds no solid (only surfaces or wires): sections need "
                "a closed part to know the material side");
  std::vector<TopoDS_Face> faces;
  for (TopExp_Explorer f(solids.Current(), TopAbs_FACE); f.More(); f.Next())
    faces.push_back(TopoDS::Face(f.Current()));

  Design d;
  for (std::size_t q = 0; q < planes.size(); ++q) {
    const StepSectionRequest& rq = planes[q];
    Eigen::Vector3d normal = rq.plane.normal;
    if (!(normal.norm() > 1e-9)) throw Error("section '" + rq.name + "': the normal is zero");
    normal.normalize();
    BRepAlgoAPI_Section cut(shape, gp_Pln(pnt(rq.plane.origin), dir(normal)), Standard_False);
    cut.Approximation(Standard_True);
    cut.Build();
    if (!cut.IsDone()) throw Error(fmt::format("{}: section '{}': the cut failed", path, rq.name));
    Handle(TopTools_HSequenceOfShape) edges = new TopTools_HSequenceOfShape;
    for (TopExp_Explorer e(cut.Shape(), TopAbs_EDGE); e.More(); e.Next())
      edges->Append(e.Current());
    if (edges->IsEmpty())
      throw Error(fmt::format(
          "{}: section '{}': the plane through ({:g}, {:g}, {:g}) misses the "
          "part",
          path, rq.name, rq.plane.origin.x(), rq.plane.origin.y(), rq.plane.origin.z()));
    Handle(TopTools_HSequenceOfShape) wires;
    ShapeAnalysis_FreeBounds::ConnectEdgesToWires(edges, kJoinTolerance, Standard_False, wires);

    std::vector<std::pair<double, Section>> contours;
    for (int w = 1; w <= wires->Length(); ++w) {
      Handle(Geom_BSplineCurve) c;
      try {
        c = join(TopoDS::Wire(wires->Value(w)));
      } catch (const Standard_Failure& e) {
        throw Error(fmt::format("{}: section '{}': {}", path, rq.name, message(e)));
      } catch (const Error& e) {
        throw Error(fmt::format("{}: section '{}': {}", path, rq.name, e.what()));
      }
      if (c->StartPoint().Distance(c->EndPoint()) > kClosureTolerance)
        throw Error(
            fmt::format("{}: section '{}': a contour of the cut is open ({:.3g} mm gap): "
                        "is the solid closed?",
                        path, rq.name, c->StartPoint().Distance(c->EndPoint())));
      if (signed_area(*c, normal) < 0) c->Reverse();
      Section s;
      s.plane = {rq.plane.origin, normal};
      s.closed = true;
      s.nurbs = nurbs(*c);
      // Material: the outward normal of the part's face under the cut, at points of the
      // contour, against the direction to the curve's left. (Ray-casting point classification
      // is not used: OCCT 7.6 misclassifies points inside some holes.)
      int left_in = 0, left_out = 0;
      for (int k = 0; k < 7; ++k) {
        const double t =
            c->FirstParameter() + (c->LastParameter() - c->FirstParameter()) * (k + 0.37) / 7;
        gp_Pnt p;
        gp_Vec d1;
        c->D1(t, p, d1);
        const Eigen::Vector3d left = normal.cross(vec(d1)).normalized();
        if (const auto out = outward_normal(faces, p)) {
          const double dot = out->dot(left);
          if (dot > 0.1) ++left_out;
          if (dot < -0.1) ++left_in;
        }
      }
      s.material = left_in > left_out ? Side::Left : Side::Right;
      GeomAdaptor_Curve ad(c);
      contours.emplace_back(GCPnts_AbscissaPoint::Length(ad), std::move(s));
    }
    std::stable_sort(contours.begin(), contours.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    for (std::size_t k = 0; k < contours.size(); ++k) {
      Section s = std::move(contours[k].second);
      s.name = contours.size() == 1 ? rq.name : fmt::format("{}.{}", rq.name, k + 1);
      d.sections.push_back(std::move(s));
    }
  }
  return d;
}

}  // namespace trueaxis::design::occt
