#include "trueaxis/compensation/table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "trueaxis/error.hpp"

namespace trueaxis::compensation {

void AxisTable::validate() const {
  const std::size_t n = position.size();
  if (n < 2) throw Error("a compensation table needs at least two positions");
  if (forward.size() != n || reverse.size() != n)
    throw Error("a compensation table needs one forward and one reverse value per position");
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(position[i]) || !std::isfinite(forward[i]) || !std::isfinite(reverse[i]))
      throw Error(fmt::format("compensation table entry {} is not finite", i + 1));
    if (i > 0 && !(position[i] > position[i - 1]))
      throw Error(fmt::format("compensation table positions must increase ({:g} after {:g} mm)",
                              position[i], position[i - 1]));
  }
}

double AxisTable::correction(double p, positioning::Direction d) const {
  const auto& v = d == positioning::Direction::Up ? forward : reverse;
  if (p <= position.front()) return v.front();
  if (p >= position.back()) return v.back();
  const auto it = std::upper_bound(position.begin(), position.end(), p);
  const std::size_t i = static_cast<std::size_t>(it - position.begin()) - 1;
  const double t = (p - position[i]) / (position[i + 1] - position[i]);
  return v[i] + t * (v[i + 1] - v[i]);
}

AxisTable from_positioning(const positioning::Result& r, bool bidirectional) {
  AxisTable t;
  for (const auto& x : r.targets) {
    double f = -x.mean_up, b = -x.mean_down;
    if (!bidirectional) {
      // The bidirectional mean where both directions were measured, else the one measured.
      const double m = !std::isnan(x.mean)      ? x.mean
                       : !std::isnan(x.mean_up) ? x.mean_up
                                                : x.mean_down;
      f = b = -m;
    }
    if (std::isnan(f) || std::isnan(b))
      throw Error(fmt::format(
          "target {:g} mm has no mean deviation for {} approaches: a bidirectional table needs "
          "both directions (make a unidirectional one instead)",
          x.position, std::isnan(f) ? "'+'" : "'-'"));
    t.position.push_back(x.position);
    t.forward.push_back(f);
    t.reverse.push_back(b);
  }
  t.validate();
  return t;
}

Eigen::Vector3d grid_centre(const map::ErrorMap& m) {
  Eigen::Vector3d c;
  for (int k = 0; k < 3; ++k) {
    const auto& x = m.axes[static_cast<std::size_t>(k)];
    c[k] = 0.5 * (x[0] + x[x.size() - 1]);
  }
  return c;
}

AxisTable from_map(const map::ErrorMap& m, int axis, const Eigen::Vector3d& at) {
  if (axis < 0 || axis > 2) throw Error("the axis must be x, y or z");
  const Eigen::VectorXd& nodes = m.axes[static_cast<std::size_t>(axis)];
  const map::Interpolator f(m);
  AxisTable t;
  for (Eigen::Index i = 0; i < nodes.size(); ++i) {
    Eigen::Vector3d p = at;
    p[axis] = nodes[i];
    const double c = -f(p)[axis];  // refuses an `at` outside the grid
    t.position.push_back(nodes[i]);
    t.forward.push_back(c);
    t.reverse.push_back(c);
  }
  t.validate();
  return t;
}

}  // namespace trueaxis::compensation
