// Report sections of the CMM acceptance tests (report/acceptance.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "trueaxis/report/acceptance.hpp"

namespace trueaxis::report {
namespace {

constexpr const char* kIso10360_5 =
    "ISO 10360-5:2010, Acceptance and reverification tests for CMMs, Part 5: CMMs using single "
    "and multiple stylus contacting probing systems (PForm, PSize, the 25-point pattern).";
constexpr const char* kIso14253_1 =
    "ISO 14253-1:2017, Decision rules for verifying conformity or nonconformity with "
    "specifications (conformance proven within the specification less U).";
constexpr const char* kIsoTs23165 =
    "ISO/TS 23165:2006, Guidelines for the evaluation of coordinate measuring machine (CMM) test "
    "uncertainty (the test value's budget: calibration, temperature, expansion coefficient, "
    "alignment, fixturing).";

// One colour per ISO 10360-2 position.
const char* position_colour(std::size_t i) {
  static const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                   "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f"};
  return kColours[i % 8];
}

std::string verdict_html(acceptance::Verdict v) {
  const char* colour = v == acceptance::Verdict::Conforms         ? "#2ca02c"
                       : v == acceptance::Verdict::DoesNotConform ? "#d62728"
                                                                  : "#ff7f0e";
  return fmt::format("<strong style=\"color:{}\">{}</strong>", colour,
                     escape(acceptance::to_string(v)));
}

}  // namespace

Section e0_section(const std::string& title, const acceptance::E0Result& r) {
  Section s;
  s.title = title;
  s.references = {refs::kIso10360_2, kIso14253_1, kIsoTs23165, refs::kGum};
  const std::string e = r.name();
  s.summary = r.lengths.empty() ? fmt::format("{}: no length measured", e)
                                : fmt::format("{} {:.2f} µm (MPE {} µm): {}", e, r.e0_max * 1e3,
                                              r.mpe_text, acceptance::to_string(r.verdict));
  if (!r.complete)
    s.warnings.push_back(
        fmt::format("The test stopped after {} lengths: {}. What was measured "
                    "is shown; conformance cannot be proven from it.",
                    r.lengths.size(), r.stopped));
  s.intro_html = fmt::format(
      "<p>The length measuring error {} of ISO 10360-2{}: {} lengths in {} positions, each "
      "probed once on each face from outside, {} times. Verdict: {}. {}.</p>",
      escape(e),
      r.stylus_offset
          ? fmt::format(", with the stylus tip offset ({:g}, {:g}, {:g}) mm from the ram axis",
                        r.stylus_offset->x(), r.stylus_offset->y(), r.stylus_offset->z())
          : std::string(),
      r.lengths.size(), r.positions.size(),
      r.lengths.empty() ? 0
                        : std::count_if(r.lengths.begin(), r.lengths.end(),
                                        [&](auto& l) {
                                          return l.position == r.lengths.front().position &&
                                                 l.block == r.lengths.front().block;
                                        }),
      verdict_html(r.verdict), escape(r.rule));
  s.table = {{"figure", "value (µm)", "MPE (µm)", "verdict"}};
  s.table.push_back({fmt::format("{} (largest |E|)", e),
                     r.lengths.empty() ? "not measured" : fmt::format("{:.2f}", r.e0_max * 1e3),
                     r.mpe_text, acceptance::to_string(r.verdict)});
  s.table.push_back({"R0 (largest range of repetitions)",
                     r.r0.empty() ? "not determined" : fmt::format("{:.2f}", r.r0_max * 1e3),
                     r.r0_text.empty() ? "not specified" : r.r0_text,
                     r.r0_pass ? (*r.r0_pass ? "within" : "beyond") : ""});
  // Per position and length: the errors of the repetitions, R0, the MPE and U.
  std::vector<std::vector<std::string>> t = {
      {"position", "block", "nominal (mm)", "errors (µm)", "R0 (µm)", "MPE (µm)", "U (µm)"}};
  std::map<std::pair<std::string, std::string>, std::vector<double>> errors;
  std::vector<const acceptance::LengthResult*> firsts;  // each length's first repetition
  for (const auto& l : r.lengths) {
    auto& list = errors[{l.position, l.block}];
    if (list.empty()) firsts.push_back(&l);
    list.push_back(l.error * 1e3);
  }
  for (const auto* row : firsts) {
    std::string list;
    for (const double v : errors[{row->position, row->block}])
      list += (list.empty() ? "" : ", ") + fmt::format("{:+.2f}", v);
    const auto r0 = std::find_if(r.r0.begin(), r.r0.end(), [&](const auto& x) {
      return x.position == row->position && x.block == row->block;
    });
    t.push_back({row->position, row->block, fmt::format("{:g}", row->nominal), list,
                 r0 == r.r0.end() ? "—" : fmt::format("{:.2f}", r0->range * 1e3),
                 fmt::format("{:.2f}", row->mpe * 1e3), fmt::format("{:.2f}", row->U * 1e3)});
  }
  s.tables_after.push_back({"Each length at each position (ISO 10360-2)", std::move(t)});
  if (r.lengths.empty()) return s;
  // Length errors against the nominal length: one series per position (markers), each drawn
  // a little beside the nominal so that positions do not hide each other.
  std::vector<std::string> names;
  for (const auto& l : r.lengths)
    if (std::find(names.begin(), names.end(), l.position) == names.end())
      names.push_back(l.position);
  std::vector<std::size_t> order(r.lengths.size());
  std::iota(order.begin(), order.end(), 0);
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& l : r.lengths) {
    lo = std::min(lo, l.nominal);
    hi = std::max(hi, l.nominal);
  }
  const double dodge = 0.006 * std::max(hi - lo, 1.0);
  auto x_of = [&](const acceptance::LengthResult& l) {
    const auto k = std::find(names.begin(), names.end(), l.position) - names.begin();
    return l.nominal +
           dodge * (static_cast<double>(k) - 0.5 * static_cast<double>(names.size() - 1));
  };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return x_of(r.lengths[a]) < x_of(r.lengths[b]);
  });
  Plot p;
  p.title = fmt::format(
      "Length error against nominal length, one colour per position, with ±MPE "
      "(dark, dashed) and ±(MPE − U), within which conformance is proven (grey, dashed)");
  p.x_label = "nominal length (mm)";
  p.y_label = "length error (µm)";
  const auto n = static_cast<Eigen::Index>(order.size());
  p.x.resize(n);
  std::vector<Series> per(names.size());
  for (std::size_t k = 0; k < names.size(); ++k)
    per[k] = {names[k], Eigen::VectorXd::Constant(n, NAN), {}, position_colour(k), false, true};
  Series up{"±MPE", Eigen::VectorXd(n), {}, "#444444", true, false},
      down{"", Eigen::VectorXd(n), {}, "#444444", true, false},
      zone{"±(MPE − U)", Eigen::VectorXd(n), {}, "#999999", true, false},
      zone_down{"", Eigen::VectorXd(n), {}, "#999999", true, false};
  down.in_legend = zone_down.in_legend = false;
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& l = r.lengths[order[static_cast<std::size_t>(i)]];
    p.x[i] = x_of(l);
    const auto k =
        static_cast<std::size_t>(std::find(names.begin(), names.end(), l.position) - names.begin());
    per[k].y[i] = l.error * 1e3;
    up.y[i] = l.mpe * 1e3;
    down.y[i] = -l.mpe * 1e3;
    zone.y[i] = std::max(0.0, l.mpe - l.U) * 1e3;
    zone_down.y[i] = -zone.y[i];
  }
  for (auto& se : per) p.series.push_back(std::move(se));
  for (auto* se : {&up, &down, &zone, &zone_down}) p.series.push_back(std::move(*se));
  s.plots.push_back(std::move(p));
  std::vector<std::vector<std::string>> pos = {
      {"position", "direction", "lengths", "space diagonal"}};
  for (const auto& q : r.positions)
    pos.push_back({q.name,
                   fmt::format("({:+.3f}, {:+.3f}, {:+.3f})", q.direction.x(), q.direction.y(),
                               q.direction.z()),
                   fmt::format("{}", q.placements.size()), q.space_diagonal ? "yes" : ""});
  s.tables_after.push_back({"The positions (machine coordinates)", std::move(pos)});
  return s;
}

Section probing_section(const std::string& title, const acceptance::ProbingResult& r,
                        const Eigen::Vector3d& pole) {
  Section s;
  s.title = title;
  s.references = {kIso10360_5, refs::kIso10360_6, kIso14253_1};
  s.summary = fmt::format("PForm {:.2f} µm, PSize {:+.2f} µm", r.form * 1e3, r.size * 1e3);
  auto verdict = [](const std::optional<acceptance::Verdict>& v) {
    return v ? std::string(acceptance::to_string(*v)) : std::string("no MPE given");
  };
  s.intro_html = fmt::format(
      "<p>The probing errors of ISO 10360-5 on the reference sphere: {} points in the "
      "standard's pattern, the least-squares sphere through them (diameter {:.4f} mm). PForm "
      "is the range of the radial distances, PSize the diameter less the calibrated one. {}.</p>",
      r.points.cols(), r.diameter, escape(r.rule));
  s.table = {{"figure", "value (µm)", "U (µm)", "MPE (µm)", "verdict"}};
  s.table.push_back(
      {"PForm", fmt::format("{:.2f}", r.form * 1e3), fmt::format("{:.2f}", r.U_form * 1e3),
       r.mpe_form ? fmt::format("{:g}", *r.mpe_form * 1e3) : "", verdict(r.form_verdict)});
  s.table.push_back(
      {"PSize", fmt::format("{:+.2f}", r.size * 1e3), fmt::format("{:.2f}", r.U_size * 1e3),
       r.mpe_size ? fmt::format("{:g}", *r.mpe_size * 1e3) : "", verdict(r.size_verdict)});
  // The deviations over a map of the sphere from its pole (each point at its angle from the pole
  // as the distance from the middle, in its azimuth: the pattern's rings evenly spaced), its
  // height the radial deviation; the rings joined, and the meridians of the first ring's points.
  const Eigen::Vector3d n = pole.normalized();
  const Eigen::Vector3d helper =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = (helper - helper.dot(n) * n).normalized(), v = n.cross(u);
  SurfaceView view;
  view.title = "Radial deviations of the 25 points, on a map of the sphere from its pole";
  view.value_label = "radial deviation (µm)";
  view.base = "a map of the sphere (radius: the angle from the pole)";
  view.x_name = "u";
  view.y_name = "v";
  auto mapped = [&](Eigen::Index k) {
    const Eigen::Vector3d d = (r.points.col(k) - r.centre).normalized();
    const double polar = std::acos(std::clamp(d.dot(n), -1.0, 1.0)) * 180 / 3.14159265358979323846;
    const double az = std::atan2(d.dot(v), d.dot(u));
    return Eigen::Vector3d(polar * std::cos(az), polar * std::sin(az), r.radial[k] * 1e3);
  };
  const int rings[4][2] = {{1, 5}, {5, 13}, {13, 17}, {17, 25}};  // [first, end)
  if (r.points.cols() == 25) {
    for (const auto& ring : rings) {
      Eigen::Matrix3Xd line(3, ring[1] - ring[0] + 1);
      for (int i = ring[0]; i <= ring[1]; ++i)
        line.col(i - ring[0]) = mapped(i == ring[1] ? ring[0] : i);
      view.lines.push_back(line);
    }
    for (int k = 1; k < 5; ++k) {
      Eigen::Matrix3Xd line(3, 2);
      line.col(0) = mapped(0);
      line.col(1) = mapped(k);
      view.lines.push_back(line);
    }
    s.views.push_back(view);
  }
  std::vector<std::vector<std::string>> t = {
      {"point", "x (mm)", "y (mm)", "z (mm)", "radial (µm)"}};
  for (Eigen::Index i = 0; i < r.points.cols(); ++i)
    t.push_back({fmt::format("{}", i + 1), fmt::format("{:.4f}", r.points(0, i)),
                 fmt::format("{:.4f}", r.points(1, i)), fmt::format("{:.4f}", r.points(2, i)),
                 fmt::format("{:+.3f}", r.radial[i] * 1e3)});
  s.more_tables.push_back(
      {"The points (machine coordinates) and their radial deviations", std::move(t)});
  return s;
}

}  // namespace trueaxis::report
