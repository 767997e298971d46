#include "trueaxis/io/geometry/points.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <vector>

#include "../fast_text.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/sim/machine.hpp"

namespace trueaxis::io {

Eigen::Matrix3Xd read_ds(const std::string& path) {
  const std::string text = detail::read_text(path);
  std::vector<double> xyz;
  long declared = -1, line = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    ++line;
    const char* b = text.data() + pos;
    const char* e = text.data() + end;
    pos = end + 1;
    auto col = [&](const char* at) { return static_cast<long>(at - b) + 1; };
    std::vector<double> nums;
    const char* p = b;
    for (;;) {
      while (p < e && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
      if (p >= e) break;
      double v = 0;
      const auto [q, ec] = std::from_chars(p, e, v);
      if (ec != std::errc() || (q < e && *q != ' ' && *q != '\t' && *q != '\r') ||
          !std::isfinite(v))
        throw Error(fmt::format("{}:{}:{}: expected a number", path, line, col(p)));
      nums.push_back(v);
      p = q;
    }
    if (nums.empty()) continue;  // blank line
    if (declared < 0) {
      if (nums.size() != 1 || nums[0] < 0 || nums[0] != std::floor(nums[0]))
        throw Error(
            fmt::format("{}:{}:1: the first line must be the number of points", path, line));
      if (nums[0] == 0)
        throw Error(fmt::format("{}:{}:1: no points (the file declares 0)", path, line));
      if (nums[0] > 1e8)
        throw Error(
            fmt::format("{}:{}:1: {:g} points declared: at most 100000000", path, line, nums[0]));
      declared = static_cast<long>(nums[0]);
      continue;
    }
    if (nums.size() != 3)
      throw Error(
          fmt::format("{}:{}:1: expected 3 coordinates x y z, got {}", path, line, nums.size()));
    xyz.insert(xyz.end(), nums.begin(), nums.end());
  }
  if (declared < 0)
    throw Error(fmt::format("{}: empty file (expected the number of points)", path));
  const long n = static_cast<long>(xyz.size() / 3);
  if (n != declared)
    throw Error(fmt::format("{}:1:1: the file declares {} points but has {}", path, declared, n));
  return Eigen::Map<const Eigen::Matrix3Xd>(xyz.data(), 3, n);
}

Eigen::Matrix3Xd read_point_set(const std::string& path) {
  std::string ext = path.size() >= 3 ? path.substr(path.size() - 3) : "";
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".ds" ? read_ds(path) : read_points(path);
}

void write_fit(const std::string& path, const geometry::Fit& f, const geometry::Form& form) {
  using geometry::Element;
  nlohmann::ordered_json j;
  j["kind"] = "fit";
  j["element"] = geometry::to_string(f.element);
  j["points"] = f.residuals.size();
  const bool centre = f.element == Element::Circle || f.element == Element::Sphere;
  j[centre ? "center" : "point"] = {f.point.x(), f.point.y(), f.point.z()};
  if (f.element != Element::Sphere) {
    const bool normal = f.element == Element::Plane || f.element == Element::Circle;
    j[normal ? "normal" : "direction"] = {f.direction.x(), f.direction.y(), f.direction.z()};
  }
  if (f.element == Element::Circle || f.element == Element::Sphere ||
      f.element == Element::Cylinder)
    j["diameter"] = f.diameter;
  if (f.element == Element::Cone) {
    j["distance"] = f.distance;
    j["apex_angle_deg"] = f.apex_angle * 180 / M_PI;
  }
  if (f.zone > 0) j["zone"] = f.zone;
  nlohmann::ordered_json fj{
      {"name", form.name},
      {"reference", form.reference},
      {"value", form.value},
      {"U", form.U ? nlohmann::ordered_json(*form.U) : nullptr},
      {"resolved", form.U ? nlohmann::ordered_json(*form.resolved()) : nullptr}};
  if (!form.U) fj["no_uncertainty"] = form.no_uncertainty;
  j["form"] = fj;
  if (f.has_uncertainty) {
    // Standard uncertainties (k = 1) of the values above, same units.
    nlohmann::ordered_json u;
    const bool centre_u = f.element == Element::Circle || f.element == Element::Sphere;
    u[centre_u ? "center" : "point"] = {f.u_point.x(), f.u_point.y(), f.u_point.z()};
    if (f.element != Element::Sphere) {
      const bool normal = f.element == Element::Plane || f.element == Element::Circle;
      u[normal ? "normal" : "direction"] = {f.u_direction.x(), f.u_direction.y(),
                                            f.u_direction.z()};
    }
    if (f.diameter > 0) u["diameter"] = f.u_diameter;
    if (f.element == Element::Cone) {
      u["distance"] = f.u_distance;
      u["apex_angle_deg"] = f.u_apex_angle * 180 / M_PI;
    }
    j["uncertainty"] = u;
    j["dof"] = f.dof;
  }
  if (std::isfinite(f.condition_number) && f.condition_number > 0)
    j["condition_number"] = f.condition_number;
  j["warnings"] = f.warnings;
  j["rms"] = f.rms;
  j["max"] = f.max;
  j["iterations"] = f.iterations;
  write_json(path, j);
}

}  // namespace trueaxis::io
