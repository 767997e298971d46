// The error-tolerant scanning controller.
#include "trueaxis/scan/controller.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "section.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::scan {
namespace {

// Free moves between touch points keep this much beyond the band the surface is searched in
// (mm): room for a part that is off its design by more than that band somewhere between them.
constexpr double kRouteMargin = 2.0;

// A design-value scan stops as a trajectory error when the probe's deflection comes within this
// fraction of the room the pushing leaves in its range (range − pushing): 0.07 mm of a 1 mm
// probe pushed 0.3 mm, about one servo tick of a surface rising 45° at 70 mm/s.
constexpr double kRangeGuard = 0.1;

// A local autonomous scan follows the part this far (mm), starting kLocalLead mm before the
// stop (then four times as far, if the part is not back on its design by then), and the part
// counts as back on its design within kRejoin times the trajectory tolerance.
constexpr double kLocalScan = 60, kLocalLead = 10, kRejoin = 0.03;

// Machine time of one operation, added to a category.
template <class Fn>
auto timed(Machine& m, double& bucket, Fn&& fn) {
  const double t0 = m.time();
  struct Add {
    Machine& m;
    double& b;
    double t0;
    ~Add() { b += m.time() - t0; }
  } add{m, bucket, t0};
  return fn();
}

struct SectionRun {
  SectionRun(const detail::SectionContext& c, design::Section section)
      : m(c.machine),
        o(c.options),
        nominal(c.planner),
        events(c.events),
        first_move(c.first_move),
        part_move(c.part_move),
        unreachable(c.unreachable),
        current(std::move(section)) {}
  Machine& m;
  const ControllerOptions& o;
  const Planner& nominal;  // against the design's solid
  std::vector<Event>& events;
  bool& first_move;  // the run's first free move rises along the stylus whatever is around
  std::vector<Correction>& part_move;  // the run's rigid corrections so far (section.hpp)
  std::vector<NotReachable>& unreachable;
  SectionResult r;
  design::Section current;
  // Against the solid moved by the corrections accepted for this section so far (what the
  // controller knows of where the part really is).
  std::optional<Planner> moved_planner;
  Eigen::Affine3d learnt = Eigen::Affine3d::Identity();
  // The design data changed (a correction, an overwrite) since the run checked that the ball can
  // come down to the section's ends.
  bool moved = false;
  const Planner& planner() const { return moved_planner ? *moved_planner : nominal; }

  // Free moves through waypoints whose legs the planner found clear by its margin: without a
  // stop at each waypoint where the margin leaves room for the corner the machine cuts there.
  void through(const std::vector<Eigen::Vector3d>& way) {
    if (planner().margin() >= 2 * Machine::kCornerCut)
      m.move_through(way, o.move_speed);
    else
      for (const auto& p : way) m.move(p, o.move_speed);
  }

  // A free move the planner finds: straight when clear of the part, else retract along the
  // stylus to the clearance level, across, and down. Where the planner finds no way (the ball
  // stands under an overhang, where a scan ended), it first moves out sideways, across the
  // stylus, to where it does (the nearest of 8 directions and 4 distances, in order).
  // `keep`: the margin to keep instead, when larger than the planner's.
  void safe_move(const Eigen::Vector3d& to, double keep = 0) {
    const Eigen::Vector3d from = m.position();
    if ((to - from).norm() < 1e-6) return;
    const Eigen::Vector3d u = m.stylus_axis();
    const std::optional<Planner> wider = keep > planner().margin()
                                             ? std::optional<Planner>(planner().with_margin(keep))
                                             : std::nullopt;
    const Planner& solid = wider ? *wider : planner();
    std::vector<Eigen::Vector3d> way;
    try {
      way = solid.route(from, to, u, first_move);
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
            way = solid.route(side, to, u, false);
            way.insert(way.begin(), side);
          } catch (const NoWay&) {
          }
        }
        if (!way.empty()) break;
      }
      if (way.empty()) throw;
    }
    first_move = false;
    timed(m, r.time.moves, [&] {
      through(way);
      return 0;
    });
  }

  // A free move in the section's plane from one touch start to the next (each at `reach` from
  // the design, the edge of the band the real surface is searched in), around the outside of
  // the design kRouteMargin beyond that: along the design's offset, cutting straight wherever
  // the chord keeps clear of the design.
  // The ball stands on the last touch's approach line, between the surface and `back_to` (that
  // touch's start); `from` and `to` are the samples nearest the two touches, `next_start` the
  // next touch's start.
  void route(const design::Samples& smp, const sim::Contour& design, double reach,
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
        if (design.nearest(p + (q - p) * (static_cast<double>(j) / k)).distance < keep)
          return false;
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
    timed(m, r.time.moves, [&] {
      through(legs);
      return 0;
    });
  }
  ScanSettings settings() const {
    ScanSettings st;
    st.pushing = o.path.pushing;
    st.active = o.active;
    st.record_spacing = o.record_spacing;
    // Start the approach beyond the band the real surface may lie in (the tolerance and 1.5 mm
    // more), so that the free move there cannot meet a part that is off its design.
    st.approach_clearance = o.tolerance + 1.5;
    st.approach_limit = o.tolerance + 1.0;
    return st;
  }
  void log(double arc, double dl, const std::string& mode, const std::string& ev,
           const std::string& decision) {
    events.push_back({m.time(), current.name, arc, dl, mode, ev, decision});
    if (ev == "trajectory_error" || ev == "touch") seen = std::max(seen, std::abs(dl));
  }
  // How far off its design (where the corrections put it) this section's surface was found so
  // far: the largest trajectory error and touch deviation since the last accepted correction,
  // or what that correction left at its touch points (mm).
  double seen = 0;

  // Where along the section's contour (mm, [from, to] pieces in order) the stylus keeps
  // `margin` from the design's solid where the corrections put it, the ball on the path.
  std::vector<std::pair<double, double>> room_with(double margin) const {
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

  // Reports [from, to] (mm along the section) as not scanned, and why.
  void cut_off(double from, double to, const std::string& why) {
    const auto smp = design::sample(current, 0.05);
    unreachable.push_back({current.name, from, to, detail::point_at(current, smp, from),
                           detail::point_at(current, smp, to), why});
    log(from, 0, "section", "not_reachable",
        fmt::format("{:.1f} to {:.1f} mm along the stretch not scanned: {}", from, to, why));
  }

  // Before a design-value scan: the ball must come down from above to where the scan starts
  // and ends (the reachability of the run's stretches was decided for the design data as they
  // were; a correction may have moved an end under the part, or down to the table). A closed
  // contour is started again where it can, an open stretch trimmed to where it can, the rest
  // reported as not reachable. False (the section not reachable) when nothing is left.
  bool reach_ends() {
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

  // Design-value scan; true when it ran through within the tolerance.
  bool design_scan(Sample& stop, std::string& why) {
    const auto path = design::make_path(current, o.path);
    const auto start = path.at(0);
    safe_move(start.p + settings().approach_clearance * start.normal);
    bool error = false, range = false;
    Trace tr;
    tr.label = r.traces.empty() ? "design" : fmt::format("rescan {}", r.traces.size());
    double next = 0;
    // The material side: a surface that comes nearer faster than the servo follows is taken up
    // by the probe's deflection alone, and a probe pushed beyond its range stops the machine (on
    // a real CMM an error state). So a deflection near the range is a trajectory error too, and
    // the scan stops before the probe does.
    const auto probe_range = m.probe_range();
    const double near_range =
        probe_range ? *probe_range - kRangeGuard * (*probe_range - o.path.pushing) : INFINITY;
    const auto out = timed(m, r.time.design, [&] {
      return m.scan_path(path, settings(), [&](const Sample& s) {
        if (s.arc >= next) {
          tr.arc.push_back(s.arc);
          tr.delta_l.push_back(s.delta_l);
          next = s.arc + 0.5;
        }
        range = s.contact && s.deflection >= near_range;
        if (range || std::abs(s.delta_l) > o.tolerance || (!o.active && !s.contact)) {
          error = true;
          return false;
        }
        return true;
      });
    });
    stop = out.stop;
    tr.arc.push_back(stop.arc);
    tr.delta_l.push_back(stop.delta_l);
    tr.completed = out.completed && !error;
    r.traces.push_back(std::move(tr));
    if (out.completed && !error) {
      r.points = out.samples;
      return true;
    }
    why = !out.fault.empty() ? out.fault
          : range
              ? fmt::format(
                    "the surface came nearer faster than the probe follows: its deflection "
                    "reached {:.3f} mm of its {:g} mm measuring range at ΔL {:+.3f} mm (stopped "
                    "before the probe's over-travel)",
                    stop.deflection, *probe_range, stop.delta_l)
          : !o.active && !stop.contact
              ? "the probe lifted off the surface"
              : fmt::format("trajectory error {:+.3f} mm beyond the ±{:g} mm tolerance",
                            stop.delta_l, o.tolerance);
    return false;
  }

  // Touch points along the design normals; returns the feet and touched points.
  std::pair<Eigen::Matrix3Xd, Eigen::Matrix3Xd> touch() {
    const double L = design::length(current);
    const int k = o.touch_points;
    const auto smp = design::sample(current, L / (current.closed ? k : k - 1) / 4);
    Eigen::Matrix3Xd feet(3, 0), got(3, 0);
    // Start just outside the band where the surface is looked for (the tolerance and 1.5 mm
    // more each way), and search across the band.
    constexpr double kMargin = 1.5;
    const double reach = o.path.tip_radius + o.tolerance + kMargin;
    const sim::Contour outline(smp.points, current.plane.normal.normalized(), current.closed,
                               current.material == design::Side::Left);
    // Evenly spread, or where they tell the part's move, turn and scale apart when evenly
    // spread ones do not (then each foot from samples 0.25 mm apart, not the route's).
    const auto places = detail::touch_places(current, k, detail::kTellsPart);
    const design::Samples fine = places.even ? design::Samples{} : design::sample(current, 0.25);
    if (!places.even)
      log(0, 0, "touch", "touch",
          fmt::format("touch points placed where they tell the part's move, turn and scale "
                      "apart (resolution {:.2f}; evenly spread, {:.2f})",
                      places.resolution, places.even_resolution));
    Eigen::Index last = -1;
    Eigen::Vector3d last_start = Eigen::Vector3d::Zero();
    for (const double arc : places.arcs) {
      const bool final_touch = &arc == &places.arcs.back();
      Eigen::Index j = 0, f = 0;
      (smp.arc.array() - arc).abs().minCoeff(&j);
      const design::Samples& at = places.even ? smp : fine;
      if (!places.even) (fine.arc.array() - arc).abs().minCoeff(&f);
      const Eigen::Vector3d p = at.points.col(places.even ? j : f),
                            nn = at.normals.col(places.even ? j : f);
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
      const auto t = timed(m, r.time.touch, [&] {
        auto got =
            m.touch(current.plane, last_start, -nn, 2 * (o.tolerance + kMargin) + o.touch_trigger,
                    o.touch_speed, o.touch_trigger);
        // After the last touch (or a search that found nothing, and went through the band),
        // back the way the ball came, to the touch's start: outside the band the part may be
        // in, where the next move can be planned against the design's solid. Before another
        // touch, the route to it leaves along that line anyway.
        if (final_touch || !got) m.move(last_start, o.move_speed);
        return got;
      });
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

  // The 2-D test: geometric correction and autonomous scanning work in a plane section. A
  // space curve that lies in a plane becomes that plane section; any other ends the section.
  bool two_dimensional(double arc, double dl) {
    if (!current.space_curve()) return true;
    std::string why;
    if (auto plane = design::as_plane_section(current, &why)) {
      current = *plane;
      log(arc, dl, "design", "two_dimensional",
          "the space curve lies in one plane: treated as a plane section from here on");
      return true;
    }
    r.reason = why +
               "; geometric correction and autonomous scanning need a plane section, so the "
               "section is not measured";
    log(arc, dl, "design", "error_exit", r.reason);
    return false;
  }

  // The stretch [from, to] (mm along the section, initially all of it) an autonomous scan keeps
  // to. The stylus's room was decided for the design with the planner's margin; a surface found
  // further off its design than that (less 1 mm) may stand nearer the stylus or the probe body
  // than the margin wherever the ball follows it. The scan then keeps to where the stylus has
  // that much room, and 1 mm more, from the design's solid (an open stretch: the longest such
  // piece, the rest reported not reachable), or is not made (false: a closed contour the stylus
  // could not follow all round, or nothing long enough left).
  bool autonomous_range(double& from, double& to) {
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

  bool autonomous() {
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
    const auto out = timed(m, r.time.autonomous, [&] {
      return m.scan_unknown(current.plane, p + reach * nn, -nn, current.material, current.closed,
                            // an open stretch: stop 1 mm short of its end, which may border
                            // on what the stylus cannot reach
                            current.closed ? L : std::max(1.0, to - smp.arc[best] - 1),
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
    log(0, 0, "autonomous", "design_overwritten",
        fmt::format("the section's design data replaced by the measured contour ({} points, "
                    "tip radius and pushing amount compensated)",
                    current.polyline.cols()));
    return true;
  }

  // A local deviation (the touch points agree with the design elsewhere, so no correction
  // fits): an autonomous scan from a little before the stop until the part is back on its
  // design, spliced into the design data, instead of following the whole contour (a 2 mm bump
  // on a 557 mm outline: ~60 mm at the autonomous speed instead of all of it). False when the
  // scans do not show the part leaving its design and coming back: the caller then scans the
  // whole contour.
  bool local_autonomous(const Sample& stop) {
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

  // Set when an autonomous scan measured the section but its contour could not become the
  // design data (autonomous()): the section is done.
  bool measured_only = false;

  // Why no scanning path can be made along s (empty if one can).
  std::string unpathable(const design::Section& s) const {
    try {
      design::make_path(s, o.path);
      return {};
    } catch (const Error& e) {
      return e.what();
    }
  }

  // Applies accepted corrections to the section's design data and to where the planner stands
  // the solid.
  void correct_by(const Eigen::Affine3d& step) {
    // The design's solid follows the corrected curve (the nominal planner already stands it at
    // the section's placement).
    detail::move_section(current, step);
    learnt = step * learnt;
    moved = true;
    moved_planner.emplace(nominal.moved(learnt));
  }

  // Before the first scan: where the part stands, as the corrections an earlier section found.
  void carry_part_move() {
    if (part_move.empty() || current.space_curve() ||
        !std::all_of(part_move.begin(), part_move.end(), [&](const Correction& c) {
          return detail::keeps_plane(current, c.transform);
        }))
      return;
    Eigen::Affine3d step = Eigen::Affine3d::Identity();
    std::string what;
    for (const auto& c : part_move) {
      step = c.transform * step;
      r.corrections.push_back(c);
      const std::string params = fmt::format(" {}", c.parameters_text());
      what += fmt::format("{}{} ({}:{})", what.empty() ? "" : ", ", c.found_on, c.type, params);
    }
    correct_by(step);
    log(0, 0, "correction", "correction_carried",
        fmt::format("the part is where the touch points of {} found it: corrections applied "
                    "before the first scan",
                    what));
  }

  // The part's move as each round of this section's own touch points told it, by the index in
  // r.corrections of the correction that round accepted.
  std::vector<std::pair<std::size_t, PartMove>> told;

  // After the section: where it found the part is where the part stands for the sections after
  // it (detail::part_move_of).
  void hand_on_part_move() const {
    if (auto moved = detail::part_move_of(r.corrections, told, current.closed, current.name))
      part_move = std::move(*moved);
  }

  void run() {
    r.name = current.name;
    const double t0 = m.time();
    if (o.strategy == Strategy::ErrorTolerant) carry_part_move();
    if (o.strategy == Strategy::Autonomous) {
      r.ok = autonomous();
      if (r.ok) log(0, 0, "section", "section_done", "measured by autonomous scanning only");
      r.time.total = m.time() - t0;
      return;
    }
    int flag = 0;
    for (int loop = 0;; ++loop) {
      Sample stop;
      std::string why;
      if (!reach_ends()) break;
      if (design_scan(stop, why)) {
        r.ok = true;
        log(stop.arc, stop.delta_l, "design", "section_done",
            loop == 0 ? "scanned along the design" : "rescan succeeded");
        break;
      }
      ++r.trajectory_errors;
      if (o.strategy == Strategy::Design) {
        log(stop.arc, stop.delta_l, "design", "error_exit", why);
        r.reason = why;
        break;
      }
      log(stop.arc, stop.delta_l, "design", "trajectory_error", why);
      if (!two_dimensional(stop.arc, stop.delta_l)) break;
      bool corrected = false, local = false;
      if (flag == 0) {
        auto [feet, got] = touch();
        if (got.cols() >= 4) {
          design::Section fixed;
          PartMove told_here;
          auto tried = fit_corrections(current, feet, got, o.accept, &fixed, &told_here);
          for (const auto& c : tried) {
            if (c.type == "none") {
              local = true;
              log(stop.arc, stop.delta_l, "correction", "correction_rejected",
                  fmt::format("the touch points agree with the design within {:.4f} mm: the "
                              "deviation is local, no geometric correction fits it",
                              c.residual_before));
              continue;
            }
            const std::string params = fmt::format(" {}", c.parameters_text());
            if (!c.diverged.empty())
              log(stop.arc, stop.delta_l, "correction", "correction_rejected",
                  fmt::format("{}: the fit diverged ({}); where it stopped:{}", c.type, c.diverged,
                              params));
            else
              log(stop.arc, stop.delta_l, "correction",
                  c.accepted ? "correction_applied" : "correction_rejected",
                  fmt::format("{}:{}; touch points within {:.4f} mm (were {:.4f})", c.type, params,
                              c.residual_after, c.residual_before));
            if (c.accepted) corrected = true;
          }
          for (const auto& c : tried)
            if (c.type != "none") r.corrections.push_back(c);
          if (corrected) {
            // What these touch points tell of the whole part, to hand on (hand_on_part_move).
            told.push_back({r.corrections.size() - 1, std::move(told_here)});
            Eigen::Affine3d step = Eigen::Affine3d::Identity();
            for (const auto& c : tried)
              if (c.accepted) step = c.transform * step;
            // The fit's own corrected curve (the same map, applied as the fit did).
            correct_by(step);
            // Where the planner now stands the part, what is left known of its offset is what
            // the accepted corrections left at the touch points (a later trajectory error adds
            // what they could not see).
            seen = 0;
            for (const auto& c : tried)
              if (c.accepted) seen = std::max(seen, c.residual_after);
            current.polyline = fixed.polyline;
            current.nurbs = fixed.nurbs;
          }
        } else {
          log(stop.arc, stop.delta_l, "correction", "correction_rejected",
              fmt::format("only {} touch points found: no correction can be fitted", got.cols()));
        }
      }
      if (corrected) {
        flag = 1;
        log(stop.arc, stop.delta_l, "design", "rescan", "rescan with the corrected design data");
        continue;
      }
      if (r.autonomous_count >= o.max_autonomous) {
        r.reason = fmt::format("loop limit: still failing after {} autonomous corrections",
                               r.autonomous_count);
        log(stop.arc, stop.delta_l, "autonomous", "loop_limit", r.reason);
        break;
      }
      // A failure the touch points do not show (they agree with the design, or with the
      // correction just applied) is local: scanned round the stop, the rest kept.
      local = local || flag == 1;
      if (!(local && local_autonomous(stop)) && !autonomous()) break;
      if (measured_only) {
        r.ok = true;
        break;
      }
      flag = 0;
      log(0, 0, "design", "rescan", "rescan in design mode with the measured design data");
    }
    hand_on_part_move();
    r.time.total = m.time() - t0;
  }
};

}  // namespace

namespace detail {
SectionResult run_section(const SectionContext& c, design::Section& section) {
  SectionRun run(c, section);
  try {
    run.run();
  } catch (...) {
    // What the section measured before it stopped stays in its result: the caller records why.
    section = run.current;
    c.partial = std::move(run.r);
    throw;
  }
  section = run.current;
  return std::move(run.r);
}
}  // namespace detail

}  // namespace trueaxis::scan
