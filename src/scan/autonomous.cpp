// Autonomous scanning within the error-tolerant flow: the whole section, or locally round a
// trajectory error's stop, its measured contour becoming the section's design data.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "section_run.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::scan::detail {
namespace {
// A local autonomous scan follows the part this far (mm), starting kLocalLead mm before the
// stop (then four times as far, if the part is not back on its design by then), and the part
// counts as back on its design within kRejoin times the trajectory tolerance.
constexpr double kLocalScan = 60, kLocalLead = 10, kRejoin = 0.03;
}  // namespace

bool SectionRun::autonomous_range(double& from, double& to) {
  if (!planner().part() || current.space_curve() || seen + 1 <= planner().margin()) return true;
  const double L = to;
  double best_len = 0;
  for (const auto& [a, b] : room_with(seen + 1))
    if (b - a > best_len) {
      best_len = b - a;
      from = a;
      to = b;
    }
  const std::string why = fmt::format(
      "the part is {:.2f} mm off its design here, and the stylus would come within {:.1f} mm "
      "of where the design puts it",
      seen, seen + 1);
  if (best_len < detail::kShortest || (current.closed && best_len < L - 1e-9)) {
    r.not_reachable = true;
    r.reason = "not scanned autonomously: " + why;
    log(0, seen, "autonomous", "error_exit", r.reason);
    return false;
  }
  if (from > 0) cut_off(0, from, why);
  if (to < L) cut_off(to, L, why);
  return true;
}

bool SectionRun::autonomous() {
  if (!two_dimensional(0, 0)) return false;
  // Approach where the design is smooth: the sample farthest (in arc) from any corner, so
  // that a moved part is still met along the normal.
  const auto smp = design::sample(current, 1.0);
  const Eigen::Index n = smp.points.cols();
  std::vector<double> corners;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index j = (i + 1) % n;
    if ((current.closed || j > i) && smp.normals.col(i).dot(smp.normals.col(j)) < std::cos(0.2))
      corners.push_back(smp.arc[i]);
  }
  const double L = design::length(current);
  double from = 0, to = L;
  if (!autonomous_range(from, to)) return false;
  // Where to start, best first. A closed contour: the samples farthest from any corner. An
  // open one is followed from near its start to its end: the smooth places from `keep` in (a
  // tenth of the way at most), in order, up to a quarter of the way, each `keep` from a
  // corner: 1 mm, or as far as the part may be off its design along the contour (the
  // planner's margin, or what was found) where a solid tells what lies beyond the stretch's
  // ends (an approach 1 mm from an end of a part moved 2.7 mm along it passed the wall it was
  // meant for and met the part beyond). The first the ball can be brought to is taken (a
  // start far off the design may lie under an overhang).
  const double keep = planner().part() ? std::max({1.0, planner().margin(), seen + 1}) : 1.0;
  const double lead = std::min(keep, 0.1 * (to - from));
  std::vector<std::pair<double, Eigen::Index>> order;  // (rank, sample)
  for (Eigen::Index i = 0; i < n; ++i) {
    double gap = L;
    for (double c : corners) {
      double d = std::abs(smp.arc[i] - c);
      if (current.closed) d = std::min(d, L - d);
      gap = std::min(gap, d);
    }
    const double in = smp.arc[i] - from;
    if (current.closed)
      order.emplace_back(-gap, i);
    else if (in >= lead && gap >= lead && in <= std::max(lead, 0.25 * (to - from)))
      order.emplace_back(smp.arc[i], i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  if (order.empty()) {
    Eigen::Index i = 0;
    (smp.arc.array() - (from + lead)).abs().minCoeff(&i);
    order.emplace_back(0, i);
  }
  const double reach = o.path.tip_radius + o.tolerance + 3;
  Eigen::Index best = -1;
  std::string no_way;
  // Up to 12 candidates, every 8th of the ranked samples (not the neighbours of one that
  // failed).
  for (std::size_t k = 0; k < order.size() && k < 8 * 12; k += 8) {
    const Eigen::Index i = order[k].second;
    try {
      safe_move(smp.points.col(i) + reach * smp.normals.col(i));
      best = i;
      break;
    } catch (const NoWay& e) {
      no_way = e.what();
    }
  }
  if (best < 0) throw NoWay(no_way);
  const Eigen::Vector3d p = smp.points.col(best), nn = smp.normals.col(best);
  // An open stretch is followed to `keep` short of its end, which may border on what the stylus
  // cannot reach: the scan measures its length along the real part from where it met it, and
  // where that is along the design is known only to within the part's move along the contour
  // (followed to 1 mm short, a part moved 1.8 mm along it took the stem under the tab beyond the
  // end of the DaimlerChrysler part's outline at z = 15 mm).
  const double short_of = planner().part() ? keep : 1.0;
  if (!current.closed && to - smp.arc[best] - short_of < detail::kShortest) {
    const std::string why = fmt::format(
        "too short to follow autonomously: {:.1f} mm from where the ball meets it to {:.1f} mm "
        "short of its end, as near as the part's unknown place along it lets the scan go",
        std::max(0.0, to - smp.arc[best]), short_of);
    cut_off(from, to, why);
    r.not_reachable = true;
    r.reason = "not reachable: " + why;
    log(0, 0, "autonomous", "error_exit", r.reason);
    return false;
  }
  if (!current.closed && short_of > 1)
    cut_off(to - short_of, to,
            fmt::format("an autonomous scan is not followed closer than {:.1f} mm to the end of "
                        "the stretch: where the part stands along it is known only that well",
                        short_of));
  const auto out = timed(m, r.time.autonomous, [&] {
    return m.scan_unknown(current.plane, p + reach * nn, -nn, current.material, current.closed,
                          current.closed ? L : std::max(1.0, to - smp.arc[best] - short_of),
                          o.autonomous_speed, settings());
  });
  ++r.autonomous_count;
  if (!out.completed || out.samples.size() < 10) {
    log(out.stop.arc, 0, "autonomous", "error_exit",
        "the autonomous scan failed: " + (out.fault.empty() ? "too few points" : out.fault));
    r.reason = "autonomous scan failed: " + out.fault;
    return false;
  }
  log(out.stop.arc, 0, "autonomous", "autonomous_scan",
      fmt::format("{} points over {:.1f} mm", out.samples.size(), out.samples.back().arc));
  r.points = out.samples;
  if (o.strategy == Strategy::Autonomous) return true;
  design::Section measured = detail::overwrite(current, out.samples);
  // The measured contour is the design for the rescan and for the next part, if the ball can
  // follow it: a measured polyline may have a notch (a corner of the real part, noise) where
  // no path keeps the offset. The section is then measured by the autonomous scan, and the
  // design data stay as they were.
  if (const std::string why = unpathable(measured); !why.empty()) {
    measured_only = true;
    log(0, 0, "autonomous", "section_done",
        "measured by the autonomous scan; its contour is not kept as the design data: " + why);
    return true;
  }
  current = std::move(measured);
  moved = true;
  as_designed = false;
  log(0, 0, "autonomous", "design_overwritten",
      fmt::format("the section's design data replaced by the measured contour ({} points, "
                  "tip radius and pushing amount compensated)",
                  current.polyline.cols()));
  return true;
}

bool SectionRun::local_autonomous(const Sample& stop) {
  if (!current.closed || current.space_curve() || !two_dimensional(0, 0)) return false;
  const auto smp = design::sample(current, 1.0);
  const Eigen::Index n = smp.points.cols();
  const double L = design::length(current);
  const double at = detail::contour_arc(smp, design::make_path(current, o.path), stop.arc);
  // As for a whole contour (autonomous_range): a surface found further off its design than
  // the planner's margin allows for is followed only where the stylus has that room (and 1 mm
  // more) from the design's solid, here over all the stretch the scans may cover.
  if (planner().part() && seen + 1 > planner().margin()) {
    const auto room = room_with(seen + 1);
    for (double a = at - 3 * kLocalLead - 1; a <= at + 4 * kLocalScan; a += 1) {
      const double w = a - L * std::floor(a / L);
      if (std::none_of(room.begin(), room.end(),
                       [&](const auto& p) { return w >= p.first && w <= p.second; }))
        return false;
    }
  }
  const double reach = o.path.tip_radius + o.tolerance + 3;
  for (const double length : {kLocalScan, 4 * kLocalScan}) {
    if (length > 0.5 * L) break;
    // The start: kLocalLead mm or more before the stop, where the design is smooth (its normal
    // turns less than 0.2 rad over a millimetre either side), so the part is met along it.
    Eigen::Index best = -1;
    for (double back = kLocalLead; back <= 3 * kLocalLead && best < 0; back += 1) {
      const Eigen::Index i = static_cast<Eigen::Index>(std::lround((at - back + L) / L * n)) % n;
      const Eigen::Index a = (i + n - 1) % n, b = (i + 1) % n;
      if (smp.normals.col(a).dot(smp.normals.col(i)) > std::cos(0.2) &&
          smp.normals.col(b).dot(smp.normals.col(i)) > std::cos(0.2))
        best = i;
    }
    if (best < 0) return false;
    const Eigen::Vector3d p = smp.points.col(best), nn = smp.normals.col(best);
    try {
      safe_move(p + reach * nn);
    } catch (const NoWay&) {
      return false;
    }
    const auto out = timed(m, r.time.autonomous, [&] {
      return m.scan_unknown(current.plane, p + reach * nn, -nn, current.material, false, length,
                            o.autonomous_speed, settings());
    });
    ++r.autonomous_count;
    if (!out.completed || out.samples.size() < 10) {
      log(out.stop.arc, 0, "autonomous", "autonomous_scan",
          "the autonomous scan round the stop failed: " +
              (out.fault.empty() ? "too few points" : out.fault));
      return false;
    }
    auto sp = detail::splice(current, out.samples, at, kRejoin * o.tolerance);
    if (sp && !unpathable(sp->section).empty()) sp.reset();  // as in autonomous()
    if (sp) {
      log(out.stop.arc, 0, "autonomous", "autonomous_scan",
          fmt::format("{} points over {:.1f} mm round the stop", out.samples.size(),
                      out.samples.back().arc));
      current = std::move(sp->section);
      moved = true;
      as_designed = false;
      r.points = out.samples;
      log(0, sp->largest, "autonomous", "design_spliced",
          fmt::format("the design data from {:.1f} to {:.1f} mm along the contour replaced by "
                      "the measured contour (up to {:.3f} mm off the design there)",
                      sp->from, sp->to, sp->largest));
      return true;
    }
    log(out.stop.arc, 0, "autonomous", "autonomous_scan",
        fmt::format("{:.0f} mm scanned round the stop: the part is not back on its design "
                    "within them",
                    length));
  }
  return false;
}

}  // namespace trueaxis::scan::detail
