// trueaxis::solid — a part as a solid, for the safety of a measuring machine: its boundary as a
// triangle mesh (from the STEP file), with the clearance queries that motion planning and
// collision checking ask of it: how far a point (a stylus ball's centre) or a segment (the axis
// of a stylus shaft or of the probe body) is from the part.
//
// Units: mm. Frame: the part's (CAD) coordinates, or wherever transformed() puts it.
// The mesh is the tessellation of the part's faces with a stated deflection (chords within it of
// the true surface): distances are exact for the mesh, and within that deflection of the part.
// Queries walk a bounding-volume hierarchy of axis-aligned boxes (a median split on the longest
// axis, four triangles per leaf), so a query near the part costs a few dozen box tests and
// triangle distances whatever the part's size.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace trueaxis::solid {

class Mesh {
 public:
  Mesh() = default;
  // vertices: 3 × n (mm, finite); triangles: 3 × m vertex indices; faces: the CAD face each
  // triangle belongs to (m ids ≥ 0; empty: each triangle a face of its own). Throws Error for an
  // index out of range, a non-finite vertex or a size mismatch.
  Mesh(Eigen::Matrix3Xd vertices, Eigen::Matrix3Xi triangles, std::vector<int> faces = {});

  // The same mesh moved by x -> t·x (any affine map: a part scaled, turned and moved).
  Mesh transformed(const Eigen::Affine3d& t) const;

  bool empty() const { return tri_.cols() == 0; }
  Eigen::Index triangles() const { return tri_.cols(); }
  const Eigen::Matrix3Xd& vertices() const { return v_; }
  const Eigen::Matrix3Xi& indices() const { return tri_; }
  const Eigen::AlignedBox3d& box() const { return box_; }
  int face_count() const { return static_cast<int>(face_box_.size()); }
  // The CAD face of each triangle.
  const std::vector<int>& triangle_faces() const { return face_; }
  // The bounding box of one CAD face's triangles.
  const Eigen::AlignedBox3d& face_box(int face) const { return face_box_[face]; }

  // The faces whose bounding boxes the plane through `origin` with normal `normal` meets (within
  // 1e-6 mm): one entry per face, true for those (the faces a ball scanning in the plane may
  // touch).
  std::vector<char> faces_crossing(const Eigen::Vector3d& origin,
                                   const Eigen::Vector3d& normal) const;

  // Distance from p to the surface (mm); `limit` when nothing is nearer than limit. Faces for
  // which skip[face] is true are left out (skip may be empty).
  double distance(const Eigen::Vector3d& p, double limit = INFINITY,
                  const std::vector<char>& skip = {}) const;
  // Whether p lies inside the part (the mesh is closed: the tessellation of a solid).
  bool inside(const Eigen::Vector3d& p) const;
  // Distance from the segment a–b to the surface (0 if it crosses it), or `limit`.
  double distance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double limit = INFINITY,
                  const std::vector<char>& skip = {}) const;

  // The highest point of the mesh along the unit direction `up` (max over vertices of v·up).
  double highest(const Eigen::Vector3d& up) const;
  // The same over the triangles whose shadow along `up` comes within `radius` of the shadow of
  // the segment a–b (what a stylus moving from a to b across `up` could meet), each counted with
  // its highest vertex (so never lower than the part under the move); −inf when none does.
  double highest_near(const Eigen::Vector3d& up, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                      double radius) const;

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int first = 0, count = 0;  // a leaf: triangles order_[first .. first + count)
    int left = -1, right = -1;
  };
  void build();
  int build(int first, int count);
  template <class BoxD2, class TriD2>
  double nearest(double limit, const std::vector<char>& skip, BoxD2 box_d2, TriD2 tri_d2) const;
  Eigen::Matrix3Xd v_;
  Eigen::Matrix3Xi tri_;
  std::vector<int> face_;
  std::vector<Eigen::AlignedBox3d> face_box_;
  Eigen::AlignedBox3d box_;
  std::vector<Node> nodes_;
  std::vector<int> order_;
};

// Whether a ball centred at c, touching the faces `skip` leaves in (those a section plane with
// unit normal `plane_normal` does not cross), touches them where their normal lies within 30°
// of the plane: the continuation of the wall it scans, where the CAD file splits a smooth wall
// into faces at or near the plane (CTC 05 at its symmetry plane y = 0), not a face off the
// plane. The contact normal is the gradient of the distance to those faces at c. Callers accept
// such a contact only as deep as kScansOnDepth of the ball's radius (a probe's deflection).
constexpr double kScansOnDepth = 0.5;
bool scans_on(const Mesh& mesh, const Eigen::Vector3d& c, const std::vector<char>& skip,
              const Eigen::Vector3d& plane_normal);

// The part of a STEP file (the union of its solids) as a mesh, with chords within `deflection`
// of its faces (mm, 1e-4 to 1). Read once per file and deflection and kept for the life of the
// process (a batch scans the same part many times). Throws Error naming the file if it cannot be
// read or holds no solid.
std::shared_ptr<const Mesh> load_step(const std::string& path, double deflection = 0.01);

}  // namespace trueaxis::solid
