// Backlash and squareness compensation values from a circular test's diagnosis; the conventions
// are stated in the header.
#include "trueaxis/circular/compensation.hpp"

#include <fmt/format.h>

#include "../common/figures.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::circular {
namespace {

const Cause* find(const Result& r, const std::string& key) {
  for (const auto& c : r.causes)
    if (c.key == key) return &c;
  return nullptr;
}

// `to_library` converts the cause's unit to mm or rad.
CompensationValue value_of(const Result& r, const std::string& key, double active,
                           double to_library, double coverage) {
  CompensationValue v;
  v.active = active;
  v.value = active;
  const Cause* c = find(r, key);
  if (!c) {
    v.reason = "not in the diagnosis (no data for it)";
    return v;
  }
  if (!c->separated || !std::isfinite(c->value)) {
    v.reason =
        "not separated from " + (c->confused_with.empty() ? "other causes" : c->confused_with);
    return v;
  }
  v.diagnosed = c->value * to_library;
  if (c->u) v.u = *c->u * to_library;
  if (!v.u) {
    v.reason = "its uncertainty cannot be stated (no degrees of freedom left)";
    return v;
  }
  if (std::abs(v.diagnosed) < coverage * *v.u) {
    v.reason = fmt::format("not significant: smaller than {:g} times its uncertainty", coverage);
    return v;
  }
  v.value = active + v.diagnosed;
  v.changed = true;
  return v;
}

}  // namespace

void CompensationOptions::validate() const {
  for (double b : active_backlash)
    if (!std::isfinite(b)) throw Error("compensation: the active backlash must be finite");
  if (!std::isfinite(active_squareness))
    throw Error("compensation: the active squareness must be finite");
  if (!(coverage >= 0) || !std::isfinite(coverage))
    throw Error("compensation: the coverage factor must be >= 0");
}

Compensation compensation_from(const Result& r, const CompensationOptions& o) {
  o.validate();
  Compensation c;
  c.plane = r.plane;
  const char* axes = "XYZ";
  for (int i = 0; i < 2; ++i)
    c.backlash[static_cast<std::size_t>(i)] =
        value_of(r, fmt::format("backlash.{}", axes[i == 0 ? r.plane.a : r.plane.b]),
                 o.active_backlash[static_cast<std::size_t>(i)], 1e-3, o.coverage);
  c.squareness = value_of(r, "squareness", o.active_squareness, 1e-6, o.coverage);
  return c;
}

std::string Compensation::summary() const {
  const char* axes = "XYZ";
  auto line = [](const std::string& name, const CompensationValue& v, double scale,
                 const char* unit) {
    std::string s = fmt::format("  {:<28} {:+.2f} {}", name, v.value * scale, unit);
    if (v.changed)
      s += fmt::format(" (was {:+.2f}; the test found {} ± {} {})", v.active * scale,
                       trueaxis::detail::rounded_to(v.diagnosed * scale, *v.u * scale),
                       trueaxis::detail::two_digits(*v.u * scale), unit);
    else
      s += " (unchanged: " + v.reason + ")";
    return s + "\n";
  };
  std::string s = fmt::format("compensation from the circular test in {}:\n", plane.name());
  for (int i = 0; i < 2; ++i)
    s += line(fmt::format("backlash of {}", axes[i == 0 ? plane.a : plane.b]),
              backlash[static_cast<std::size_t>(i)], 1e3, "µm");
  s += line(fmt::format("squareness ({} += slope·{})", axes[plane.a], axes[plane.b]), squareness,
            1e6, "µm/m");
  return s;
}

}  // namespace trueaxis::circular
