// The error-tolerant scanning controller: on one section, design-value scans, touch points and
// corrections, and autonomous scans, in the order the section's trajectory errors call for.
#include "trueaxis/scan/controller.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "section_run.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::scan::detail {
namespace {
// A design-value scan stops as a trajectory error when the probe's deflection comes within this
// fraction of the room the pushing leaves in its range (range − pushing): 0.07 mm of a 1 mm
// probe pushed 0.3 mm, about one servo tick of a surface rising 45° at 70 mm/s.
constexpr double kRangeGuard = 0.1;
}  // namespace

bool SectionRun::design_scan(Sample& stop, std::string& why) {
  const auto& path = scanned_path.emplace(design::make_path(current, o.path));
  const auto start = path.at(0);
  // Where an unexpected touch on the way found the part further off than the approach allows
  // for, the approach starts further out (found_extra).
  for (;;) {
    const int before = unexpected;
    try {
      safe_move(start.p + settings().approach_clearance * start.normal);
      break;
    } catch (const NoWay&) {
      if (unexpected == before || unexpected >= kMostUnexpected) throw;
    }
  }
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
    partial.clear();
    return true;
  }
  partial = out.samples;
  why = !out.fault.empty() ? out.fault
        : range            ? fmt::format(
                                 "the surface came nearer faster than the probe follows: its deflection "
                                            "reached {:.3f} mm of its {:g} mm measuring range at ΔL {:+.3f} mm (stopped "
                                            "before the probe's over-travel)",
                                 stop.deflection, *probe_range, stop.delta_l)
        : !o.active && !stop.contact
            ? "the probe lifted off the surface"
            : fmt::format("trajectory error {:+.3f} mm beyond the ±{:g} mm tolerance", stop.delta_l,
                          o.tolerance);
  return false;
}

bool SectionRun::two_dimensional(double arc, double dl) {
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

bool SectionRun::fit_touches(const Sample& stop, const Eigen::Matrix3Xd& feet,
                             const Eigen::Matrix3Xd& got, bool nominal,
                             const design::Section& touched_on, bool& local,
                             const std::string& what) {
  bool corrected = false;
  design::Section fixed;
  PartMove told_here;
  auto tried = fit_corrections(current, feet, got, o.accept, &fixed, &told_here);
  Eigen::Index pooled = 0;
  auto solid = solid_instead(tried, pooled);
  // Where a move of the solid fits instead, the menu's candidates are logged as rejected for it.
  const std::string instead =
      solid ? ": a move of the part's solid fits them, and those of the sections before, as well"
            : "";
  for (auto& c : tried) {
    if (solid) c.accepted = false;
    if (c.type == "none") {
      local = true;
      log(stop.arc, stop.delta_l, "correction", "correction_rejected",
          fmt::format("the {} agree with the design within {:.4f} mm: the "
                      "deviation is local, no geometric correction fits it",
                      what, c.residual_before));
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
          fmt::format("{}:{}; {} within {:.4f} mm (were {:.4f}){}", c.type, params, what,
                      c.residual_after, c.residual_before, instead));
    if (c.accepted) corrected = true;
  }
  for (const auto& c : tried)
    if (c.type != "none") r.corrections.push_back(c);
  if (solid) {
    auto& [move, cut] = *solid;
    if (unguessed)
      r.corrections.erase(r.corrections.begin(),
                          r.corrections.begin() + static_cast<std::ptrdiff_t>(guess.size()));
    r.corrections.push_back(move);
    // Touch points in one plane tell the move in it; the planner stands the solid there.
    current = std::move(cut);
    learnt = Eigen::Affine3d::Identity();
    took(detail::in_plane_part(move.transform, current.plane));
    seen = move.residual_after;
    log(stop.arc, stop.delta_l, "correction", "correction_applied",
        fmt::format("solid-move: {}; these {} and the {} points before them all within "
                    "{:.4f} mm of the part's solid moved so (were {:.4f}): the section's design "
                    "data cut from it (points in one plane tell such a move only up to its "
                    "mirror image across the plane, which cuts the plane alike)",
                    move.parameters_text(), what, pooled - got.cols(), move.residual_after,
                    move.residual_before));
    return true;
  }
  if (corrected) {
    // What these touch points tell of the whole part, to hand on (hand_on_part_move).
    told.push_back({r.corrections.size() - 1, std::move(told_here)});
    if (nominal) own_rounds.push_back({touched_on, feet, got});
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
  return corrected;
}

void SectionRun::run() {
  r.name = current.name;
  const double t0 = m.time();
  if (o.strategy == Strategy::ErrorTolerant) {
    carry_part_move();
    if (r.corrections.empty()) guess_part_move();
  }
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
      if (unguessed) confirm_by_points();
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
    if (flag == 0 && rest_autonomous(stop)) break;
    bool corrected = false, local = false;
    if (flag == 0) {
      const bool nominal = as_designed;
      const design::Section touched_on = current;
      auto [feet, got] = touch();
      if (got.cols() >= kFewestTouches && this->nominal.part()) {
        touched.push_back({this->nominal.part().get(), current.name, current.plane, got});
        made_round = true;
      }
      if (got.cols() >= kFewestTouches) {
        corrected = fit_touches(stop, feet, got, nominal, touched_on, local);
      } else if (const int k = touch_count(); k < kFewestTouches) {
        log(stop.arc, stop.delta_l, "correction", "correction_rejected",
            fmt::format("no touch points made: the {:.1f} mm long {} holds {} a ball's diameter "
                        "apart, and a correction needs {}",
                        design::length(current), current.closed ? "contour" : "stretch",
                        std::max(k, 0), kFewestTouches));
      } else {
        log(stop.arc, stop.delta_l, "correction", "correction_rejected",
            fmt::format("only {} touch points found: no correction can be fitted", got.cols()));
      }
      if (unguessed) {
        // Touch points that agree with the guessed design confirm it (corrected: correct_by
        // made it this section's); otherwise the section starts again without it.
        if (local) {
          confirm_guess();
        } else if (!corrected) {
          drop_guess(stop);
          // The touch points are the part's wherever the guess put the design data: fitted
          // again to those data without it, they may still correct the section (a part scaled
          // about its middle: a stretch on one side suggests a move the other side's refutes,
          // and its touch points tell that side's own move).
          const sim::Contour curve = detail::contour_of(current);
          Eigen::Matrix3Xd at(3, got.cols());
          for (Eigen::Index i = 0; i < got.cols(); ++i) at.col(i) = curve.nearest(got.col(i)).point;
          bool agree = false;
          if (got.cols() >= kFewestTouches)
            corrected = fit_touches(stop, at, got, true, current, agree);
          if (!corrected) {
            if (!beyond_margin(stop, curve, got)) break;
            continue;
          }
        }
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
    if (local && local_autonomous(stop)) {
      flag = 0;
      log(0, 0, "design", "rescan", "rescan in design mode with the spliced design data");
      continue;
    }
    if (!autonomous()) break;
    // The whole section (or all of the stretch it can follow) is measured: the autonomous scan
    // is the measurement, and its contour the design data for the next part. A rescan in design
    // mode would measure it again, and might not be possible at all: a part off its design by
    // more than the margin lies where the design's solid leaves the ball no way down to it.
    r.ok = true;
    break;
  }
  hand_on_part_move();
  r.time.total = m.time() - t0;
}

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
  // A section measured found the part where its design data put it.
  c.found = c.found || run.r.ok;
  return std::move(run.r);
}

}  // namespace trueaxis::scan::detail
