// Private: the 4 × 4 × 4 node sum of a tricubic evaluation, portable and, on x86-64 processors
// that have them, with AVX2 and FMA (chosen once at run time).
#pragma once

#include <Eigen/Core>

namespace trueaxis::map::detail {

// v[q] = Σ_ijk wx[i]·wy[j]·wz[k]·row0[dy·j + dz·k + 3i + q] for the 3 components q: `row0` is
// the first node's first component, dy and dz the strides (doubles) between rows along y and z;
// the 4 nodes along x are 12 adjacent doubles. The weights of axis a are polynomials in t[a]:
// w[q] = Σ_p poly[a][4p + q]·t[a]^p.
using TricubicSum = void (*)(const double* row0, Eigen::Index dy, Eigen::Index dz,
                             const double* const poly[3], const double t[3], double* v);

void tricubic_sum_portable(const double* row0, Eigen::Index dy, Eigen::Index dz,
                           const double* const poly[3], const double t[3], double* v);
// The AVX2 + FMA version, or nullptr where the processor (or the compiler) lacks them.
TricubicSum tricubic_sum_avx2();
// The one evaluations use: the AVX2 version where available, else the portable one.
TricubicSum tricubic_sum();

}  // namespace trueaxis::map::detail
