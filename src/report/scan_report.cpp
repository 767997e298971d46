// Report section for an error-tolerant scanning run.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "trueaxis/report/scan.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::report {
namespace {

// The log's identifiers in words, for a reader of the report (the files keep the identifiers).
std::string event_words(const std::string& id) {
  static const std::pair<const char*, const char*> words[] = {
      {"trajectory_error", "trajectory error"},
      {"touch", "touch point"},
      {"correction_applied", "correction applied"},
      {"correction_rejected", "correction rejected"},
      {"correction_carried", "correction carried over from another section"},
      {"part_move_found", "the part's move found from several sections' touch points"},
      {"part_move_guessed",
       "the part's solid moved to fit the touch points, tried on the next sections"},
      {"autonomous_scan", "autonomous scan"},
      {"rest_autonomous",
       "the rest scanned autonomously, which costs less than touch points and a rescan"},
      {"approach_missed", "no surface met on the approach: tried again further along"},
      {"unexpected_touch", "the probe stopped a free move on the part"},
      {"design_overwritten", "design data replaced by the measured contour"},
      {"design_spliced", "design data replaced by the measured contour where the part left it"},
      {"rescan", "rescan"},
      {"section_done", "section done"},
      {"error_exit", "error exit"},
      {"loop_limit", "too many autonomous scans"},
      {"two_dimensional", "the curve lies in a plane"},
      {"not_reachable", "not reachable"},
      {"restart", "started again elsewhere"},
      {"design_moved", "design data moved for the next part where other sections found the part"},
  };
  for (const auto& [k, w] : words)
    if (id == k) return w;
  std::string out = id;
  for (char& c : out)
    if (c == '_') c = ' ';
  return out;
}

std::string mode_words(const std::string& mode) {
  if (mode == "design") return "design-value scanning";
  if (mode == "autonomous") return "autonomous scanning";
  if (mode == "touch") return "touch";
  return mode;
}

}  // namespace

Section scan_section(const std::string& title, const scan::Result& r, const design::Design& design,
                     double tolerance, const std::vector<Eigen::VectorXd>& truth_um,
                     const std::vector<Eigen::Matrix3Xd>& true_part) {
  Section s;
  s.title = title;
  s.references = {kErrorTolerantScanning};
  s.intro_html = fmt::format(
      "<p>Each section is scanned along its design data (design-value scanning). When the "
      "trajectory error ΔL (how far the stylus centre runs from where it would on the design, "
      "along the normal) leaves ±{:g} mm, points are touched along the design normals and a "
      "geometric correction of that section's design data is fitted (translation, rotation, "
      "scale, scale and rotation, scale along one direction); if none fits, the section is "
      "scanned autonomously (slowly, following the surface) and its design data are replaced by "
      "the measured contour. Then it is scanned along the design again. Times are machine "
      "seconds.</p><p>{}</p>",
      tolerance, escape(r.summary()));
  s.table = {{"section", "status", "machine time (s)", "design / touch / autonomous / moves (s)",
              "trajectory errors", "correction applied", "autonomous scans", "points",
              "max |distance| from the simulated part (µm)"}};
  for (std::size_t i = 0; i < r.sections.size(); ++i) {
    const auto& sec = r.sections[i];
    if (!sec.ok) s.warnings.push_back(fmt::format("section '{}': {}", sec.name, sec.reason));
    std::string applied;
    for (const auto& c : sec.corrections)
      if (c.accepted) {
        applied += (applied.empty() ? "" : "; ") + c.type + " " + c.parameters_text();
        if (!c.found_on.empty()) applied += fmt::format(" (found on {})", c.found_on);
      }
    if (applied.empty()) applied = "none";
    std::string truth = "not known";
    if (i < truth_um.size() && truth_um[i].size())
      truth = fmt::format("{:.2f}", truth_um[i].cwiseAbs().maxCoeff());
    s.table.push_back({sec.name, sec.status(), fmt::format("{:.1f}", sec.time.total),
                       fmt::format("{:.1f} / {:.1f} / {:.1f} / {:.1f}", sec.time.design,
                                   sec.time.touch, sec.time.autonomous, sec.time.moves),
                       std::to_string(sec.trajectory_errors), applied,
                       std::to_string(sec.autonomous_count), std::to_string(sec.points.size()),
                       truth});
  }

  for (std::size_t i = 0; i < r.sections.size() && i < design.sections.size(); ++i) {
    const auto& sec = r.sections[i];
    // ΔL of every design-value scan on one arc axis (0.5 mm), with the tolerance.
    double end = 0;
    for (const auto& t : sec.traces)
      if (!t.arc.empty()) end = std::max(end, t.arc.back());
    if (!sec.traces.empty() && end > 0) {
      Plot p;
      p.title =
          fmt::format("section '{}': trajectory error ΔL along each design-value scan", sec.name);
      p.x_label = "arc along the path (mm)";
      p.y_label = "ΔL (mm)";
      const Eigen::Index n = static_cast<Eigen::Index>(std::ceil(end / 0.5)) + 1;
      p.x = Eigen::VectorXd::LinSpaced(n, 0, 0.5 * static_cast<double>(n - 1));
      for (const auto& t : sec.traces) {
        Eigen::VectorXd y = Eigen::VectorXd::Constant(n, NAN);
        for (std::size_t k = 0; k < t.arc.size(); ++k) {
          const auto j = static_cast<Eigen::Index>(std::lround(t.arc[k] / 0.5));
          if (j >= 0 && j < n) y[j] = t.delta_l[k];
        }
        p.series.push_back({t.label + (t.completed ? "" : " (stopped)"), y, {}, "", false, false});
      }
      p.series.push_back(
          {"+tolerance", Eigen::VectorXd::Constant(n, tolerance), {}, "#c62828", true, false});
      p.series.push_back(
          {"−tolerance", Eigen::VectorXd::Constant(n, -tolerance), {}, "#c62828", true, false});
      // Where each scan stopped on a trajectory error.
      Eigen::VectorXd stops = Eigen::VectorXd::Constant(n, NAN);
      for (const auto& e : r.events)
        if (e.section == sec.name && e.event == "trajectory_error") {
          const auto j = static_cast<Eigen::Index>(std::lround(e.arc / 0.5));
          if (j >= 0 && j < n) stops[j] = e.delta_l;
        }
      if (stops.array().isFinite().any())
        p.series.push_back({"trajectory error: scan stopped", stops, {}, "#000000", false, true});
      s.plots.push_back(std::move(p));
    }
    if (sec.points.empty()) continue;
    // The measured contour against the design it started from: deviation along the normal.
    const design::Section& d = design.sections[i];
    if (d.space_curve()) continue;  // no plane to draw a space curve in
    const auto smp = design::sample(d, 0.05);
    const sim::Contour c(smp.points, d.plane.normal.normalized(), d.closed,
                         d.material == design::Side::Left);
    const Eigen::Index m = static_cast<Eigen::Index>(sec.points.size());
    Eigen::VectorXd arc(m), dev(m), px(m), py(m);
    const Eigen::Vector3d n = d.plane.normal.normalized();
    const Eigen::Vector3d a =
        std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d e1 = (a - a.dot(n) * n).normalized(), e2 = n.cross(e1);
    std::vector<sim::Contour::Nearest> measured_feet;  // each measured point's foot on the design
    measured_feet.reserve(static_cast<std::size_t>(m));
    for (Eigen::Index k = 0; k < m; ++k) {
      const auto& pt = sec.points[static_cast<std::size_t>(k)].surface;
      const auto& nr = measured_feet.emplace_back(c.nearest(pt));
      arc[k] = nr.arc;
      dev[k] = nr.distance;
      px[k] = (pt - d.plane.origin).dot(e1);
      py[k] = (pt - d.plane.origin).dot(e2);
    }
    Plot p;
    p.title = fmt::format(
        "section '{}': measured surface minus the design, along the design's outward "
        "normal",
        sec.name);
    p.x_label = "arc along the design (mm)";
    p.y_label = "deviation (mm)";
    // Sorted by arc, so that the curve reads left to right.
    std::vector<Eigen::Index> order(static_cast<std::size_t>(m));
    for (Eigen::Index k = 0; k < m; ++k) order[static_cast<std::size_t>(k)] = k;
    std::sort(order.begin(), order.end(), [&](auto u, auto v) { return arc[u] < arc[v]; });
    p.x.resize(m);
    Eigen::VectorXd y(m), tr(m);
    const bool has_truth = i < truth_um.size() && truth_um[i].size() == m;
    for (Eigen::Index k = 0; k < m; ++k) {
      const Eigen::Index j = order[static_cast<std::size_t>(k)];
      p.x[k] = arc[j];
      y[k] = dev[j];
      if (has_truth) tr[k] = truth_um[i][j] * 1e-3;
    }
    p.series.push_back({"measured − design", y, {}, "", false, true});
    if (has_truth)
      p.series.push_back({"measured − simulated part", tr, {}, "#2e7d32", false, true});
    s.plots.push_back(std::move(p));

    HeatMap h;
    h.title = fmt::format(
        "section '{}': the measured contour, coloured by its deviation from the "
        "design",
        sec.name);
    h.x_label = "in-plane u (mm)";
    h.y_label = "in-plane v (mm)";
    h.value_label = "deviation (mm)";  // as the plot above: a part may sit millimetres off
    h.px = px;
    h.py = py;
    h.pvalue = dev;
    std::vector<Eigen::Index> line(static_cast<std::size_t>(m));
    for (Eigen::Index k = 0; k < m; ++k) line[static_cast<std::size_t>(k)] = k;
    h.lines.push_back(std::move(line));
    s.heat_maps.push_back(std::move(h));

    // The section in its plane: design, corrected design, measured points and the true part,
    // each drawn at the design's foot point plus its deviation along the design normal × M.
    // Each point's foot on the design is found once.
    struct Curve {
      std::string label;
      std::vector<sim::Contour::Nearest> feet;
      Eigen::Matrix3Xd points;  // the curve's own points, whose feet those are
    };
    auto feet_of = [&](std::string label, const Eigen::Matrix3Xd& q) {
      Curve cv{std::move(label), {}, q};
      cv.feet.reserve(static_cast<std::size_t>(q.cols()));
      for (Eigen::Index k = 0; k < q.cols(); ++k) cv.feet.push_back(c.nearest(q.col(k)));
      return cv;
    };
    std::vector<Curve> curves;
    if (i < r.design.sections.size())
      curves.push_back(
          feet_of("corrected design", design::sample(r.design.sections[i], 0.5).points));
    if (i < true_part.size() && true_part[i].cols() > 1)
      curves.push_back(feet_of("simulated true part", true_part[i]));
    {
      Eigen::Matrix3Xd q(3, m);
      for (Eigen::Index k = 0; k < m; ++k)
        q.col(k) = sec.points[static_cast<std::size_t>(k)].surface;
      curves.push_back({"measured points", std::move(measured_feet), std::move(q)});
    }
    double worst = 0;
    for (const auto& cv : curves)
      for (const auto& f : cv.feet) worst = std::max(worst, std::abs(f.distance));
    const double size = std::max(px.maxCoeff() - px.minCoeff(), py.maxCoeff() - py.minCoeff());
    const double mag = std::max(1.0, nice_magnification(worst * 1e3, size, 0.06));
    auto in_plane = [&](const Eigen::Vector3d& p) {
      return Eigen::Vector2d((p - d.plane.origin).dot(e1), (p - d.plane.origin).dot(e2));
    };
    PlaneView v;
    v.title =
        fmt::format("section '{}' in its plane: deviations from the design ×{:g}", sec.name, mag);
    v.x_label = "in-plane u (mm)";
    v.y_label = "in-plane v (mm)";
    Eigen::Matrix2Xd design_xy(2, smp.points.cols());
    for (Eigen::Index k = 0; k < smp.points.cols(); ++k)
      design_xy.col(k) = in_plane(smp.points.col(k));
    v.curves.push_back({"design", design_xy, "#757575", false, false, false});
    for (const auto& cv : curves) {
      Eigen::Matrix2Xd xy(2, static_cast<Eigen::Index>(cv.feet.size()));
      // Each point at its foot plus its own deviation vector × M (in the plane). Along a
      // segment that is the deviation along the normal; at a corner, where the foot is the
      // vertex, it keeps the point's direction from it, so a rounded or offset corner is drawn
      // as a magnified round corner, not as a spike along one side's normal.
      for (std::size_t k = 0; k < cv.feet.size(); ++k) {
        const auto& f = cv.feet[k];
        const Eigen::Vector2d foot = in_plane(f.point);
        xy.col(static_cast<Eigen::Index>(k)) =
            foot + mag * (in_plane(cv.points.col(static_cast<Eigen::Index>(k))) - foot);
      }
      const bool corrected = cv.label == "corrected design";
      const bool points = cv.label == "measured points";
      v.curves.push_back({cv.label, xy,
                          corrected ? "#1565c0"
                          : points  ? "#e65100"
                                    : "#2e7d32",
                          corrected, points, false});
    }
    s.planes.push_back(std::move(v));
  }

  std::vector<std::vector<std::string>> ev{
      {"t (s)", "section", "arc (mm)", "ΔL (mm)", "mode", "event", "decision"}};
  for (const auto& e : r.events)
    ev.push_back({fmt::format("{:.3f}", e.t), e.section, fmt::format("{:.1f}", e.arc),
                  fmt::format("{:+.3f}", e.delta_l), mode_words(e.mode), event_words(e.event),
                  e.decision});
  s.more_tables.push_back({"every decision of the flow", std::move(ev)});
  return s;
}

}  // namespace trueaxis::report
