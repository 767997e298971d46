// A scanning run over all sections of a design: each section in its probe orientation, whole or
// in the stretches the stylus reaches, and a result that keeps what was measured when the run
// stops early.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <tuple>

#include "section.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/scan/controller.hpp"
#include "trueaxis/scan/planner.hpp"

namespace trueaxis::scan {
namespace {

// Blocked stretches of a contour are widened by this on each side (mm): the ball keeps off the
// place where the stylus stops fitting.
constexpr double kWiden = 0.5;

}  // namespace

namespace detail {

std::optional<std::pair<double, double>> reachable_ends(const design::Section& s, double a,
                                                        double b, const Planner& planner,
                                                        const ControllerOptions& o,
                                                        double approach) {
  const Eigen::Vector3d u = design::stylus_axis(s.probe);
  while (b - a >= kShortest) {
    const auto p = design::make_path(design::piece(s, a, b, s.name), o.path);
    const auto p0 = p.at(0), p1 = p.at(p.length());
    const bool in = planner.from_above(p0.p + approach * p0.normal, u);
    const bool out = planner.from_above(p1.p + approach * p1.normal, u);
    if (in && out) return std::pair{a, b};
    if (!in) a += 0.5;
    if (!out) b -= 0.5;
  }
  return std::nullopt;
}

std::optional<double> reachable_start(const design::Section& s, const Planner& planner,
                                      const ControllerOptions& o, double approach) {
  const double L = design::length(s);
  for (double a = 0; a < L; a += 1) {
    const auto q = design::make_path(started_at(s, a), o.path).at(0);
    if (planner.from_above(q.p + approach * q.normal, design::stylus_axis(s.probe))) return a;
  }
  return std::nullopt;
}

Eigen::Vector3d point_at(const design::Section& s, const design::Samples& smp, double arc) {
  const double L = smp.arc.size() ? smp.arc[smp.arc.size() - 1] : 0.0;
  const double a =
      s.closed && L > 0 ? std::fmod(std::fmod(arc, L) + L, L) : std::clamp(arc, 0.0, L);
  Eigen::Index i = 0;
  (smp.arc.array() - a).abs().minCoeff(&i);
  return smp.points.col(i);
}

double contour_arc(const design::Samples& smp, const design::ScanPath& path, double along) {
  const auto p = path.at(along);
  const Eigen::Vector3d foot = p.p - path.offset * p.normal;
  Eigen::Index best = 0;
  (smp.points.colwise() - foot).colwise().squaredNorm().minCoeff(&best);
  return smp.arc[best];
}

design::Section started_at(const design::Section& s, double a) {
  if (a == 0) return s;
  design::Section again = design::piece(s, a, a + design::length(s), s.name);
  again.closed = true;
  return again;
}

}  // namespace detail

namespace {

std::string orientation(const design::ProbeOrientation& p) {
  return fmt::format("A{:g}° B{:g}°", p.a_deg, p.b_deg);
}

// The stretches of a section to scan (the section itself when the stylus reaches all of it),
// recording what it cannot reach. Throws Error when nothing of it can be scanned.
std::vector<design::Section> stretches(const design::Section& s, const Planner& planner,
                                       const ControllerOptions& o, double approach, Result& res) {
  if (const std::string why = design::head_refusal(s.probe); !why.empty())
    throw Error("the probe head cannot take " + why);
  if (s.space_curve() || !planner.part()) return {s};
  const Eigen::Vector3d u = design::stylus_axis(s.probe);
  const design::ScanPath path = design::make_path(s, o.path);
  const auto blocked = planner.unreachable(path, u);
  // All of it is reachable: start where the ball can come down to it from above, at the
  // approach distance off the path (a closed contour is started again there; an open one whose
  // ends the ball cannot come down to is trimmed below, like any stretch).
  if (blocked.empty() && s.closed) {
    if (const auto a = detail::reachable_start(s, planner, o, approach))
      return {detail::started_at(s, *a)};
    throw Error(
        fmt::format("not reachable with the probe at {}: the part covers it, no way "
                    "down to it from above",
                    orientation(s.probe)));
  }
  if (blocked.empty()) {
    const auto ends = detail::reachable_ends(s, 0, design::length(s), planner, o, approach);
    if (ends && ends->first == 0 && ends->second == design::length(s)) return {s};
  }
  // Each blocked stretch of the path, on the design contour: the contour points the ball's
  // centre stands over at its ends.
  const double L = design::length(s);
  const auto smp = design::sample(s, 0.05);
  struct Span {
    double from, length;
    std::string why;
  };
  std::vector<Span> spans;
  for (const auto& b : blocked) {
    double a0 = detail::contour_arc(smp, path, b.from), a1 = detail::contour_arc(smp, path, b.to);
    if (b.from <= 0) a0 = s.closed ? a0 : 0;
    if (b.to >= path.length()) a1 = s.closed ? a1 : L;
    double len = a1 - a0;
    if (s.closed) len = std::fmod(len + 2 * L, L);
    if (s.closed && b.from <= 0 && b.to >= path.length()) len = L;
    spans.push_back({a0 - kWiden, std::max(0.0, len) + 2 * kWiden, b.why});
  }
  // Merge, in order along the contour (a closed one wraps).
  std::sort(spans.begin(), spans.end(),
            [](const Span& a, const Span& b) { return a.from < b.from; });
  std::vector<Span> merged;
  for (const auto& sp : spans) {
    if (!merged.empty() && sp.from <= merged.back().from + merged.back().length)
      merged.back().length =
          std::max(merged.back().length, sp.from + sp.length - merged.back().from);
    else
      merged.push_back(sp);
  }
  if (s.closed && merged.size() > 1 &&
      merged.back().from + merged.back().length >= merged.front().from + L) {
    merged.front().length = std::max(
        merged.front().length + merged.front().from + L - merged.back().from, merged.back().length);
    merged.front().from = merged.back().from - L;
    merged.pop_back();
  }
  auto point_at = [&](double arc) { return detail::point_at(s, smp, arc); };
  for (const auto& m : merged) {
    const double from = s.closed ? std::fmod(m.from + L, L) : std::max(0.0, m.from);
    const double to = s.closed ? from + std::min(m.length, L) : std::min(L, m.from + m.length);
    res.unreachable.push_back(
        {s.name, from, to, point_at(from), point_at(to),
         fmt::format("{} with the probe at {}", m.why, orientation(s.probe))});
  }
  // What is left, as open stretches, each with a clear approach and retract.
  std::vector<std::pair<double, double>> free;
  if (s.closed) {
    for (std::size_t i = 0; i < merged.size(); ++i) {
      const double a = merged[i].from + merged[i].length;
      const double b = i + 1 < merged.size() ? merged[i + 1].from : merged.front().from + L;
      if (merged[i].length < L) free.emplace_back(a, b);
    }
  } else {
    double at = 0;
    for (const auto& m : merged) {
      free.emplace_back(at, m.from);
      at = m.from + m.length;
    }
    free.emplace_back(at, L);
  }
  std::vector<design::Section> out;
  for (auto [a, b] : free) {
    if (s.closed) {
      const double shift = std::floor(a / L) * L;
      a -= shift;
      b -= shift;
    }
    a = std::max(a, 0.0);
    if (!s.closed) b = std::min(b, L);
    if (b <= a) continue;  // between two blocked spans that overlap once widened
    // Move the ends in until the ball can come in along the normal from the approach distance
    // and leave the same way; what is cut off is not reachable either.
    const double a_was = a, b_was = b;
    const std::string covered =
        fmt::format("the part covers it, no way down to it from above with the probe at {}",
                    orientation(s.probe));
    const auto ends = detail::reachable_ends(s, a, b, planner, o, approach);
    if (!ends) {
      res.unreachable.push_back({s.name, a_was, b_was, point_at(a_was), point_at(b_was), covered});
      continue;
    }
    std::tie(a, b) = *ends;
    if (a > a_was)
      res.unreachable.push_back({s.name, a_was, a, point_at(a_was), point_at(a), covered});
    if (b < b_was)
      res.unreachable.push_back({s.name, b, b_was, point_at(b), point_at(b_was), covered});
    out.push_back(design::piece(s, a, b, fmt::format("{}:{}", s.name, out.size() + 1)));
  }
  if (out.empty())
    throw Error(fmt::format(
        "not reachable with the probe at {}: {}", orientation(s.probe),
        merged.empty() ? "the part covers it, no way down to it from above" : merged.front().why));
  return out;
}

}  // namespace

bool Result::ok() const {
  if (!stopped.empty()) return false;
  for (const auto& s : sections)
    if (!s.ok) return false;
  return true;
}

std::string Result::summary() const {
  int ok = 0, errors = 0, aut = 0, corr = 0, carried = 0;
  for (const auto& s : sections) {
    ok += s.ok;
    errors += s.trajectory_errors;
    aut += s.autonomous_count;
    bool got = false;
    for (const auto& c : s.corrections) {
      corr += c.accepted && c.found_on.empty();
      got = got || !c.found_on.empty();
    }
    carried += got;
  }
  double blocked = 0;
  for (const auto& u : unreachable) blocked += u.to - u.from;
  return fmt::format(
      "{} of {} sections scanned{}{}; {} trajectory errors, {} geometric corrections{}, {} "
      "autonomous scans; machine time {:.1f} s (design {:.1f}, touch {:.1f}, autonomous {:.1f}, "
      "moves {:.1f}){}",
      ok, sections.size(),
      unreachable.empty() ? ""
                          : fmt::format(" ({} stretches, {:.1f} mm of contour, not reachable)",
                                        unreachable.size(), blocked),
      stopped.empty() ? "" : "; the run stopped early", errors, corr,
      carried ? fmt::format(" (carried to {} more section{})", carried, carried > 1 ? "s" : "")
              : "",
      aut, time.total, time.design, time.touch, time.autonomous, time.moves,
      stopped.empty() ? "" : ": " + stopped);
}

Eigen::Vector3d start_position(const design::Design& design, const ControllerOptions& options) {
  double top = -INFINITY;
  for (const auto& s : design.sections)
    top = std::max(top, design::sample(s, 1.0).points.row(2).maxCoeff());
  if (!design.solid.empty()) top = std::max(top, solid::load_step(design.solid)->box().max().z());
  const auto first = design::sample(design.sections.front(), 1.0);
  return Eigen::Vector3d(first.points(0, 0), first.points(1, 0),
                         top + options.clearance + options.path.tip_radius);
}

namespace {

// Sections a run did not measure, and that found nothing of the part themselves, keep their
// design data as planned: the next part of a batch would meet the same trajectory error there.
// The part's move the run handed on last (detail::part_move_of) is where the part stands for
// them too, in the corrected design data, as it is for the sections after the one that found
// it, when it keeps their plane.
void carry_to_unmeasured(const std::vector<Correction>& move, double t, Result& res) {
  if (move.empty()) return;
  Eigen::Affine3d step = Eigen::Affine3d::Identity();
  std::string found_on;
  for (const auto& c : move) {
    step = c.transform * step;
    found_on = c.found_on;
  }
  for (std::size_t i = 0; i < res.sections.size(); ++i) {
    const SectionResult& r = res.sections[i];
    design::Section& s = res.design.sections[i];
    if (r.ok || !r.corrections.empty() || s.space_curve() || !detail::keeps_plane(s, step))
      continue;
    detail::move_section(s, step);
    res.events.push_back({t, s.name, 0, 0, "correction", "design_moved",
                          fmt::format("not measured: its design data for the next part are moved "
                                      "where the points measured on {} found the part",
                                      found_on)});
  }
}

}  // namespace

Result scan(Machine& machine, const design::Design& design, const ControllerOptions& options,
            const Progress& progress) {
  options.validate();
  Result res;
  res.design.solid = res.planned.solid = design.solid;
  std::shared_ptr<const solid::Mesh> part;
  if (!design.solid.empty()) part = solid::load_step(design.solid);
  double top = -INFINITY;
  for (const auto& s : design.sections)
    top = std::max(top, design::sample(s, 1.0).points.row(2).maxCoeff());
  const Planner planner(part, options.path.tip_radius, options.stylus,
                        options.margin > 0 ? options.margin : options.tolerance + 1.0,
                        options.clearance, top);
  // The approach starts this far outside the path (as the section flow sets it).
  const double approach = options.tolerance + 1.5;

  // What to scan: each section whole, or the stretches of it the stylus reaches.
  // Each section is planned against the solid where its curve says the part stands (moved
  // with the curve by the corrections of an earlier part of the batch); sections that share a
  // placement share a planner.
  std::vector<std::shared_ptr<const Planner>> placed;
  auto planner_for = [&](const design::Section& s) {
    for (const auto& p : placed)
      if (p->placement().isApprox(s.solid_placement, 1e-12)) return p;
    placed.push_back(std::make_shared<const Planner>(planner.moved(s.solid_placement)));
    return placed.back();
  };
  struct Item {
    design::Section section;
    std::string source, refusal;
    std::shared_ptr<const Planner> planner;
  };
  std::vector<Item> items;
  for (const auto& s : design.sections) {
    const auto sp = planner_for(s);
    try {
      const auto pieces = stretches(s, *sp, options, approach, res);
      for (const auto& p : pieces) items.push_back({p, p.name == s.name ? "" : s.name, "", sp});
    } catch (const Error& e) {
      // Whatever stops it (a tip that fits nowhere along it, a head that cannot take the
      // orientation), a section none of which can be scanned is not reachable, and says so.
      const std::string why = e.what();
      items.push_back(
          {s, "", why.rfind("not reachable", 0) == 0 ? why : "not reachable: " + why, sp});
    }
  }
  // A move of the part found on a whole closed contour is carried to the sections after it in
  // parallel planes (run_section); an open stretch's touch points cannot tell one. So, among
  // consecutive sections in parallel planes with one probe orientation, the whole closed contours
  // are scanned first: the stretches of an outline that the stylus reaches only in pieces then
  // start where the part stands, instead of each paying a trajectory error and its touch points.
  if (options.strategy == Strategy::ErrorTolerant) {
    auto same_setup = [](const Item& a, const Item& b) {
      if (a.section.space_curve() || b.section.space_curve()) return false;
      const Eigen::Vector3d na = a.section.plane.normal.normalized();
      const Eigen::Vector3d nb = b.section.plane.normal.normalized();
      return na.cross(nb).norm() < 1e-9 &&
             (design::stylus_axis(a.section.probe) - design::stylus_axis(b.section.probe)).norm() <
                 1e-12;
    };
    for (std::size_t b = 0; b < items.size();) {
      std::size_t e = b + 1;
      while (e < items.size() && same_setup(items[b], items[e])) ++e;
      std::stable_partition(items.begin() + static_cast<std::ptrdiff_t>(b),
                            items.begin() + static_cast<std::ptrdiff_t>(e),
                            [](const Item& it) { return it.section.closed && it.refusal.empty(); });
      b = e;
    }
  }
  for (const auto& u : res.unreachable)
    res.events.push_back({machine.time(), u.section, u.from, 0, "section", "not_reachable",
                          fmt::format("{:.1f} to {:.1f} mm along the contour not scanned: {}",
                                      u.from, u.to, u.why)});

  bool first_move = true;
  std::vector<Correction> part_move;
  std::vector<detail::TouchRound> rounds;
  std::vector<Correction> guess;
  std::vector<detail::SolidTouches> touched;
  bool found = false;
  double off_design = 0;
  for (std::size_t i = 0; i < items.size(); ++i) {
    Item& it = items[i];
    if (progress) progress(i, items.size(), it.section.name);
    res.planned.sections.push_back(it.section);
    SectionResult r;
    r.name = it.section.name;
    r.source = it.source;
    if (!res.stopped.empty() || !it.refusal.empty()) {
      r.reason = !it.refusal.empty() ? it.refusal : "not scanned: " + res.stopped;
      r.not_reachable = !it.refusal.empty();
      res.events.push_back({machine.time(), r.name, 0, 0, "section", "error_exit", r.reason});
      res.design.sections.push_back(it.section);
      res.sections.push_back(std::move(r));
      continue;
    }
    const double t0 = machine.time();
    try {
      // Turn the head where the stylus is clear: retracted along its axis above the part.
      const Eigen::Vector3d axis = design::stylus_axis(it.section.probe);
      if ((axis - machine.stylus_axis()).norm() > 1e-12) {
        const Eigen::Vector3d u = machine.stylus_axis(), p = machine.position();
        const double level =
            (part ? part->highest(u) : top) + options.path.tip_radius + options.clearance;
        if (p.dot(u) < level) machine.move(p + (level - p.dot(u)) * u, options.move_speed);
        machine.orient(axis);
        first_move = true;
      }
      SectionResult partial;
      try {
        r = detail::run_section(
            {machine, options, *it.planner, res.events, first_move, partial, part_move,
             res.unreachable, rounds, guess, design.solid, touched, found, off_design},
            it.section);
      } catch (...) {
        r = std::move(partial);
        throw;
      }
    } catch (const NoWay& e) {
      // No free way to go on with this section: the machine stands where it was; the next
      // section starts from there. What the stylus cannot get to is not reachable, and what
      // the section had not measured is reported as such.
      r.name = it.section.name;
      r.ok = false;
      r.not_reachable = true;
      r.reason = fmt::format("not reachable: {}", e.what());
      r.time.total = machine.time() - t0;
      res.events.push_back({machine.time(), r.name, 0, 0, "section", "error_exit", r.reason});
      if (r.points.empty()) {
        const auto smp = design::sample(it.section, 0.05);
        const double L = design::length(it.section);
        res.unreachable.push_back({r.name, 0, L, detail::point_at(it.section, smp, 0),
                                   detail::point_at(it.section, smp, L), e.what()});
        res.events.push_back(
            {machine.time(), r.name, 0, 0, "section", "not_reachable",
             fmt::format("0.0 to {:.1f} mm along the contour not scanned: {}", L, e.what())});
      }
    } catch (const Error& e) {
      r.name = it.section.name;
      r.ok = false;
      r.reason = e.what();
      r.time.total = machine.time() - t0;
      res.stopped = fmt::format("section '{}': {}", r.name, e.what());
      res.events.push_back({machine.time(), r.name, 0, 0, "section", "error_exit",
                            "the run stops: " + std::string(e.what())});
    }
    r.source = it.source;
    res.design.sections.push_back(it.section);
    res.time.total += r.time.total;
    res.time.design += r.time.design;
    res.time.touch += r.time.touch;
    res.time.autonomous += r.time.autonomous;
    res.time.moves += r.time.moves;
    res.sections.push_back(std::move(r));
  }
  carry_to_unmeasured(part_move, machine.time(), res);
  return res;
}

}  // namespace trueaxis::scan
