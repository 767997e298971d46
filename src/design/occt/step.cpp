// Sections of a STEP part: OCCT reads the file and its stated tolerance, takes the union of its
// solids, cuts it with each plane, and chains the cut's edges into closed contours, each joined
// into one B-spline. Each plane succeeds or fails on its own, with the reason.
#include <fmt/format.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRepAlgoAPI_Common.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepAlgoAPI_Section.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_GTransform.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepGProp.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GCPnts_AbscissaPoint.hxx>
#include <GProp_GProps.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <GeomConvert.hxx>
#include <GeomConvert_CompCurveToBSplineCurve.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <STEPConstruct_UnitContext.hxx>
#include <STEPControl_Reader.hxx>
#include <ShapeAnalysis_FreeBounds.hxx>
#include <StepData_StepModel.hxx>
#include <StepGeom_GeomRepContextAndGlobUnitAssCtxAndGlobUncertaintyAssCtx.hxx>
#include <StepRepr_GlobalUncertaintyAssignedContext.hxx>
#include <StepRepr_GlobalUnitAssignedContext.hxx>
#include <StepRepr_Representation.hxx>
#include <StepShape_SolidModel.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_HSequenceOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <gp_GTrsf.hxx>
#include <gp_Pln.hxx>
#include <gp_Trsf.hxx>
#include <map>
#include <mutex>

#include "occt.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {
namespace {

// The tolerance the file states for its solids' geometry (ISO 10303-41
// uncertainty_measure_with_unit in the solid representation's global_uncertainty_assigned_context),
// in mm; the largest if several solids state different ones. Nothing if none is stated.
std::optional<double> file_tolerance(const STEPControl_Reader& reader) {
  Handle(StepData_StepModel) model = reader.StepModel();
  if (model.IsNull()) return std::nullopt;
  std::optional<double> out;
  for (int i = 1; i <= model->NbEntities(); ++i) {
    Handle(StepRepr_Representation) rep =
        Handle(StepRepr_Representation)::DownCast(model->Value(i));
    if (rep.IsNull() || rep->Items().IsNull()) continue;
    bool solid = false;
    for (int k = 1; k <= rep->NbItems() && !solid; ++k)
      solid = !rep->ItemsValue(k).IsNull() &&
              rep->ItemsValue(k)->IsKind(STANDARD_TYPE(StepShape_SolidModel));
    if (!solid) continue;
    auto ctx = Handle(StepGeom_GeomRepContextAndGlobUnitAssCtxAndGlobUncertaintyAssCtx)::DownCast(
        rep->ContextOfItems());
    if (ctx.IsNull() || ctx->GlobalUncertaintyAssignedContext().IsNull()) continue;
    STEPConstruct_UnitContext units;
    if (units.ComputeFactors(ctx->GlobalUnitAssignedContext()) != 0) continue;
    units.ComputeTolerance(ctx->GlobalUncertaintyAssignedContext());
    if (!units.HasUncertainty()) continue;
    const double mm = units.Uncertainty() * units.LengthFactor();
    if (std::isfinite(mm) && mm > 0) out = std::max(out.value_or(0.0), mm);
  }
  return out;
}

}  // namespace

StepPart read_step(const std::string& path, const StepCutOptions& o, StepCut& out) {
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
  const TopoDS_Shape all = reader.OneShape();
  std::vector<TopoDS_Shape> solids;
  for (TopExp_Explorer e(all, TopAbs_SOLID); e.More(); e.Next()) solids.push_back(e.Current());
  if (solids.empty())
    throw Error(path +
                ": the STEP file holds no solid (only surfaces or wires): sections need "
                "a closed part to know the material side");
  out.solids = static_cast<int>(solids.size());
  out.file_tolerance = file_tolerance(reader);
  StepPart p;
  p.join = std::clamp(out.file_tolerance.value_or(o.min_join), o.min_join, o.max_join);
  out.join_tolerance = p.join;
  if (out.file_tolerance && *out.file_tolerance > o.max_join)
    out.notes.push_back(fmt::format(
        "the file states a tolerance of {:.4g} mm; cut edges are joined across gaps of at most "
        "{:g} mm",
        *out.file_tolerance, o.max_join));
  if (solids.size() == 1) {
    p.shape = solids.front();
  } else {
    // The part is the union of its solids. Say which of them share volume (those that only
    // touch, like a boss on a face, are the common case and need no word).
    std::vector<Bnd_Box> boxes(solids.size());
    for (std::size_t i = 0; i < solids.size(); ++i) BRepBndLib::Add(solids[i], boxes[i]);
    for (std::size_t i = 0; i < solids.size(); ++i)
      for (std::size_t j = i + 1; j < solids.size(); ++j) {
        if (boxes[i].IsOut(boxes[j])) continue;
        BRepAlgoAPI_Common common(solids[i], solids[j]);
        if (!common.IsDone()) continue;
        GProp_GProps g;
        BRepGProp::VolumeProperties(common.Shape(), g);
        if (g.Mass() > 1e-6)
          out.notes.push_back(fmt::format(
              "solids {} and {} of the file overlap ({:.4g} mm³ in common): the part is taken as "
              "their union",
              i + 1, j + 1, g.Mass()));
      }
    TopTools_ListOfShape args, tools;
    args.Append(solids.front());
    for (std::size_t i = 1; i < solids.size(); ++i) tools.Append(solids[i]);
    BRepAlgoAPI_Fuse fuse;
    fuse.SetArguments(args);
    fuse.SetTools(tools);
    fuse.SetFuzzyValue(p.join);
    fuse.Build();
    if (!fuse.IsDone())
      throw Error(
          fmt::format("{}: the union of its {} solids could not be formed", path, solids.size()));
    p.shape = fuse.Shape();
    out.notes.push_back(
        fmt::format("the file holds {} solids; the part is their union", solids.size()));
  }
  BRepBndLib::Add(p.shape, p.box);
  return p;
}

namespace {

// The planar faces of the part that lie in the plane (within the join tolerance).
std::vector<TopoDS_Face> faces_in_plane(const TopoDS_Shape& shape, const gp_Pln& plane,
                                        double tol) {
  std::vector<TopoDS_Face> out;
  for (TopExp_Explorer f(shape, TopAbs_FACE); f.More(); f.Next()) {
    BRepAdaptor_Surface s(TopoDS::Face(f.Current()), false);
    if (s.GetType() != GeomAbs_Plane) continue;
    const gp_Pln fp = s.Plane();
    if (!fp.Axis().IsParallel(plane.Axis(), 1e-9)) continue;
    if (plane.Distance(fp.Location()) > tol) continue;
    out.push_back(TopoDS::Face(f.Current()));
  }
  return out;
}

// The face (of `faces`) whose boundary the closed curve runs along (every one of 16 points of it
// within `tol` of that face), or nothing.
const TopoDS_Face* along_face(const Geom_BSplineCurve& c, const std::vector<TopoDS_Face>& faces,
                              double tol) {
  for (const TopoDS_Face& f : faces) {
    bool all = true;
    for (int k = 0; k < 16 && all; ++k) {
      const double t =
          c.FirstParameter() + (c.LastParameter() - c.FirstParameter()) * (k + 0.5) / 16;
      BRepExtrema_DistShapeShape dist(BRepBuilderAPI_MakeVertex(c.Value(t)).Vertex(), f);
      all = dist.IsDone() && dist.Value() <= tol;
    }
    if (all) return &f;
  }
  return nullptr;
}

// One closed contour of a cut as a single B-spline in the wire's order; `gap` receives the largest
// gap between consecutive edges and between the last edge and the first (mm), which are closed.
Handle(Geom_BSplineCurve) join(const TopoDS_Wire& w, double tol, double& gap) {
  GeomConvert_CompCurveToBSplineCurve joined;
  bool any = false;
  gap = 0;
  gp_Pnt last;
  for (BRepTools_WireExplorer ex(w); ex.More(); ex.Next()) {
    const TopoDS_Edge& e = ex.Current();
    double a = 0, b = 0;
    Handle(Geom_Curve) g = BRep_Tool::Curve(e, a, b);
    if (g.IsNull()) continue;
    Handle(Geom_BSplineCurve) bs =
        GeomConvert::CurveToBSplineCurve(new Geom_TrimmedCurve(g, a, b), Convert_TgtThetaOver2);
    if (bs->IsPeriodic()) bs->SetNotPeriodic();
    if (e.Orientation() == TopAbs_REVERSED) bs->Reverse();
    if (bs->StartPoint().Distance(bs->EndPoint()) < 1e-12 && !BRep_Tool::IsClosed(e) &&
        GCPnts_AbscissaPoint::Length(GeomAdaptor_Curve(bs)) < tol)
      continue;  // a sliver edge shorter than the tolerance
    if (any) {
      const double d = last.Distance(bs->StartPoint());
      if (d > tol)
        throw Error(fmt::format(
            "the cut edges leave a gap of {:.4g} mm at ({:.3f}, {:.3f}, {:.3f}), more than the "
            "{:.4g} mm they are joined across",
            d, last.X(), last.Y(), last.Z(), tol));
      gap = std::max(gap, d);
      if (d > 0) {
        // Close the gap: the new piece starts where the last ended (its first pole moves by d).
        bs->SetPole(1, last);
      }
    }
    if (!joined.Add(bs, std::max(tol, 1e-7), Standard_True))
      throw Error(
          fmt::format("the cut edges do not join into one contour near ({:.3f}, {:.3f}, "
                      "{:.3f})",
                      last.X(), last.Y(), last.Z()));
    last = bs->EndPoint();
    any = true;
  }
  if (!any) throw Error("a contour of the cut has no curve");
  Handle(Geom_BSplineCurve) c = joined.BSplineCurve();
  const double closure = c->StartPoint().Distance(c->EndPoint());
  if (closure > tol)
    throw Error(fmt::format(
        "a contour of the cut does not close: its ends at ({:.3f}, {:.3f}, {:.3f}) and ({:.3f}, "
        "{:.3f}, {:.3f}) are {:.4g} mm apart, more than the {:.4g} mm the edges are joined "
        "across",
        c->StartPoint().X(), c->StartPoint().Y(), c->StartPoint().Z(), c->EndPoint().X(),
        c->EndPoint().Y(), c->EndPoint().Z(), closure, tol));
  if (closure > 0) c->SetPole(c->NbPoles(), c->Pole(1));
  gap = std::max(gap, closure);
  return c;
}

// The closed contour as a polygon in plane coordinates (for nesting).
std::vector<Eigen::Vector2d> polygon(const Geom_BSplineCurve& c, const Eigen::Vector3d& e1,
                                     const Eigen::Vector3d& e2) {
  constexpr int m = 2000;
  std::vector<Eigen::Vector2d> out;
  out.reserve(m);
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector3d p =
        vec(c.Value(c.FirstParameter() + (c.LastParameter() - c.FirstParameter()) * i / m));
    out.emplace_back(p.dot(e1), p.dot(e2));
  }
  return out;
}

// Winding number of a closed polygon about q (non-zero: q is inside).
int winding(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& q) {
  int w = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[(i + 1) % poly.size()];
    const double cross = (b.x() - a.x()) * (q.y() - a.y()) - (q.x() - a.x()) * (b.y() - a.y());
    if (a.y() <= q.y()) {
      if (b.y() > q.y() && cross > 0) ++w;
    } else if (b.y() <= q.y() && cross < 0) {
      --w;
    }
  }
  return w;
}

struct Contour {
  Handle(Geom_BSplineCurve) curve;
  double length = 0, gap = 0;
  std::vector<Eigen::Vector2d> poly;
};

// The sections of one plane (throws Error with the reason when the plane gives none).
std::vector<Section> cut(const StepPart& part, const StepSectionRequest& rq,
                         std::vector<std::string>& refused) {
  Eigen::Vector3d normal = rq.plane.normal;
  if (!(normal.norm() > 1e-9)) throw Error("the plane's normal is zero");
  normal.normalize();
  const gp_Pln plane(pnt(rq.plane.origin), dir(normal));
  // The part's extent along the normal, from its box corners (for the message of a miss).
  double lo = INFINITY, hi = -INFINITY;
  {
    double x0, y0, z0, x1, y1, z1;
    part.box.Get(x0, y0, z0, x1, y1, z1);
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d c(k & 1 ? x1 : x0, k & 2 ? y1 : y0, k & 4 ? z1 : z0);
      lo = std::min(lo, (c - rq.plane.origin).dot(normal));
      hi = std::max(hi, (c - rq.plane.origin).dot(normal));
    }
  }
  const std::vector<TopoDS_Face> flat = faces_in_plane(part.shape, plane, part.join);
  BRepAlgoAPI_Section section(part.shape, plane, Standard_False);
  section.Approximation(Standard_True);
  section.Build();
  if (!section.IsDone()) throw Error("Open CASCADE could not cut the part with this plane");
  Handle(TopTools_HSequenceOfShape) edges = new TopTools_HSequenceOfShape;
  for (TopExp_Explorer e(section.Shape(), TopAbs_EDGE); e.More(); e.Next())
    edges->Append(e.Current());
  if (edges->IsEmpty()) {
    if (lo > 0 || hi < 0)
      throw Error(fmt::format(
          "the plane misses the part: the part lies {:.3f} to {:.3f} mm from it along its normal",
          lo, hi));
    throw Error("the plane crosses the part's bounding box but cuts no face of the part");
  }
  Handle(TopTools_HSequenceOfShape) wires;
  ShapeAnalysis_FreeBounds::ConnectEdgesToWires(edges, part.join, Standard_False, wires);

  const Eigen::Vector3d a =
      std::abs(normal.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e1 = (a - a.dot(normal) * normal).normalized(), e2 = normal.cross(e1);
  std::vector<Contour> contours;
  std::vector<std::string> on_face;  // contours refused: they run along a face in the plane
  for (int w = 1; w <= wires->Length(); ++w) {
    Contour c;
    c.curve = join(TopoDS::Wire(wires->Value(w)), part.join, c.gap);
    c.length = GCPnts_AbscissaPoint::Length(GeomAdaptor_Curve(c.curve));
    if (c.length < 10 * part.join) continue;  // the plane grazes the part: a point, no contour
    // The section lies in the plane: the curve's poles are put there exactly (an approximated
    // intersection curve may leave them some micrometres off; the curve moves only along the
    // normal, by as much).
    for (int k = 1; k <= c.curve->NbPoles(); ++k) {
      const Eigen::Vector3d q = vec(c.curve->Pole(k));
      c.curve->SetPole(k, pnt(q - (q - rq.plane.origin).dot(normal) * normal));
    }
    if (const TopoDS_Face* f = along_face(*c.curve, flat, part.join)) {
      GProp_GProps g;
      BRepGProp::SurfaceProperties(*f, g);
      const Eigen::Vector3d at = vec(g.CentreOfMass());
      on_face.push_back(fmt::format(
          "a contour of {:.1f} mm runs along the edge of a flat face of the part that lies in the "
          "plane (the face around ({:.3f}, {:.3f}, {:.3f})): the ball cannot hold contact there "
          "without touching that face; cut the part at least the tip radius above or below it",
          c.length, at.x(), at.y(), at.z()));
      continue;
    }
    if (signed_area(*c.curve, normal) < 0) c.curve->Reverse();
    c.poly = polygon(*c.curve, e1, e2);
    contours.push_back(std::move(c));
  }
  if (contours.empty() && !on_face.empty())
    throw Error(on_face.size() == 1
                    ? on_face.front()
                    : fmt::format("the plane lies on flat faces of the part: all {} contours of "
                                  "the cut run along their edges ({})",
                                  on_face.size(), on_face.front()));
  // Material side by nesting: a contour inside an even number of others bounds material on its
  // inside (an outline, or an island in a hole), inside an odd number it bounds a hole. With
  // every contour counter-clockwise seen from the normal, the inside is on the left.
  std::vector<int> depth(contours.size(), 0);
  for (std::size_t i = 0; i < contours.size(); ++i)
    for (std::size_t j = 0; j < contours.size(); ++j)
      if (i != j && winding(contours[j].poly, contours[i].poly.front()) != 0) ++depth[i];
  std::vector<std::size_t> order(contours.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    return contours[x].length > contours[y].length;
  });
  std::vector<Section> out;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Contour& c = contours[order[k]];
    Section s;
    s.name = order.size() == 1 ? rq.name : fmt::format("{}.{}", rq.name, k + 1);
    s.plane = {rq.plane.origin, normal};
    s.closed = true;
    s.nurbs = nurbs(*c.curve);
    s.material = depth[order[k]] % 2 == 0 ? Side::Left : Side::Right;
    s.joined_gap = c.gap;
    out.push_back(std::move(s));
  }
  refused = std::move(on_face);
  return out;
}

}  // namespace

Design moved_sections(const std::string& path, const double (&map)[12], const Plane& plane) {
  // The part is read once per process (a batch cuts the same part for every simulated piece).
  static std::mutex mutex;
  static std::map<std::string, StepPart> parts;
  StepPart part;
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = parts.find(path);
    if (it == parts.end()) {
      StepCut info;
      it = parts.emplace(path, read_step(path, StepCutOptions{}, info)).first;
    }
    part = it->second;
  }
  // A rigid move with a uniform scale keeps the exact surfaces; any other affine map turns
  // them into B-splines first.
  const Eigen::Matrix3d A =
      Eigen::Map<const Eigen::Matrix<double, 3, 4, Eigen::RowMajor>>(map).leftCols<3>();
  const double det = A.determinant();
  const double k = std::cbrt(std::abs(det));
  const bool similar =
      det > 0 && (A.transpose() * A - k * k * Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <
                     1e-12 * k * k;
  if (similar) {
    gp_Trsf t;
    t.SetValues(map[0], map[1], map[2], map[3], map[4], map[5], map[6], map[7], map[8], map[9],
                map[10], map[11]);
    part.shape = BRepBuilderAPI_Transform(part.shape, t, true).Shape();
  } else {
    gp_GTrsf g;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) g.SetValue(r + 1, c + 1, map[4 * r + c]);
      g.SetValue(r + 1, 4, map[4 * r + 3]);
    }
    part.shape = BRepBuilderAPI_GTransform(part.shape, g, true).Shape();
  }
  part.box = Bnd_Box();
  BRepBndLib::Add(part.shape, part.box);
  std::vector<std::string> refused;
  Design out;
  out.sections = cut(part, {"", plane}, refused);
  return out;
}

StepCut cut_step(const std::string& path, const std::vector<StepSectionRequest>& planes,
                 const StepCutOptions& options) {
  StepCut out;
  const StepPart part = read_step(path, options, out);
  for (const StepSectionRequest& rq : planes) {
    try {
      std::vector<std::string> refused;
      for (Section& s : cut(part, rq, refused)) out.design.sections.push_back(std::move(s));
      for (std::string& why : refused) out.failures.push_back({rq.name, rq.plane, std::move(why)});
    } catch (const Error& e) {
      out.failures.push_back({rq.name, rq.plane, e.what()});
    } catch (const Standard_Failure& e) {
      out.failures.push_back({rq.name, rq.plane, "Open CASCADE failed: " + message(e)});
    }
  }
  return out;
}

}  // namespace trueaxis::design::occt
