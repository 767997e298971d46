// trueaxis::sim — a manufactured part that differs from its design: what a scanning CMM meets.
//
// The real part is the design moved and distorted by, in this order: local form deviations per
// section (smooth bumps along the surface normal, and form noise), then a uniform scale about a
// point, a scale along one direction about the same point, a rotation about the design's centroid
// (degrees about x, then y, then z: R = Rz·Ry·Rx) and a translation (mm).
//
// Each section's true contour is where the real part meets the design's section plane: with the
// part's solid, the exact cut of the moved solid; without, the distorted curve projected into the
// plane (exact for rotations about the plane's normal and for translations; for a part whose
// walls are perpendicular to the plane, to first order in the tilt otherwise).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "trueaxis/design/design.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::sim {

// A smooth bump on one section: a raised cosine of the given full width (mm of arc), centred at
// `arc` (mm from the curve's start), `height` mm along the outward normal (negative: a dent).
struct Bump {
  std::string section;
  double arc = 0, height = 0, width = 0;
};

struct PartDeviation {
  double scale = 1;                                            // uniform, about scale_about
  bool scale_about_given = false;                              // else the design's centroid
  Eigen::Vector3d scale_about = Eigen::Vector3d::Zero();       // mm
  Eigen::Vector3d scale_direction = Eigen::Vector3d::UnitX();  // unit
  double directional_scale = 1;                                // along scale_direction
  Eigen::Vector3d rotation_deg = Eigen::Vector3d::Zero();      // about x, y, z, at the centroid
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();       // mm
  std::vector<Bump> bumps;
  double noise = 0;  // form noise: standard deviation along the normal (mm), smooth over 2 mm
  std::uint64_t seed = 1;
};

struct Part {
  design::Design design;
  PartDeviation deviation;
  // Throws Error naming the field: scales in [0.5, 2], rotations within ±45°, translations
  // within ±1000 mm, bumps on existing sections with |height| ≤ 10 mm and widths in (0, 10000]
  // mm, noise in [0, 1] mm.
  void validate() const;
};

// Throws Error unless the bump lies on a section of `design`, |height| ≤ 10 mm, width in
// (0, 10000] mm and its arc position is a number.
void validate(const Bump& bump, const design::Design& design);

// Centroid of the design's section curves (arc-length weighted), mm.
Eigen::Vector3d centroid(const design::Design& d);

// The rigid-and-scale part of the deviation: x_real = T · x_design.
Eigen::Affine3d transform(const Part& part);

// The true contour of `section` (a section of part.design) as a polyline ready for the probe:
// points at most `spacing` mm apart, every corner of the curve among them, and chords within
// 0.01 µm of the part's curve. When the design names its solid (a STEP file), the contour is the
// exact section of the moved solid in the section's plane (the contour of that cut nearest to the
// moved design curve), with the local form deviations along its normals; otherwise the design
// curve moved and projected into its plane, which is exact for moves within the plane.
// Throws Error for a space-curve section.
Contour true_contour(const Part& part, const design::Section& section, double spacing = 0.1);

// The same for a space-curve section: the real curve and its surface normals (the part's
// transformation applied to both), every `spacing` mm.
SpaceCurve true_space_curve(const Part& part, const design::Section& section, double spacing = 0.1);

}  // namespace trueaxis::sim
