// trueaxis::geometry — a plane triangulation of scattered stations and the piecewise-linear
// surface over it: to draw the height field of a surface measured along lines (a surface
// plate's Union Jack or grid) as a contour map.
//
// Units: any, the same for x and y (mm in the library); values in their own unit.
#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

namespace trueaxis::geometry {

// The Delaunay triangulation of points (2 × n) by Bowyer–Watson insertion (A. Bowyer, Computing
// Dirichlet tessellations, The Computer Journal 24(2), 1981; D. F. Watson, Computing the
// n-dimensional Delaunay tessellation with application to Voronoi polytopes, same issue).
// Triangles are index triples, counter-clockwise; together they cover the convex hull. Points
// closer than 1e-9 of the extent to an earlier one are left out (a station measured on two lines
// is one point). O(n²) in the worst case: meant for the tens to a few thousand stations of a
// surface, not for clouds. Fewer than three points not all on one line give no triangle.
std::vector<std::array<int, 3>> delaunay(const Eigen::Matrix2Xd& points);

// Where the piecewise-linear surface over `triangles` (values at the points) crosses `level`:
// one segment (its two ends) per triangle it crosses. Triangles with a non-finite value are
// skipped.
std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> contour_segments(
    const Eigen::Matrix2Xd& points, const Eigen::VectorXd& values,
    const std::vector<std::array<int, 3>>& triangles, double level);

// The piecewise-linear surface's value at each query point (2 × m): linear within the triangle
// that holds it, NaN outside the triangulation.
Eigen::VectorXd interpolate_linear(const Eigen::Matrix2Xd& points, const Eigen::VectorXd& values,
                                   const std::vector<std::array<int, 3>>& triangles,
                                   const Eigen::Matrix2Xd& queries);

}  // namespace trueaxis::geometry
