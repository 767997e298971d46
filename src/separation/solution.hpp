// Private: what the parts of straightness separation hand each other. A method (a recurrence or
// the least-squares solve) gives a Raw solution on its own grids; the reference (least-squares
// line, minimum zone, parabola gauge) is applied to it in place; the uncertainty propagation reads
// the grids and, for the least-squares solve, the solver's factorisation. Each part is a file of
// its own:
//   layout.cpp                  the least-squares design and the observability of a probe layout
//   lsq_solve.cpp               the least-squares solve (banded QR, or direct without redundancy)
//   recurrences.cpp             the two- and three-point recurrences
//   reference.cpp               the reference lines and the parabola gauge
//   uncertainty_lsq.cpp         uncertainties from the least-squares covariance
//   uncertainty_recurrence.cpp  uncertainties propagated through a recurrence
//   uncertainty_direct.cpp      uncertainties of the direct least-squares solve
//   separation.cpp              the driver: checks, method, reference, uncertainties, report
#pragma once

#include <Eigen/Core>
#include <future>
#include <memory>
#include <optional>
#include <vector>

#include "design.hpp"
#include "prefault.hpp"
#include "trueaxis/separation/separation.hpp"

namespace trueaxis::separation::detail {

class BandedLsq;

// A solution before the reference is applied, on its own grids.
struct Raw {
  Eigen::VectorXd xw, w;      // workpiece grid and values (mm)
  Eigen::VectorXd xg, g;      // station grid, guide (mm)
  Eigen::VectorXd xt, theta;  // pitch grid and values (rad); empty if not modelled
  bool parabola_free = false;
  // xg is known to be strictly increasing (the checked data's stations): its range is its ends.
  bool xg_increasing = false;
};

// Long profiles have independent passes (workpiece and guide, copies) run on two cores.
constexpr Eigen::Index kTwoCorePoints = 50000;

inline std::launch policy_for(const Raw& r) {
  return r.g.size() >= kTwoCorePoints ? std::launch::async : std::launch::deferred;
}

// Everything the uncertainty propagation needs from a least-squares solve. The banded solve
// leaves its factorisation (engine); the direct solve of a layout without redundancy has none
// (dof 0), and its uncertainties, which depend on the grids alone, are under way on another core
// when wanted (propagation, into uw, ug, ut, from the stations).
struct LsqState {
  Design D;
  std::unique_ptr<detail::BandedLsq> engine;
  double h = 0;
  double ssr = 0;
  long dof = 0;
  Eigen::VectorXd uw, ug, ut;
  std::future<void> propagation;
  long rows = 0;  // rows of the solved system (the residual's rms divides by them)

  LsqState();
  ~LsqState();  // out of line: BandedLsq is complete only where the system is solved
};

// Workpiece position j (a whole number) of a least-squares grid starting at the first station x0:
// the one formula for every copy of the grid (the direct solve's uncertainties form their own,
// and must agree with the solve's to the last bit).
inline double workpiece_position(double x0, double j, double h) {
  return x0 + j * h;
}

// --- lsq_solve.cpp
// The least-squares solution by the banded QR of BandedLsq, with iterative refinement; leaves the
// factorisation and the residual in st for the uncertainties. Throws Error for an unobservable
// layout or a rank-deficient system.
Raw solve_lsq(const ProbeData& data, const Options& opt, LsqState& st);
// The least-squares solution of a direct_layout (no redundancy) by its recurrence.
Raw solve_lsq_direct(const ProbeData& data, const Options& opt);

// --- recurrences.cpp
// The arrays a recurrence (two- or three-point) fills for n stations, sized but not set, and their
// memory regions (for Prefault).
Raw recurrence_arrays(Method m, long n);
std::vector<Prefault::Region> regions_of(const Raw& r);
// The two-point recurrence (probes at 0 and 1 step) and the three-point one (0, 1, 2 steps;
// JPH0464003B2 eqs. 12–17), into r as sized by recurrence_arrays. Throw Error for another layout.
void two_point(const ProbeData& d, Raw& r);
void three_point(const ProbeData& d, std::optional<double> zero_difference, Raw& r);

// --- reference.cpp
// Coordinates for the parabola gauge: t = (x - xc)/L.
struct Scale {
  double xc = 0, L = 1;
};

// The scale of grid x: its mid-range and half range (from its ends when it is known to increase).
Scale scale_of(Eigen::Ref<const Eigen::VectorXd> x, bool increasing = false);

// A profile's sums in the parabola's coordinate t = (x − x_c)/L: Σtᵏ (k ≤ 4) and Σtᵏ·y (k ≤ 2).
struct Moments {
  double t[5] = {0, 0, 0, 0, 0}, ty[3] = {0, 0, 0};
};

// A profile's moments (y at the points x) on scale s.
Moments moments_of(Eigen::Ref<const Eigen::VectorXd> x, Eigen::Ref<const Eigen::VectorXd> y,
                   const Scale& s);

// Coefficients e of the functional φ_K = e_0 + e_1·t_K + e_2·t_K² with φᵀg = the coefficient of t²
// in the LS fit of g by {1, t, t²} (t = (x − x_c)/L): e = G⁻¹·(0, 0, 1), G = TᵀT from the moments
// of t.
Eigen::Vector3d quad_coefficients_from(const Moments& m);

// The least-squares straightness of the workpiece and guide as referenced, where apply_reference
// found it on the way (the ls reference); NaN otherwise.
struct LsWidths {
  double w = std::numeric_limits<double>::quiet_NaN(), g = w;
};

// Applies the ls / min-zone reference to r in place (the parabola gauge first, if free); returns
// the least-squares straightness of each profile when the ls reference found it on the way.
LsWidths apply_reference(Raw& r, Reference ref);

// --- uncertainty_*.cpp: standard uncertainties (mm, and rad for the pitch) of the reported
// profiles under the ls reference, for a noise variance noise_var (mm²) per reading, into uw, ug
// and ut (ut only with with_pitch).
// From the least-squares covariance (AᵀA)⁻¹ of the solve in st.
void lsq_uncertainties(LsqState& st, const Raw& r, bool with_pitch, double noise_var,
                       Eigen::VectorXd& uw, Eigen::VectorXd& ug, Eigen::VectorXd& ut);
// By exact propagation of every reading through the two- or three-point recurrence.
void recurrence_uncertainties(const ProbeData& d, Method method, const Raw& r, bool with_pitch,
                              double noise_var, Eigen::VectorXd& uw, Eigen::VectorXd& ug,
                              Eigen::VectorXd& ut);
// Of solve_lsq_direct on stations x (its grids alone, not the readings).
void direct_uncertainties(const Eigen::VectorXd& x, bool parabola_free, bool with_pitch, double h,
                          double noise_var, Eigen::VectorXd& uw, Eigen::VectorXd& ug,
                          Eigen::VectorXd& ut);

}  // namespace trueaxis::separation::detail
