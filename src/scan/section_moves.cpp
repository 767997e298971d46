// The error-tolerant controller's free moves and touch points on one section.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "section_run.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::scan::detail {
namespace {

// Free moves between touch points keep this much beyond the band the surface is searched in
// (mm): room for a part that is off its design by more than that band somewhere between them.
constexpr double kRouteMargin = 2.0;
// Free moves slow to the machine's guarded speed where the ball, the stylus or the probe's body
// comes within this much beyond what the section keeps from the part's design (mm): a part that
// far further off than the move allows for stops it on the probe's trigger, not in a collision.
constexpr double kGuardBand = 2.0;
// Until the run has found the part, free moves are guarded this much further out (mm): a part
// placed up to about 13 mm off its design (the margin, both bands and the 1 mm the guarded speed
// stops in) is met by the probe at the guarded speed on the first moves to it, not at full speed.
constexpr double kUnfoundBand = 10.0;
// What speeding up to a leg's speed and slowing down from it adds to the leg's time at that speed,
// at the move speed (s; v/a: 200 mm/s at 2000 mm/s²); at lower speeds in proportion. Only ways
// are compared with it.
constexpr double kLegRamp = 0.1;
}  // namespace

std::pair<std::vector<Eigen::Vector3d>, std::vector<double>> SectionRun::guarded(
    const std::vector<Eigen::Vector3d>& way, const Eigen::Vector3d& from) const {
  const std::optional<double> slow = guard_speed();
  if (!slow || *slow >= o.move_speed || !planner().part())
    return {way, std::vector<double>(way.size(), o.move_speed)};
  const Planner& solid = planner();
  const Eigen::Vector3d u = m.stylus_axis();
  const double band = std::max({solid.margin(), seen + 1, off_design + 1}) + kGuardBand +
                      (found ? 0.0 : kUnfoundBand);
  // How far from a along the leg to b the band is first entered (the leg's length if never):
  // steps never longer than the clearance beyond the band (every element moves as far as the
  // ball), nor shorter than 0.2 mm.
  auto enters = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const double L = (b - a).norm();
    for (double t = 0; t <= L;) {
      const double c = solid.part_clearance(a + (b - a) * (t / L), u);
      if (c < band) return t;
      t += std::max(0.2, c - band);
    }
    return L;
  };
  // A way that ends coming down along the stylus beside the part comes down further out where
  // that leaves less of it to go at the guarded speed: down a column whose foot lies outside the
  // band (one of 16 directions across the stylus), then across to its end.
  auto slow_down = [&](const Eigen::Vector3d& top, const Eigen::Vector3d& foot) {
    return (foot - top).norm() - enters(top, foot);
  };
  std::vector<Eigen::Vector3d> to_go = way;
  if (const std::size_t n = to_go.size(); n >= 2) {
    const Eigen::Vector3d top = to_go[n - 2], end = to_go[n - 1];
    const Eigen::Vector3d down = end - top;
    const Eigen::Vector3d before = n >= 3 ? to_go[n - 3] : from;
    const double c_end = solid.clearance(end, u);
    if (down.dot(u) < 0 && down.cross(u).norm() < 1e-6 * down.norm() &&
        solid.part_clearance(end, u) < band) {
      const Eigen::Vector3d e1 = u.unitOrthogonal(), e2 = u.cross(e1);
      double best = slow_down(top, end);
      std::optional<Eigen::Vector3d> shift;
      for (int k = 0; k < 16 && best > 0; ++k) {
        const double t = std::numbers::pi / 8 * k;
        const Eigen::Vector3d h = std::cos(t) * e1 + std::sin(t) * e2;
        for (double d = 0.5; d <= band + 1 && d < best; d += 0.5) {
          const Eigen::Vector3d q = end + d * h;
          if (solid.part_clearance(q, u) < band) continue;
          if (solid.clear(q, end, u, std::min(solid.margin(), c_end - 0.01)) &&
              solid.clear(top + d * h, q, u, solid.margin()) &&
              solid.clear(before, top + d * h, u, solid.margin())) {
            const double cost = slow_down(top + d * h, q) + d;
            if (cost < best) {
              best = cost;
              shift = d * h;
            }
          }
          break;
        }
      }
      if (shift) {
        to_go[n - 2] = top + *shift;
        to_go.insert(to_go.end() - 1, end + *shift);
      }
    }
  }
  std::vector<Eigen::Vector3d> legs;
  std::vector<double> speeds;
  Eigen::Vector3d a = from;
  for (const Eigen::Vector3d& b : to_go) {
    const double L = (b - a).norm();
    if (L < 1e-9) {
      legs.push_back(b);
      speeds.push_back(o.move_speed);
      continue;
    }
    // A rise along the stylus takes the ball through where the stylus stood: not slowed.
    const bool rise = (b - a).dot(u) > 0 && (b - a).cross(u).norm() < 1e-6 * L;
    const double in = rise ? L : enters(a, b);
    const double out = in >= L ? L : L - enters(b, a);
    const Eigen::Vector3d d = (b - a) / L;
    if (in >= L) {
      legs.push_back(b);
      speeds.push_back(o.move_speed);
    } else {
      if (in > 1e-6) {
        legs.push_back(a + in * d);
        speeds.push_back(o.move_speed);
      }
      legs.push_back(a + std::max(in, out) * d);
      speeds.push_back(*slow);
      if (out < L - 1e-6) {
        legs.push_back(b);
        speeds.push_back(o.move_speed);
      }
    }
    a = b;
  }
  return {legs, speeds};
}

double SectionRun::way_time(const std::vector<Eigen::Vector3d>& way,
                            const Eigen::Vector3d& from) const {
  const auto [legs, speeds] = guarded(way, from);
  double t = 0;
  Eigen::Vector3d a = from;
  for (std::size_t k = 0; k < legs.size(); ++k) {
    t += (legs[k] - a).norm() / speeds[k] + kLegRamp * speeds[k] / o.move_speed;
    a = legs[k];
  }
  return t;
}

void SectionRun::through(const std::vector<Eigen::Vector3d>& way, bool guard) {
  const Eigen::Vector3d from = m.position();
  auto [legs, speeds] =
      guard ? guarded(way, from) : std::pair{way, std::vector<double>(way.size(), o.move_speed)};
  try {
    if (planner().margin() >= 2 * Machine::kCornerCut)
      m.move_legs(legs, speeds);
    else
      m.Machine::move_legs(legs, speeds);  // one move per waypoint, stopping at each
  } catch (const UnexpectedTouch& e) {
    // Back the way the ball came, at the guarded speed, to the last waypoint it passed (where
    // the guarded leg began, or where the move started): free there when it passed.
    ++unexpected;
    const Eigen::Vector3d back = e.passed > 0 ? legs[std::min(e.passed, legs.size()) - 1] : from;
    try {
      m.move(back, std::min(o.move_speed, guard_speed().value_or(o.move_speed)));
    } catch (const UnexpectedTouch& again) {
      throw Error(fmt::format("{}; on the way back the probe stopped the machine again: {}",
                              e.what(), again.what()));
    }
    const double off = planner().clearance(e.at, m.stylus_axis());
    seen = std::max(seen, off);
    off_design = std::max(off_design, off);
    // Scans and touches start outside the band the part may be in, now as far as it was met,
    // and at least 1 mm further out each time: where the part is met near a start, how far it
    // is off there is known only as at least that.
    found_extra = std::max(found_extra + 1, off + 1 - (o.tolerance + kBandMargin));
    log(0, 0, "correction", "unexpected_touch",
        fmt::format("{}: the part stands at least {:.2f} mm off its design there; the ball went "
                    "back the way it came, and free moves on this section keep {:.2f} mm from it",
                    e.what(), off, seen + 1));
    throw;
  }
}

void SectionRun::safe_move(const Eigen::Vector3d& to, double keep) {
  const Eigen::Vector3d from = m.position();
  if ((to - from).norm() < 1e-6) return;
  const Eigen::Vector3d u = m.stylus_axis();
  auto plan = [&](const Planner& solid) {
    std::vector<Eigen::Vector3d> way;
    try {
      way = solid.route(
          from, to, u, first_move,
          [&](const std::vector<Eigen::Vector3d>& w) { return way_time(w, from); },
          1 / o.move_speed);
    } catch (const NoWay&) {
      // Not on the run's first move: where the machine stands then is not trusted.
      if (first_move) throw;
      const Eigen::Vector3d e1 = u.unitOrthogonal(), e2 = u.cross(e1);
      const double margin = std::min(solid.margin(), solid.clearance(from, u) - 0.01);
      for (const double d : {5.0, 10.0, 20.0, 40.0}) {
        for (int k = 0; k < 8 && way.empty(); ++k) {
          const double t = std::numbers::pi / 4 * k;
          const Eigen::Vector3d side = from + d * (std::cos(t) * e1 + std::sin(t) * e2);
          if (!solid.clear(from, side, u, margin)) continue;
          try {
            way = solid.route(
                side, to, u, false,
                [&](const std::vector<Eigen::Vector3d>& w) { return way_time(w, side); },
                1 / o.move_speed);
            way.insert(way.begin(), side);
          } catch (const NoWay&) {
          }
        }
        if (!way.empty()) break;
      }
      if (way.empty()) throw;
    }
    return way;
  };
  // Where this section found the part further off its design than the margin allows for, less
  // 1 mm (a trajectory error, a touch point), the move keeps 1 mm more than that from the part
  // where the planner stands it, as the route between touch points does; as far as the target
  // itself lies from it. Where no way keeps that much, the planner's margin (or `keep`) is kept.
  std::vector<Eigen::Vector3d> way;
  const double kept = std::max(keep, planner().margin());
  if (seen + 1 > kept) {
    const double found = std::min(seen + 1, planner().clearance(to, u) - 0.01);
    if (found > kept) {
      try {
        way = plan(planner().with_margin(found));
      } catch (const NoWay&) {
        way.clear();
      }
    }
  }
  if (way.empty()) way = plan(keep > planner().margin() ? planner().with_margin(keep) : planner());
  first_move = false;
  try {
    timed(m, r.time.moves, [&] {
      through(way);
      return 0;
    });
  } catch (const UnexpectedTouch& e) {
    // Planned again from where the move started, keeping what the touch found, when the target
    // itself keeps that much; otherwise the caller finds another (a scan's start further out).
    const std::string why = fmt::format(
        "the part stands further off its design than the free move to ({:.2f}, {:.2f}, {:.2f}) "
        "mm can keep from it ({} unexpected touches, the last at ({:.2f}, {:.2f}, {:.2f}) mm)",
        to.x(), to.y(), to.z(), unexpected, e.at.x(), e.at.y(), e.at.z());
    if (unexpected >= kMostUnexpected || planner().clearance(to, u) < seen + 1) throw NoWay(why);
    safe_move(to, keep);
  }
}

void SectionRun::route(const design::Samples& smp, const sim::Contour& design, double reach,
                       Eigen::Index from, Eigen::Index to, const Eigen::Vector3d& back_to,
                       const Eigen::Vector3d& next_start) {
  const Eigen::Index n = smp.points.cols();
  // Waypoints kRouteMargin beyond the touch starts; chords between them may cut in to half
  // of that margin.
  const double keep = reach + 0.5 * kRouteMargin;
  reach += kRouteMargin;
  std::vector<Eigen::Vector3d> way;
  for (Eigen::Index k = from;; k = (k + 1) % n) {
    const Eigen::Index next = (k + 1) % n;
    way.push_back(smp.points.col(k) + reach * smp.normals.col(k));
    if (k == to) break;
    // Round a corner (normals turning by more than 15°) on an arc of waypoints.
    const Eigen::Vector3d a = smp.normals.col(k), b = smp.normals.col(next);
    const double turn = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
    const int steps = static_cast<int>(turn / (M_PI / 12));
    const Eigen::Vector3d corner = smp.points.col(next);
    for (int j = 1; j <= steps; ++j) {
      const double f = static_cast<double>(j) / (steps + 1);
      way.push_back(corner + reach * ((1 - f) * a + f * b).normalized());
    }
  }
  auto clear = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    const int k = std::max(2, static_cast<int>((q - p).norm() / 0.5));
    for (int j = 0; j <= k; ++j)
      if (design.nearest(p + (q - p) * (static_cast<double>(j) / k)).distance < keep) return false;
    return true;
  };
  // Back out along the last touch's approach line to the route (the touch start lies on the
  // way), round, and in along the next touch's approach line; every leg clear of the part's
  // solid, or else the planner's way (over the part).
  std::vector<Eigen::Vector3d> legs{way.front()};
  std::size_t at = 0;
  while (at + 1 < way.size()) {
    std::size_t best = at + 1;
    for (std::size_t j = way.size() - 1; j > at + 1; --j)
      if (clear(way[at], way[j])) {
        best = j;
        break;
      }
    legs.push_back(way[best]);
    at = best;
  }
  legs.push_back(next_start);
  // The legs keep the planner's margin from the solid where the corrections put it, or 1 mm
  // more than the touches found the part off it: a correction carried from another section
  // may be wrong here by more than the margin allows for. The first and the last leg follow
  // the touches' approach lines, out from the surface just touched and in to the edge of the
  // band the next touch searches: each may come as near as its nearer end, no nearer.
  const Planner& solid = planner();
  const Eigen::Vector3d u = m.stylus_axis();
  const double keep_off = std::max(solid.margin(), seen + 1);
  const double at_next = std::min(keep_off, solid.clearance(next_start, u) - 0.01);
  Eigen::Vector3d leg_start = m.position();
  double margin = std::min(keep_off, solid.clearance(leg_start, u) - 0.01);
  for (std::size_t k = 0; k < legs.size(); ++k) {
    const Eigen::Vector3d& p = legs[k];
    if (k + 1 == legs.size()) margin = std::min(margin, at_next);
    if (!solid.clear(leg_start, p, u, margin)) {
      // The planner's way (over the part), from the touch's start, outside the band.
      timed(m, r.time.moves, [&] {
        m.move(back_to, o.move_speed);
        return 0;
      });
      safe_move(next_start, at_next);
      return;
    }
    leg_start = p;
    margin = keep_off;
  }
  try {
    timed(m, r.time.moves, [&] {
      through(legs, false);
      return 0;
    });
  } catch (const UnexpectedTouch&) {
    // Back at the last touch's approach line: the planner's way, keeping what the touch found.
    safe_move(next_start, at_next);
  }
}

std::vector<std::pair<double, double>> SectionRun::room_with(double margin) const {
  const double L = design::length(current);
  const design::ScanPath path = design::make_path(current, o.path);
  const auto blocked = planner().with_margin(margin).unreachable(path, m.stylus_axis());
  const auto smp = design::sample(current, 0.05);
  std::vector<std::pair<double, double>> free;
  double at = 0;
  for (const auto& b : blocked) {
    const double a0 = b.from <= 0 ? 0 : detail::contour_arc(smp, path, b.from) - 0.5;
    const double a1 = b.to >= path.length() ? L : detail::contour_arc(smp, path, b.to) + 0.5;
    if (a0 > at) free.emplace_back(at, a0);
    at = std::max(at, a1);
  }
  if (at < L) free.emplace_back(at, L);
  return free;
}

void SectionRun::cut_off(double from, double to, const std::string& why) {
  const auto smp = design::sample(current, 0.05);
  unreachable.push_back({current.name, from, to, detail::point_at(current, smp, from),
                         detail::point_at(current, smp, to), why});
  log(from, 0, "section", "not_reachable",
      fmt::format("{:.1f} to {:.1f} mm along the stretch not scanned: {}", from, to, why));
}

bool SectionRun::reach_ends() {
  if (!planner().part() || current.space_curve() || !moved) return true;
  moved = false;
  const double approach = settings().approach_clearance;
  const std::string covered =
      "the part, where the corrections put it, covers it: no way down to it from above";
  if (current.closed) {
    const auto a = detail::reachable_start(current, planner(), o, approach);
    if (!a) {
      r.not_reachable = true;
      r.reason = "not reachable: " + covered;
      log(0, 0, "section", "error_exit", r.reason);
      return false;
    }
    if (*a > 0) {
      log(*a, 0, "section", "restart",
          fmt::format("the contour is scanned from {:.0f} mm along it, where the ball can come "
                      "down to it",
                      *a));
      current = detail::started_at(current, *a);
    }
    return true;
  }
  const double L = design::length(current);
  const auto ends = detail::reachable_ends(current, 0, L, planner(), o, approach);
  if (!ends) {
    const auto smp = design::sample(current, 0.05);
    unreachable.push_back({current.name, 0, L, detail::point_at(current, smp, 0),
                           detail::point_at(current, smp, L), covered});
    r.not_reachable = true;
    r.reason = "not reachable: " + covered;
    log(0, 0, "section", "error_exit", r.reason);
    return false;
  }
  const auto [a, b] = *ends;
  if (a == 0 && b == L) return true;
  // Each piece cut off is reported, as the run reports the stretches it leaves out.
  if (a > 0) cut_off(0, a, covered);
  if (b < L) cut_off(b, L, covered);
  current = design::piece(current, a, b, current.name);
  return true;
}

int SectionRun::touch_count() const {
  // touch_places spreads a closed contour's points over all of it, an open stretch's over the
  // middle nine tenths.
  const double span = (current.closed ? 1.0 : 0.9) * design::length(current);
  const double spacing = kTouchSpacing * 2 * o.path.tip_radius;
  const int fit = static_cast<int>(std::floor(span / spacing)) + (current.closed ? 0 : 1);
  return std::min(o.touch_points, fit);
}

std::pair<Eigen::Matrix3Xd, Eigen::Matrix3Xd> SectionRun::touch() {
  const double L = design::length(current);
  const int k = touch_count();
  if (k < kFewestTouches) return {Eigen::Matrix3Xd(3, 0), Eigen::Matrix3Xd(3, 0)};
  const auto smp = design::sample(current, L / (current.closed ? k : k - 1) / 4);
  Eigen::Matrix3Xd feet(3, 0), got(3, 0);
  // Start just outside the band where the surface is looked for (the tolerance and 1.5 mm
  // more each way), and search across the band.
  // About a guessed design the band reaches further out by the guess's move (approach_extra),
  // and as far as an unexpected touch found the part (found_extra).
  const double reach = o.path.tip_radius + o.tolerance + kBandMargin + approach_extra + found_extra;
  const sim::Contour outline(smp.points, current.plane.normal.normalized(), current.closed,
                             current.material == design::Side::Left);
  // Evenly spread, or where they tell the part's move, turn and scale apart when evenly
  // spread ones do not (then each foot from samples 0.25 mm apart, not the route's).
  // Where the ball can come down to the touch's start from above (and, about a guessed design,
  // where that start keeps the margin from the part as designed too).
  const Eigen::Vector3d u = m.stylus_axis();
  auto usable = [&](const Eigen::Vector3d& foot, const Eigen::Vector3d& normal) {
    const Eigen::Vector3d start = foot + reach * normal;
    if (unguessed && nominal.part() && nominal.clearance(start, u) < nominal.margin()) return false;
    return planner().from_above(start, u);
  };
  const auto places = detail::touch_places(current, k, detail::kTellsPart, usable);
  const design::Samples fine = places.even ? design::Samples{} : design::sample(current, 0.25);
  if (places.unreachable > 0)
    log(0, 0, "touch", "touch",
        fmt::format("{} of the evenly spread touch points moved to where the ball can come "
                    "down to their start (resolution {:.2f})",
                    places.unreachable, places.resolution));
  if (!places.even && places.resolution > places.even_resolution)
    log(0, 0, "touch", "touch",
        fmt::format("touch points placed where they tell the part's move, turn and scale "
                    "apart (resolution {:.2f}; evenly spread, {:.2f})",
                    places.resolution, places.even_resolution));
  Eigen::Index last = -1;
  Eigen::Vector3d last_start = Eigen::Vector3d::Zero();
  // A round that can no longer find the points a correction needs stops there (a part far off
  // its design, searched for along normals that miss it: ~1 s a point for nothing).
  const auto total = static_cast<Eigen::Index>(places.arcs.size());
  Eigen::Index tried = 0;
  auto hopeless = [&] {
    if (got.cols() + (total - tried) >= kFewestTouches) return false;
    log(0, 0, "touch", "touch",
        fmt::format("touch round stopped after {} of {} points: with {} found, it cannot give "
                    "the {} a correction needs",
                    tried, total, got.cols(), kFewestTouches));
    return true;
  };
  for (const double arc : places.arcs) {
    if (tried > 0 && hopeless()) break;
    ++tried;
    const bool final_touch = &arc == &places.arcs.back();
    Eigen::Index j = 0, f = 0;
    (smp.arc.array() - arc).abs().minCoeff(&j);
    const design::Samples& at = places.even ? smp : fine;
    if (!places.even) (fine.arc.array() - arc).abs().minCoeff(&f);
    const Eigen::Vector3d p = at.points.col(places.even ? j : f),
                          nn = at.normals.col(places.even ? j : f);
    // About a guessed design, from where the part as designed leaves the planner's margin too.
    if (unguessed && nominal.part() &&
        nominal.clearance(p + reach * nn, m.stylus_axis()) < nominal.margin()) {
      log(arc, 0, "touch", "touch",
          fmt::format("touch point left out: its start lies within {:g} mm of the part where the "
                      "design puts it, and the guessed move is not confirmed",
                      nominal.margin()));
      continue;
    }
    try {
      if (last < 0)
        safe_move(p + reach * nn);
      else
        route(smp, outline, reach, last, j, last_start, p + reach * nn);
    } catch (const NoWay& e) {
      // The next touch point is tried with a free move planned from wherever the machine
      // stands (a route may have stopped part way).
      log(arc, 0, "touch", "touch",
          fmt::format("touch point left out: no free way to its start ({})", e.what()));
      last = -1;
      continue;
    }
    last = j;
    last_start = p + reach * nn;
    std::optional<Touch> t;
    try {
      t = timed(m, r.time.touch, [&] {
        auto got = m.touch(
            current.plane, last_start, -nn,
            2 * (o.tolerance + kBandMargin) + approach_extra + found_extra + o.touch_trigger,
            o.touch_speed, o.touch_trigger);
        // After the last touch (or a search that found nothing, and went through the band),
        // back the way the ball came, to the touch's start: outside the band the part may be
        // in, where the next move can be planned against the design's solid. Before another
        // touch, the route to it leaves along that line anyway.
        if (final_touch || !got) m.move(last_start, o.move_speed);
        return got;
      });
    } catch (const UnexpectedTouch& e) {
      // The stem, or the ball off the plane, met the part first: no point the probe can place.
      m.move(last_start, std::min(o.move_speed, guard_speed().value_or(o.move_speed)));
      ++unexpected;
      log(arc, 0, "touch", "unexpected_touch", fmt::format("touch point left out: {}", e.what()));
      last = -1;
      if (unexpected >= kMostUnexpected) break;
      continue;
    }
    if (!t) {
      log(arc, 0, "touch", "touch", "no surface found along the design normal here");
      continue;
    }
    const double dev = (t->surface - p).dot(nn);
    log(arc, dev, "touch", "touch", fmt::format("surface {:+.4f} mm from the design", dev));
    feet.conservativeResize(3, feet.cols() + 1);
    got.conservativeResize(3, got.cols() + 1);
    feet.col(feet.cols() - 1) = p;
    got.col(got.cols() - 1) = t->surface;
  }
  return {feet, got};
}

}  // namespace trueaxis::scan::detail
