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

// The rest of a stretch is scanned autonomously from a smooth place at most this far (mm) before
// the stop.
constexpr double kRestBack = 10;
// An open stretch's autonomous scan whose approach finds no surface is tried from further along
// the stretch, up to this many approaches in all.
constexpr int kApproachTries = 4;
// What a free move loses to accelerating, braking and settling, and a touch to its retract,
// beyond its length at speed (s): on the virtual CMM (2000 mm/s², a 7 ms servo lag) a touch
// round on the shared CAD parts took 0.4–1.3 s a point, 0.8 s at the median, of which about
// 0.35 s are the search across the band and the route at speed.
constexpr double kMoveOverhead = 0.3;
// The correction menu is fitted to this many of the measured points, evenly spread (a touch
// round has 8).
constexpr Eigen::Index kRestFitPoints = 24;

// Whether the design normals turn less than 0.2 rad over a sample either side of sample i.
bool smooth_at(const design::Samples& smp, Eigen::Index i, bool closed) {
  const Eigen::Index n = smp.points.cols();
  if (!closed && (i == 0 || i + 1 >= n)) return false;
  const Eigen::Index a = (i + n - 1) % n, b = (i + 1) % n;
  return smp.normals.col(a).dot(smp.normals.col(i)) > std::cos(0.2) &&
         smp.normals.col(b).dot(smp.normals.col(i)) > std::cos(0.2);
}
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
  // An open stretch is followed to `keep` short of its end, which may border on what the stylus
  // cannot reach: the scan measures its length along the real part from where it met it, and
  // where that is along the design is known only to within the part's move along the contour
  // (followed to 1 mm short, a part moved 1.8 mm along it took the stem under the tab beyond the
  // end of the DaimlerChrysler part's outline at z = 15 mm).
  const double short_of = planner().part() ? keep : 1.0;
  // The first of `starts` the ball can be brought to: up to 12 candidates, every 8th (not the
  // neighbours of one that failed).
  auto bring = [&](const std::vector<std::pair<double, Eigen::Index>>& starts, std::size_t every) {
    std::string no_way;
    for (std::size_t k = 0; k < starts.size() && k < every * 12; k += every) {
      const Eigen::Index i = starts[k].second;
      try {
        safe_move(smp.points.col(i) + reach * smp.normals.col(i));
        return i;
      } catch (const NoWay& e) {
        no_way = e.what();
      }
    }
    throw NoWay(no_way);
  };
  Eigen::Index best = bring(order, 8);
  ScanOutcome out;
  double missed = -1;  // the last approach that found no surface (mm along the stretch)
  // Where the approach finds no surface within its search (the part is not where its design
  // puts it there: moved across a vertical section's plane, the part is cut elsewhere), an open
  // stretch is tried again from further along, the first smooth place (`lead` from a corner) 1 mm
  // beyond, up to
  // kApproachTries times; what lies before the start that met the part is reported.
  for (int attempt = 0;; ++attempt) {
    if (!current.closed && to - smp.arc[best] - short_of < detail::kShortest) {
      const std::string why =
          attempt == 0 ? fmt::format(
                             "too short to follow autonomously: {:.1f} mm from where the ball "
                             "meets it to {:.1f} mm short of its end, as near as the part's "
                             "unknown place along it lets the scan go",
                             std::max(0.0, to - smp.arc[best]), short_of)
                       : fmt::format(
                             "no surface found on the approaches up to {:.1f} mm along it, and "
                             "too short beyond them to follow autonomously",
                             smp.arc[best]);
      cut_off(from, to, why);
      r.not_reachable = true;
      r.reason = "not reachable: " + why;
      log(0, 0, "autonomous", "error_exit", r.reason);
      return false;
    }
    const Eigen::Vector3d p = smp.points.col(best), nn = smp.normals.col(best);
    out = timed(m, r.time.autonomous, [&] {
      return m.scan_unknown(current.plane, p + reach * nn, -nn, current.material, current.closed,
                            current.closed ? L : std::max(1.0, to - smp.arc[best] - short_of),
                            o.autonomous_speed, settings());
    });
    ++r.autonomous_count;
    if (out.completed || !out.missed_surface || current.closed || attempt + 1 >= kApproachTries)
      break;
    missed = smp.arc[best];
    std::vector<std::pair<double, Eigen::Index>> later;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (smp.arc[i] < missed + 1 || smp.arc[i] > to || !smooth_at(smp, i, false)) continue;
      const bool by_corner = std::any_of(corners.begin(), corners.end(),
                                         [&](double c) { return std::abs(smp.arc[i] - c) < lead; });
      if (!by_corner) later.emplace_back(smp.arc[i], i);
    }
    if (later.empty()) break;
    log(missed, 0, "autonomous", "approach_missed",
        fmt::format("no surface found on the approach at {:.1f} mm along the stretch: tried "
                    "again from further along",
                    missed));
    try {
      best = bring(later, 1);
    } catch (const NoWay&) {
      break;
    }
  }
  if (!out.completed || out.samples.size() < 10) {
    log(out.stop.arc, 0, "autonomous", "error_exit",
        "the autonomous scan failed: " + (out.fault.empty() ? "too few points" : out.fault));
    r.reason = "autonomous scan failed: " + out.fault;
    return false;
  }
  if (missed >= 0 && smp.arc[best] > from)
    cut_off(from, smp.arc[best],
            fmt::format("no surface found on the approach {:.1f} mm along the stretch: the part "
                        "is not within the approach's search of its design there",
                        missed));
  if (!current.closed && short_of > 1)
    cut_off(to - short_of, to,
            fmt::format("an autonomous scan is not followed closer than {:.1f} mm to the end of "
                        "the stretch: where the part stands along it is known only that well",
                        short_of));
  log(out.stop.arc, 0, "autonomous", "autonomous_scan",
      fmt::format("{} points over {:.1f} mm", out.samples.size(), out.samples.back().arc));
  r.points = out.samples;
  // How far off its design data the part stood along the scan: no correction accounts for it.
  const sim::Contour design = detail::contour_of(current);
  for (const Sample& s : out.samples)
    off_design = std::max(off_design, std::abs(design.nearest(s.surface).distance));
  if (o.strategy == Strategy::Autonomous) return true;
  // The scan is the section's measurement. The measured contour is the design data for the next
  // part, if the ball can follow it: a measured polyline may have a notch (a corner of the real
  // part, noise) where no path keeps the offset; the design data then stay as they were.
  const std::string why = take_measured(out.samples);
  log(0, 0, "autonomous", "section_done",
      why.empty() ? "measured by autonomous scanning; the measured contour is the design data for "
                    "the next part"
                  : "measured by the autonomous scan; its contour is not kept as the design "
                    "data: " +
                        why);
  return true;
}

std::string SectionRun::take_measured(const std::vector<Sample>& samples) {
  design::Section measured = detail::overwrite(current, samples);
  if (std::string why = unpathable(measured); !why.empty()) return why;
  current = std::move(measured);
  moved = true;
  as_designed = false;
  log(0, 0, "autonomous", "design_overwritten",
      fmt::format("the section's design data replaced by the measured contour ({} points, "
                  "tip radius and pushing amount compensated)",
                  current.polyline.cols()));
  return {};
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
      if (smooth_at(smp, i, true)) best = i;
    }
    if (best < 0) return false;
    const Eigen::Vector3d p = smp.points.col(best), nn = smp.normals.col(best);
    try {
      safe_move(p + reach * nn);
    } catch (const NoWay&) {
      return false;
    }
    const auto scanned = follow(p + reach * nn, nn, false, length, "round the stop");
    if (!scanned) return false;
    const ScanOutcome& out = *scanned;
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

std::optional<ScanOutcome> SectionRun::follow(const Eigen::Vector3d& start,
                                              const Eigen::Vector3d& normal, bool closed,
                                              double length, const std::string& what) {
  auto out = timed(m, r.time.autonomous, [&] {
    return m.scan_unknown(current.plane, start, -normal, current.material, closed, length,
                          o.autonomous_speed, settings());
  });
  ++r.autonomous_count;
  if (!out.completed || out.samples.size() < 10) {
    log(out.stop.arc, 0, "autonomous", "autonomous_scan",
        fmt::format("the autonomous scan {} failed: {}", what,
                    out.fault.empty() ? "too few points" : out.fault));
    return std::nullopt;
  }
  return out;
}

bool SectionRun::rest_autonomous(const Sample& stop) {
  // Where the flow would make a touch round. About a guessed move of the part, the scan's
  // points confirm or drop the guess as that round's would.
  if (current.space_curve() || !scanned_path) return false;
  const design::ScanPath& path = *scanned_path;
  const bool closed = current.closed;
  const int k = touch_count();
  if (k < kFewestTouches) return false;
  const double L = design::length(current);
  // As autonomous(): an open stretch is followed from `lead` in and to `short_of` before its
  // end, where a solid tells what lies beyond them.
  const double keep = planner().part() ? std::max({1.0, planner().margin(), seen + 1}) : 1.0;
  const double short_of = planner().part() ? keep : 1.0, lead = std::min(keep, 0.1 * L);
  // The machine time of each way on (s). The touch round: each point searched across the
  // band at the touch speed, routed a spacing on and back out at the move speed; then back to
  // the path's start and the whole path at its design speeds. The autonomous scan: the move to
  // its start and its length at the autonomous speed. The approach to the surface is alike for
  // both ways and left out.
  const double band = o.tolerance + kBandMargin + approach_extra + found_extra;
  const double spacing = closed ? L / k : 0.9 * L / (k - 1);
  const double touching = k * (band / o.touch_speed + 2 * spacing / o.move_speed + kMoveOverhead);
  const double rescan =
      (stop.surface - path.at(0).p).norm() / o.move_speed + kMoveOverhead + path.nominal_time();
  auto scanning = [&](double length, double move) {
    return move / o.move_speed + kMoveOverhead + length / o.autonomous_speed;
  };
  // Before the start is looked for (queries of the solid): the least the rest can cost, started
  // at the stop.
  const double at_about = stop.arc / path.length() * L;
  if (scanning(closed ? L : L - at_about - short_of, 0) >= touching + rescan) return false;
  const auto smp = design::sample(current, 1.0);
  const double at = detail::contour_arc(smp, path, stop.arc);
  auto sample_at = [&](double a) {
    if (closed) a -= L * std::floor(a / L);
    Eigen::Index i = 0;
    (smp.arc.array() - a).abs().minCoeff(&i);
    return i;
  };
  // The start: the nearest smooth place at or before the stop, else after it, from which the
  // approach can be made: the ball comes down to it from above, and about a guessed design it
  // keeps the planner's margin from the part where the design puts it too (as a touch's start
  // does).
  const double reach = o.path.tip_radius + o.tolerance + 3;
  const Eigen::Vector3d u = m.stylus_axis();
  auto usable = [&](Eigen::Index i) {
    if (!smooth_at(smp, i, closed)) return false;
    const Eigen::Vector3d start = smp.points.col(i) + reach * smp.normals.col(i);
    if (unguessed && nominal.part() && nominal.clearance(start, u) < nominal.margin()) return false;
    return planner().from_above(start, u);
  };
  Eigen::Index best = -1;
  if (closed) {
    // A closed contour is followed all round, from before the stop or after it.
    for (double d = 0; d <= kRestBack && best < 0; d += 1)
      for (const double a : {at - d, at + d})
        if (best < 0 && usable(sample_at(a))) best = sample_at(a);
  } else {
    for (double a = std::min(at, L - short_of); a >= std::max(lead, at - kRestBack) && best < 0;
         a -= 1)
      if (usable(sample_at(a))) best = sample_at(a);
    // After the stop only where it stopped at the stretch's start (what lies between would not
    // be measured).
    for (double a = std::max(at, lead); a <= std::min(lead + kRestBack, L - short_of) && best < 0;
         a += 1)
      if (usable(sample_at(a))) best = sample_at(a);
  }
  if (best < 0) return false;
  const double from = smp.arc[best], length = closed ? L : L - from - short_of;
  if (length < detail::kShortest) return false;
  // The stylus's room, as for any autonomous scan (autonomous_range).
  if (planner().part() && seen + 1 > planner().margin()) {
    const auto room = room_with(seen + 1);
    for (double a = closed ? 0 : from; a <= (closed ? L : L - short_of); a += 1)
      if (std::none_of(room.begin(), room.end(),
                       [&](const auto& p) { return a >= p.first && a <= p.second; }))
        return false;
  }
  const Eigen::Vector3d p = smp.points.col(best), nn = smp.normals.col(best);
  const double rest = scanning(length, (stop.surface - p).norm());
  if (rest >= touching + rescan) return false;
  try {
    safe_move(p + reach * nn);
  } catch (const NoWay&) {
    return false;
  }
  log(at, stop.delta_l, "autonomous", "rest_autonomous",
      fmt::format("{} scanned autonomously from {:.1f} mm: about {:.1f} s of machine time "
                  "against {:.1f} s for {} touch points and a rescan",
                  closed ? "the contour" : "the rest of the stretch", from, rest, touching + rescan,
                  k));
  const auto scanned = follow(p + reach * nn, nn, closed, length, "of the rest");
  if (!scanned) return false;
  const ScanOutcome& out = *scanned;
  // What neither scan measured, as autonomous() reports it: before the start, where the
  // design-value scan stopped short of it, and the end the scan keeps away from.
  if (!closed && from > at + 1)
    cut_off(at, from,
            fmt::format("the design-value scan stopped here, and the autonomous scan of the rest "
                        "could start no nearer ({:.1f} mm in from the stretch's start, on the "
                        "design's smooth part that the ball can come down to)",
                        from));
  if (!closed && short_of > 1)
    cut_off(L - short_of, L,
            fmt::format("an autonomous scan is not followed closer than {:.1f} mm to the end of "
                        "the stretch: where the part stands along it is known only that well",
                        short_of));
  // The measurement: the design-value scan's points before where the autonomous scan started,
  // then the autonomous scan's.
  const sim::Contour curve = detail::contour_of(current);
  std::vector<Sample> all;
  // (A closed contour's autonomous scan went all round.)
  for (const auto& s : partial)
    if (!closed && curve.nearest(s.surface).arc < from) all.push_back(s);
  const std::size_t designed = all.size();
  all.insert(all.end(), out.samples.begin(), out.samples.end());
  log(out.stop.arc, 0, "autonomous", "autonomous_scan",
      fmt::format("{} points over {:.1f} mm; with the design-value scan's {} before them",
                  out.samples.size(), out.samples.back().arc, designed));
  // The correction menu on points spread over all of them.
  const Eigen::Index count = std::min<Eigen::Index>(kRestFitPoints, all.size());
  Eigen::Matrix3Xd feet(3, count), got(3, count);
  for (Eigen::Index j = 0; j < count; ++j) {
    const auto i = static_cast<std::size_t>(
        std::lround(static_cast<double>(j) * static_cast<double>(all.size() - 1) /
                    static_cast<double>(count - 1)));
    got.col(j) = all[i].surface;
    feet.col(j) = curve.nearest(got.col(j)).point;
  }
  if (nominal.part()) {
    touched.push_back({nominal.part().get(), current.name, current.plane, got});
    made_round = true;
  }
  bool local = false;
  const design::Section measured_on = current;
  bool corrected = fit_touches(stop, feet, got, as_designed, measured_on, local, "scan points");
  bool confirmed = false;
  if (unguessed) {
    if (local) {
      confirm_guess();
      confirmed = true;
    } else if (!corrected) {
      // Fitted again to the design data without the guess (as after a touch round).
      drop_guess(stop);
      const sim::Contour designed_curve = detail::contour_of(current);
      for (Eigen::Index j = 0; j < got.cols(); ++j)
        feet.col(j) = designed_curve.nearest(got.col(j)).point;
      bool agree = false;
      corrected = fit_touches(stop, feet, got, true, current, agree, "scan points");
    }
  }
  if (!corrected && !confirmed) {
    // The next part's design data: the measured contour, where the ball can follow it.
    if (const std::string why = take_measured(all); !why.empty())
      log(0, 0, "autonomous", "design_kept",
          "the measured contour is not kept as the design data: " + why);
  }
  r.points = std::move(all);
  r.ok = true;
  log(at, 0, "autonomous", "section_done",
      closed         ? fmt::format("measured by autonomous scanning all round from {:.1f} mm", from)
      : designed > 0 ? fmt::format("measured by the design-value scan to {:.1f} mm and autonomous "
                                   "scanning from {:.1f} mm",
                                   at, from)
                     : fmt::format("measured by autonomous scanning from {:.1f} mm (the "
                                   "design-value scan stopped at its start)",
                                   from));
  return true;
}

}  // namespace trueaxis::scan::detail
