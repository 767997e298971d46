// Private to fit.cpp: what the fits share with their extended-precision polish (the axis frame,
// the cone/cylinder residual) and the polish itself: Newton steps in 80-bit arithmetic from a
// double-precision solution near the minimum. Kept in its own file because its Eigen code in
// `long double` is most of the fits' compile time. Units: mm and rad.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "sphere_kernels.hpp"

namespace trueaxis::geometry::detail {

// An orthonormal, right-handed basis whose third column is `w` (unit).
Eigen::Matrix3d basis(const Eigen::Vector3d& w);

// ---- cylinder and cone: an axis through x0 along unit a ---------------------------------------

struct AxisState {
  Eigen::Vector3d x0 = Eigen::Vector3d::Zero(), a = Eigen::Vector3d::UnitZ();
  double r = 0;    // radius at x0 (cylinder: everywhere)
  double psi = 0;  // cone: half apex angle (signed: > 0 opens towards +a)
};

// One point's orthogonal distance to a cone (ψ = 0: a cylinder) from its coordinates x, y, z
// (mm) in the axis frame, given r at the frame's origin and cos ψ, sin ψ, tan ψ; with `d`, its
// derivatives with respect to the local correction (x0 in the plane, the axis' tilt, r, and ψ
// for a cone). One formula for the fit (double) and its polish (80-bit).
template <class T>
T axis_residual(T x, T y, T z, T r0, T C, T S, T Tn, bool cone, T* d) {
  using std::sqrt;
  const T rho = sqrt(x * x + y * y);  // not hypot: mm-scale values cannot overflow; 3-5x cheaper
  const T gap = rho - r0 - z * Tn;    // radial gap at the point's axial position
  if (d) {
    const T xr = x / rho, yr = y / rho;  // two divisions (x87 ones are slow in the 80-bit pass)
    d[0] = -C * xr;
    d[1] = -C * yr;
    d[2] = C * (-xr * z - Tn * x);
    d[3] = C * (-yr * z - Tn * y);
    d[4] = -C;
    if (cone) d[5] = -z / C - gap * S;
  }
  return gap * C;
}

// Polishes a circle fit (centre and radius in the coordinates of q, 2 × n) in place.
void polish_circle(const Eigen::Matrix2Xd& q, Eigen::Vector2d& centre, double& radius);

// Polishes a sphere fit (centre and radius in the coordinates of q, whose largest absolute
// coordinate is `largest`) in place.
void polish_sphere(const Coords& q, const SphereKernels& kernels, double largest,
                   Eigen::Vector3d& centre, double& radius);

// Polishes a cylinder (cone: `cone`) fit from s0 near the minimum; `extent` is the cloud's size
// (mm) and `settled` (if given) says whether the last Newton step was below 1e-10 of it.
AxisState polish_axis(const Eigen::Matrix3Xd& p, const Eigen::Vector3d& centroid,
                      const AxisState& s0, bool cone, double extent, bool* settled);

}  // namespace trueaxis::geometry::detail
