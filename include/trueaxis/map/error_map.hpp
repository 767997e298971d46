// trueaxis::map — error-vector maps on a rectilinear 3-D grid: interpolation, compensation and
// correction (shared by the error space of surface/space.hpp and the ball-gauge map of
// ballgauge/ballgauge.hpp).
//
// An ErrorMap holds the error vector e = actual − nominal (mm) of a machine at the nodes of a
// grid x_i × y_j × z_k (mm, machine coordinates), with an optional standard uncertainty per
// component. Between nodes: trilinear interpolation (default) or a C¹ tensor-product cubic
// (Hermite with three-point slopes; reproduces quadratics, needs ≥ 3 nodes per axis for its
// benefit). Outside the grid: a clear refusal (default) or, only when asked, a clamp to the
// nearest face (the error there is held constant: never extrapolated).
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace trueaxis::map {

enum class Interpolation { Linear, Cubic };
enum class Outside { Refuse, Clamp };

const char* to_string(Interpolation i);
Interpolation interpolation_from_string(const std::string& s);  // "linear" | "cubic"

struct ErrorMap {
  std::array<Eigen::VectorXd, 3> axes;  // node coordinates per axis (mm), strictly increasing, ≥ 2
  Eigen::Matrix3Xd error;               // mm, column n = node (i, j, k), n = i + nx·(j + ny·k)
  Eigen::Matrix3Xd uncertainty;         // mm, same layout, or empty
  // ≥ 0: the map holds one plane normal to this axis (0 x, 1 y, 2 z; a ball plate's map): the
  // axis has two nodes, the plane ± a band, with equal errors, so a point within the band takes
  // the plane's error and a point outside it is refused as off the plane.
  int plane = -1;

  Eigen::Index size(int axis) const { return axes[static_cast<std::size_t>(axis)].size(); }
  Eigen::Index nodes() const { return size(0) * size(1) * size(2); }
  Eigen::Index index(Eigen::Index i, Eigen::Index j, Eigen::Index k) const {
    return i + size(0) * (j + size(1) * k);
  }
  Eigen::Vector3d node(Eigen::Index n) const;
  bool contains(const Eigen::Vector3d& p, double tolerance = 1e-9) const;
  // "(x, y, z) mm is outside the map's grid x [..], y [..], z [..] mm (give --clamp ...)".
  std::string outside_message(const Eigen::Vector3d& p) const;
  // Throws Error naming the problem (axes not increasing, sizes, non-finite values).
  void validate() const;
};

struct EvalOptions {
  Interpolation interpolation = Interpolation::Linear;
  Outside outside = Outside::Refuse;
  double tolerance = 1e-9;  // mm: how far outside the grid still counts as on it
};

// A prepared evaluator (precomputes the per-axis lookup and cubic slopes; cheap to copy). The
// map must outlive it.
class Interpolator {
 public:
  Interpolator(const ErrorMap& map, EvalOptions options = {});
  // Error at p (mm). With Outside::Refuse, throws Error if p is outside the grid.
  Eigen::Vector3d operator()(const Eigen::Vector3d& p) const;
  // Same, clamping p to the grid whatever the options say (for compensation iterates).
  Eigen::Vector3d clamped(const Eigen::Vector3d& p) const;
  const EvalOptions& options() const { return options_; }

 private:
  struct Axis {
    const double* x = nullptr;
    Eigen::Index n = 0;
    double x0 = 0, inv_h = 0;  // uniform axes: direct cell lookup
    bool uniform = false;
    std::vector<double> slope;  // cubic: per node, its three-point slope's 3 coefficients
    // Cubic: per cell i, the first of its (up to) 4 nodes and the weights of those nodes as
    // cubic polynomials in the local coordinate t: poly[16 i + 4 p + q] is the t^p coefficient
    // of node q's weight (made once per axis, so a point's weights are three Horner steps).
    std::vector<Eigen::Index> base;
    std::vector<double> poly;
    int count = 0;                      // nodes per weight set: min(n, 4)
    Eigen::Index cell(double v) const;  // i with x[i] <= v <= x[i+1], v already clamped
  };
  Eigen::Vector3d eval(const Eigen::Vector3d& p) const;
  const ErrorMap* map_;
  EvalOptions options_;
  std::array<Axis, 3> axis_;
};

// Errors at many points (3 × n, mm), in parallel. Refusal names the first point outside
// (0-based column) and the grid's extent.
Eigen::Matrix3Xd evaluate(const ErrorMap& map, const Eigen::Matrix3Xd& points,
                          const EvalOptions& options = {});

struct CompensateOptions {
  EvalOptions eval;
  int iterations = 2;  // fixed-point iterations of c' = c − e(c'), ≥ 1
};

// Compensated commands, in place: for a wanted tool position c, the command c' with
// c' + e(c') ≈ c, by c'₀ = c, c'ₘ₊₁ = c − e(c'ₘ). The wanted positions must lie in the grid
// (or are clamped, if asked); the iterates, which move by only |e|, are evaluated clamped.
// Contraction: the error after m iterations is about |∇e|ᵐ·|e| (|∇e| ~ 1e-5 on machines).
void compensate(const ErrorMap& map, Eigen::Ref<Eigen::Matrix3Xd> points,
                const CompensateOptions& options = {});

// Corrected measured points, in place: X = x − e(x) (a CMM's reading x, ball-gauge style).
void correct(const ErrorMap& map, Eigen::Ref<Eigen::Matrix3Xd> points,
             const EvalOptions& options = {});

// The map sampled from a function e(p) at the nodes of the given axes (for simulations and
// tests). `fn` is called once per node.
template <class Fn>
ErrorMap sample(const std::array<Eigen::VectorXd, 3>& axes, Fn&& fn) {
  ErrorMap m;
  m.axes = axes;
  m.error.resize(3, m.nodes());
  for (Eigen::Index n = 0; n < m.nodes(); ++n) m.error.col(n) = fn(m.node(n));
  return m;
}

}  // namespace trueaxis::map
