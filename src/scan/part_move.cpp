// What the error-tolerant controller hands from one section to the next: the part's move found
// on a section carried to the next ones in parallel planes, a move the touch points suggest
// tried as a guess (in the plane, or of the part's solid cut in the plane), confirmed or dropped
// by the section's own touch points or scan.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "section_run.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::scan::detail {

std::optional<std::pair<design::Section, Eigen::Affine3d>> SectionRun::placed_by(
    const std::vector<Correction>& cs) const {
  if (cs.empty() || current.space_curve()) return std::nullopt;
  Eigen::Affine3d step = Eigen::Affine3d::Identity();
  for (const auto& c : cs) step = c.transform * step;
  if (std::all_of(cs.begin(), cs.end(),
                  [&](const Correction& c) { return detail::keeps_plane(current, c.transform); })) {
    design::Section moved_design = current;
    detail::move_section(moved_design, step);
    return std::pair{std::move(moved_design), step};
  }
  // Only a move of the solid fitted in three dimensions is cut from the solid in another plane:
  // a move found in a plane says nothing of the move across it.
  const Eigen::Matrix3d R = step.linear();
  if (!solid_guess(cs) || solid_file.empty() ||
      (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-9 || R.determinant() < 0)
    return std::nullopt;
  try {
    if (auto cut = detail::on_moved_solid(current, solid_file, step))
      return std::pair{std::move(*cut), step};
  } catch (const Error&) {
    // No section of the moved solid: the section is scanned as designed.
  }
  return std::nullopt;
}

namespace {
// The names, each once, in order, joined by ", ".
std::string joined(const std::vector<std::string>& names) {
  std::vector<std::string> once;
  std::string out;
  for (const auto& n : names)
    if (std::find(once.begin(), once.end(), n) == once.end()) {
      once.push_back(n);
      out += (out.empty() ? "" : ", ") + n;
    }
  return out;
}

// How a carried correction was brought to a section, in words.
std::string how_placed(const std::vector<Correction>& cs) {
  return std::any_of(cs.begin(), cs.end(),
                     [](const Correction& c) { return c.type == "solid-move"; })
             ? "its design data cut from the part's solid moved there"
             : "its design data moved with it";
}
}  // namespace

void SectionRun::carry_part_move() {
  auto placed = placed_by(part_move);
  if (!placed) return;
  std::string what;
  for (const auto& c : part_move) {
    r.corrections.push_back(c);
    const std::string params = fmt::format(" {}", c.parameters_text());
    what += fmt::format("{}{} ({}:{})", what.empty() ? "" : ", ", c.found_on, c.type, params);
  }
  current = std::move(placed->first);
  took(placed->second);
  log(0, 0, "correction", "correction_carried",
      fmt::format("the part is where the points measured on {} found it: {} before the first scan",
                  what, how_placed(part_move)));
}

bool SectionRun::in_touched_plane() const {
  const Eigen::Vector3d n = current.plane.normal.normalized();
  return std::any_of(touched.begin(), touched.end(), [&](const SolidTouches& t) {
    return t.solid == nominal.part().get() && t.plane.normal.normalized().cross(n).norm() < 1e-9 &&
           std::abs((t.plane.origin - current.plane.origin).dot(n)) < 1e-9;
  });
}

void SectionRun::guess_part_move() {
  if (solid_guess(guess) && !in_touched_plane()) return;
  auto placed = placed_by(guess);
  if (!placed) return;
  const Eigen::Affine3d step = placed->second;
  design::Section moved_design = std::move(placed->first);
  const std::string from = guess.front().found_on;
  double shift = 0;
  const auto smp = design::sample(current, 1.0);
  for (Eigen::Index i = 0; i < smp.points.cols(); ++i)
    shift = std::max(shift, (step * smp.points.col(i) - smp.points.col(i)).norm());
  try {
    const auto start = design::make_path(moved_design, o.path).at(0);
    const Eigen::Vector3d a = start.p + (settings().approach_clearance + shift) * start.normal;
    if (nominal.part() && nominal.clearance(a, m.stylus_axis()) < nominal.margin()) {
      log(0, 0, "correction", "correction_rejected",
          fmt::format("the part's move as the points measured on {} suggest it is not tried here: "
                      "the scan would start within {:g} mm of the part where the design puts it",
                      from, nominal.margin()));
      return;
    }
  } catch (const Error&) {
    return;  // no path along the moved design: scanned as designed
  }
  approach_extra = shift;
  // Where the guess puts the part; the planner stands it as designed until then. A move of the
  // solid fitted to touch points in a plane is known only in its part in the plane.
  learnt = solid_guess(guess) ? detail::in_plane_part(step, current.plane) : step;
  unguessed = current;
  current = std::move(moved_design);
  moved = true;
  as_designed = false;
  std::string what;
  for (const auto& c : guess) {
    r.corrections.push_back(c);
    what += fmt::format("{}{}: {}", what.empty() ? "" : ", ", c.type, c.parameters_text());
  }
  log(0, 0, "correction", "correction_carried",
      fmt::format("the part's move as the points measured on {} suggest it ({}), tried before the "
                  "first scan, {}: they did not tell a move from a scale, so free moves keep to "
                  "the part where the design puts it until this section's touch points confirm it",
                  from, what, how_placed(guess)));
}

void SectionRun::drop_guess(const Sample& stop) {
  r.corrections.erase(r.corrections.begin(),
                      r.corrections.begin() + static_cast<std::ptrdiff_t>(guess.size()));
  current = std::move(*unguessed);
  unguessed.reset();
  approach_extra = 0;
  learnt = Eigen::Affine3d::Identity();
  moved = true;
  as_designed = true;
  log(stop.arc, stop.delta_l, "correction", "correction_rejected",
      "the part's move tried as a guess does not hold here (the points measured fit no correction "
      "to it): the section goes on from its design data");
}

bool SectionRun::beyond_margin(const Sample& stop, const sim::Contour& curve,
                               const Eigen::Matrix3Xd& touched) {
  // How far off the design data the touch points found the part: what the section starts again
  // with.
  seen = 0;
  for (Eigen::Index i = 0; i < touched.cols(); ++i)
    seen = std::max(seen, std::abs(curve.nearest(touched.col(i)).distance));
  if (!nominal.part() || seen <= nominal.margin()) return true;
  // The free moves of a section keep the margin from the part as designed: a part found further
  // off than that would be met by them (the way down to the scan's start, 3 mm off the design).
  r.not_reachable = true;
  r.reason = fmt::format(
      "not reachable: its touch points found the part up to {:.2f} mm off its design, more than "
      "the {:g} mm the free moves keep from it",
      seen, nominal.margin());
  log(stop.arc, seen, "section", "error_exit", r.reason);
  return false;
}

void SectionRun::confirm_by_points() {
  // 24 of the scan's points, evenly spread over it, as touch points about the guessed design.
  const auto& pts = r.points;
  constexpr std::size_t kPoints = 24;
  if (pts.size() < kPoints) return;
  const sim::Contour curve = detail::contour_of(current);
  Eigen::Matrix3Xd feet(3, kPoints), got(3, kPoints);
  for (std::size_t i = 0; i < kPoints; ++i) {
    const auto& p = pts[i * (pts.size() - 1) / (kPoints - 1)].surface;
    got.col(static_cast<Eigen::Index>(i)) = p;
    feet.col(static_cast<Eigen::Index>(i)) = curve.nearest(p).point;
  }
  const PartMove tells = fit_part_move(current, feet, got, o.accept);
  double worst = 0;
  for (Eigen::Index i = 0; i < got.cols(); ++i)
    worst = std::max(worst, std::abs(curve.nearest(got.col(i)).distance));
  if (worst > o.accept || (!current.closed && tells.resolution < detail::kTellsPart)) return;
  guess_confirmed = true;
  confirm_guess();
  log(0, 0, "correction", "correction_applied",
      fmt::format("the part's move tried as a guess holds: the scan's points lie within {:.4f} mm "
                  "of the guessed design all along the {}, which tells a move from a scale",
                  worst, current.closed ? "contour" : "stretch"));
}

std::optional<std::pair<Correction, design::Section>> SectionRun::solid_instead(
    const std::vector<Correction>& tried, Eigen::Index& points) const {
  // The menu's move or turn in the plane, or touch points that agree with the design, stand.
  if (std::any_of(tried.begin(), tried.end(), [](const Correction& c) {
        return c.type == "none" ||
               (c.accepted && (c.type == "translation" || c.type == "rotation"));
      }))
    return std::nullopt;
  // Only on design data as the design stands the part, or as a guess moved them.
  if (!(as_designed || unguessed) || current.space_curve()) return std::nullopt;
  auto c = pooled_solid_move(points);
  if (!c) return std::nullopt;
  try {
    if (auto cut =
            detail::on_moved_solid(unguessed ? *unguessed : current, solid_file, c->transform)) {
      c->found_on.clear();  // this section's own touch points are among those it fits
      return std::pair{std::move(*c), std::move(*cut)};
    }
  } catch (const Error&) {
    // No section of the moved solid: the menu's candidates stand.
  }
  return std::nullopt;
}

void SectionRun::hand_on_part_move() {
  if (!hand_on_in_plane() && made_round) guess_solid_move();
}

std::optional<Correction> SectionRun::pooled_solid_move(Eigen::Index& points) const {
  points = 0;
  if (!nominal.part() || solid_file.empty()) return std::nullopt;
  std::vector<std::string> names;
  for (const auto& t : touched)
    if (t.solid == nominal.part().get()) {
      points += t.points.cols();
      names.push_back(t.section);
    }
  Eigen::Matrix3Xd pts(3, points);
  Eigen::Index at = 0;
  for (const auto& t : touched)
    if (t.solid == nominal.part().get()) {
      pts.middleCols(at, t.points.cols()) = t.points;
      at += t.points.cols();
    }
  return detail::fit_solid_move(*nominal.part(), pts, o.accept, joined(names));
}

void SectionRun::guess_solid_move() {
  Eigen::Index n = 0;
  const auto c = pooled_solid_move(n);
  if (!c) {
    if (solid_guess(guess)) guess.clear();  // the touch points since contradict it
    return;
  }
  const std::string& on = c->found_on;
  guess = {*c};
  log(0, 0, "correction", "part_move_guessed",
      fmt::format("the points measured on {} ({} of them) all lie within {:.4f} mm of the part's "
                  "solid moved by {} (were {:.4f}). Points in one plane may fit other "
                  "moves alike (its mirror image across the plane), so this is not reported as "
                  "where the part stands: it is tried on the sections after this one in the "
                  "planes of these touch points, their design data cut from the solid moved so",
                  on, n, c->residual_after, c->parameters_text(), c->residual_before));
}

bool SectionRun::hand_on_in_plane() {
  // A move of the solid stays a guess, however well this section's points agree with it: touch
  // points in one plane do not tell it from its mirror image (guess_solid_move fits it again
  // with this section's touch points).
  if (std::any_of(r.corrections.begin(), r.corrections.end(),
                  [](const Correction& c) { return c.accepted && c.type == "solid-move"; }))
    return false;
  if (auto moved = detail::part_move_of(r.corrections, told, current.closed, current.name)) {
    part_move = std::move(*moved);
    rounds.clear();
    guess.clear();
    return true;
  }
  if (guess_confirmed) {
    // The guess is where the part stands (every accepted correction rigid: the guess's own).
    part_move.clear();
    for (const auto& c : r.corrections)
      if (c.accepted) part_move.push_back(c);
    rounds.clear();
    guess.clear();
    return true;
  }
  if (own_rounds.empty()) return false;
  // What this section's own touch points found, made on the design as it stands the part: the
  // run's guess of the part's move when it is rigid, and no guess at all when it is not.
  std::vector<Correction> own;
  bool rigid = true;
  for (const auto& c : r.corrections) {
    if (!c.accepted) continue;
    if (!c.found_on.empty()) rigid = false;  // not found on the design as it stands the part
    const Eigen::Matrix3d R = c.transform.linear();
    rigid = rigid && (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-9 &&
            R.determinant() > 0;
    own.push_back(c);
    own.back().found_on = current.name;
  }
  guess.clear();
  if (rigid) guess = std::move(own);
  const Eigen::Vector3d n = own_rounds.front().section.plane.normal.normalized();
  if (!rounds.empty() &&
      std::abs(rounds.front().section.plane.normal.normalized().dot(n)) < 1 - 1e-9)
    rounds.clear();
  rounds.insert(rounds.end(), own_rounds.begin(), own_rounds.end());
  std::vector<std::string> names;
  for (const auto& t : rounds)
    if (std::find(names.begin(), names.end(), t.section.name) == names.end())
      names.push_back(t.section.name);
  if (names.size() < 2) return !guess.empty();
  const std::string on = joined(names);
  const auto c = detail::pooled_part_move(rounds, o.accept, on);
  if (!c) return !guess.empty();
  Eigen::Index points = 0;
  for (const auto& t : rounds) points += t.touched.cols();
  part_move = {*c};
  rounds.clear();
  guess.clear();
  log(0, 0, "correction", "part_move_found",
      fmt::format("the points measured on {} together tell where the part stands ({} of them): "
                  "{}: {}; all within {:.4f} mm of the moved design (were {:.4f}); the sections "
                  "after this one in parallel planes start there",
                  on, points, c->type, c->parameters_text(), c->residual_after,
                  c->residual_before));
  return true;
}

}  // namespace trueaxis::scan::detail
