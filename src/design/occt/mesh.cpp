// The part of a STEP file as triangles: Open CASCADE's incremental mesher on the union of its
// solids, each face's triangulation gathered in the part's frame, turned to face out of the part.
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Poly_Triangulation.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>

#include "occt.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {

void step_mesh(const std::string& path, double deflection, detail::MeshData& out) {
  StepCut info;
  const StepPart part = read_step(path, StepCutOptions{}, info);
  // Chords within `deflection` of every face, and no more than 0.3 rad of turn per triangle.
  BRepMesh_IncrementalMesh mesher(part.shape, deflection, false, 0.3, false);
  if (!mesher.IsDone()) throw Error(path + ": the part could not be tessellated");
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  std::vector<int> faces;
  int face = 0;
  for (TopExp_Explorer f(part.shape, TopAbs_FACE); f.More(); f.Next(), ++face) {
    const TopoDS_Face& F = TopoDS::Face(f.Current());
    TopLoc_Location loc;
    Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(F, loc);
    if (tri.IsNull()) continue;
    const int base = static_cast<int>(v.size());
    const gp_Trsf trsf = loc.Transformation();
    for (int i = 1; i <= tri->NbNodes(); ++i) v.push_back(vec(tri->Node(i).Transformed(trsf)));
    const bool reversed = F.Orientation() == TopAbs_REVERSED;
    for (int i = 1; i <= tri->NbTriangles(); ++i) {
      int a = 0, b = 0, c = 0;
      tri->Triangle(i).Get(a, b, c);
      if (reversed) std::swap(b, c);
      t.emplace_back(base + a - 1, base + b - 1, base + c - 1);
      faces.push_back(face);
    }
  }
  if (t.empty()) throw Error(path + ": the part's faces gave no triangles");
  out.vertices.resize(3, static_cast<Eigen::Index>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) out.vertices.col(static_cast<Eigen::Index>(i)) = v[i];
  out.triangles.resize(3, static_cast<Eigen::Index>(t.size()));
  for (std::size_t i = 0; i < t.size(); ++i) out.triangles.col(static_cast<Eigen::Index>(i)) = t[i];
  out.faces = std::move(faces);
}

}  // namespace trueaxis::design::occt
