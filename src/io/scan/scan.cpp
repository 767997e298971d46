// Results of a scanning run: scan.json, points.csv, events.csv.
#include "trueaxis/io/scan/scan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "../design/design_json.hpp"
#include "trueaxis/io/files.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::io {
namespace {

using ojson = nlohmann::ordered_json;

ojson times(const scan::MachineTime& t) {
  return {{"total", t.total},
          {"design", t.design},
          {"touch", t.touch},
          {"autonomous", t.autonomous},
          {"moves", t.moves}};
}

// A CSV field: quoted when it holds a comma, a quote or a line break.
std::string field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c == '\n' || c == '\r' ? ' ' : c;
  }
  return out + "\"";
}

}  // namespace

void write_scan(const std::string& path, const scan::Result& r, const scan::ControllerOptions& o,
                const ScanCmm& cmm) {
  ojson secs = ojson::array();
  for (const auto& s : r.sections) {
    ojson corr = ojson::array();
    for (const auto& c : s.corrections) {
      ojson params = ojson::object();
      for (const auto& [k, v] : c.parameters) params[k] = v;
      ojson one{{"type", c.type},
                {"parameters", params},
                {"accepted", c.accepted},
                {"residual_before_mm", c.residual_before}};
      // A fit that diverged has no residual: it was never applied to the design.
      if (c.diverged.empty())
        one["residual_after_mm"] = c.residual_after;
      else
        one.update(ojson{{"residual_after_mm", nullptr}, {"diverged", c.diverged}});
      // Carried over from the section whose touch points found it (the residuals are theirs).
      if (!c.found_on.empty()) one["found_on"] = c.found_on;
      corr.push_back(std::move(one));
    }
    ojson pts = ojson::array(), nrm = ojson::array(), ts = ojson::array();
    for (const auto& p : s.points) {
      pts.push_back({p.surface.x(), p.surface.y(), p.surface.z()});
      nrm.push_back({p.normal.x(), p.normal.y(), p.normal.z()});
      ts.push_back(p.t);
    }
    ojson traces = ojson::array();
    for (const auto& t : s.traces)
      traces.push_back({{"label", t.label},
                        {"completed", t.completed},
                        {"arc_mm", t.arc},
                        {"delta_l_mm", t.delta_l}});
    ojson sec{{"name", s.name}};
    if (!s.source.empty()) sec["stretch_of"] = s.source;
    sec.update(ojson{{"status", s.status()},
                     {"reason", s.reason},
                     {"machine_time_s", times(s.time)},
                     {"corrections", corr},
                     {"autonomous_count", s.autonomous_count},
                     {"trajectory_errors", s.trajectory_errors},
                     {"points", pts},
                     {"normals", nrm},
                     {"times_s", ts},
                     {"traces", traces}});
    secs.push_back(std::move(sec));
  }
  ojson blocked = ojson::array();
  for (const auto& u : r.unreachable)
    blocked.push_back({{"section", u.section},
                       {"from_arc_mm", u.from},
                       {"to_arc_mm", u.to},
                       {"start_mm", {u.start.x(), u.start.y(), u.start.z()}},
                       {"end_mm", {u.end.x(), u.end.y(), u.end.z()}},
                       {"reason", u.why}});
  ojson events = ojson::array();
  for (const auto& e : r.events)
    events.push_back({{"t_s", e.t},
                      {"section", e.section},
                      {"arc_mm", e.arc},
                      {"delta_l_mm", e.delta_l},
                      {"mode", e.mode},
                      {"event", e.event},
                      {"decision", e.decision}});
  const auto folder = std::filesystem::absolute(path).parent_path();
  write_json(
      path,
      ojson{{"kind", "scan"},
            {"strategy", scan::to_string(o.strategy)},
            {"tolerance_mm", o.tolerance},
            {"ok", r.ok()},
            {"summary", r.summary()},
            {"stopped", r.stopped.empty() ? ojson(nullptr) : ojson(r.stopped)},
            {"cmm",
             {{"tip_radius_mm", cmm.tip_radius},
              {"probe_noise_um", cmm.probe_noise_um},
              {"geometric_errors", cmm.machine.empty() ? ojson(nullptr) : ojson(cmm.machine)},
              {"part_origin_mm", cmm.part_origin ? ojson{cmm.part_origin->x(), cmm.part_origin->y(),
                                                         cmm.part_origin->z()}
                                                 : ojson(nullptr)}}},
            {"machine_time_s", times(r.time)},
            {"sections", secs},
            {"not_reachable", blocked},
            {"events", events},
            {"planned_design", detail::design_object(r.planned, folder)},
            {"corrected_design", detail::design_object(r.design, folder)}});
}

void write_scan_points(const std::string& path, const scan::Result& r) {
  std::string out = "section,x,y,z,nx,ny,nz,t\n";
  for (const auto& s : r.sections)
    for (const auto& p : s.points)
      out += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.4f}\n", field(s.name),
                         p.surface.x(), p.surface.y(), p.surface.z(), p.normal.x(), p.normal.y(),
                         p.normal.z(), p.t);
  write_text(path, out);
}

void write_scan_events(const std::string& path, const scan::Result& r) {
  std::string out = "t,section,arc_mm,delta_l_mm,mode,event,decision\n";
  for (const auto& e : r.events)
    out += fmt::format("{:.4f},{},{:.3f},{:.4f},{},{},{}\n", e.t, field(e.section), e.arc,
                       e.delta_l, e.mode, e.event, field(e.decision));
  write_text(path, out);
}

namespace {

using ptr = JsonFile::pointer;

double finite(const JsonFile& f, const ptr& p) {
  const double v = f.number(p);
  if (!std::isfinite(v)) f.fail(p, "must be a finite number");
  return v;
}

Eigen::Vector3d xyz_at(const JsonFile& f, const ptr& p) {
  const Eigen::VectorXd v = f.numbers(p);
  if (v.size() != 3) f.fail(p, "needs [x, y, z]");
  return v;
}

scan::MachineTime times_at(const JsonFile& f, const ptr& p) {
  scan::MachineTime t;
  t.total = finite(f, p / "total");
  t.design = finite(f, p / "design");
  t.touch = finite(f, p / "touch");
  t.autonomous = finite(f, p / "autonomous");
  t.moves = finite(f, p / "moves");
  return t;
}

bool flag(const JsonFile& f, const ptr& p) {
  if (!f.root()[p].is_boolean()) f.fail(p, "must be true or false");
  return f.root()[p].get<bool>();
}

}  // namespace

ScanFile read_scan(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  const ptr root;
  if (f.string(root / "kind") != "scan")
    f.fail(root / "kind", "not a scan result ('kind': 'scan')");
  for (const char* k : {"events", "planned_design", "corrected_design"})
    if (!f.has(root / k))
      f.fail(root, fmt::format("'{}' is missing: the file was written by an older trueaxis, "
                               "which kept the report's data only in the run's --report",
                               k));
  ScanFile out;
  scan::Result& r = out.result;
  out.tolerance = finite(f, root / "tolerance_mm");
  if (!(out.tolerance > 0)) f.fail(root / "tolerance_mm", "the tolerance must be positive (mm)");
  if (!f.root()[root / "stopped"].is_null()) r.stopped = f.string(root / "stopped");
  r.time = times_at(f, root / "machine_time_s");
  r.planned = detail::design_object_at(f, root / "planned_design");
  r.design = detail::design_object_at(f, root / "corrected_design");
  const auto& secs = f.array(root / "sections");
  if (secs.size() != r.planned.sections.size())
    f.fail(root / "sections", fmt::format("{} sections, but the planned design has {}", secs.size(),
                                          r.planned.sections.size()));
  for (std::size_t i = 0; i < secs.size(); ++i) {
    const ptr p = root / "sections" / i;
    scan::SectionResult s;
    s.name = f.string(p / "name");
    if (f.has(p / "stretch_of")) s.source = f.string(p / "stretch_of");
    const std::string status = f.string(p / "status");
    if (status != "ok" && status != "error" && status != "not_reachable")
      f.fail(p / "status", "status '" + status + "': ok, error or not_reachable");
    s.ok = status == "ok";
    s.not_reachable = status == "not_reachable";
    s.reason = f.string(p / "reason");
    s.time = times_at(f, p / "machine_time_s");
    s.autonomous_count = static_cast<int>(finite(f, p / "autonomous_count"));
    s.trajectory_errors = static_cast<int>(finite(f, p / "trajectory_errors"));
    const auto& corr = f.array(p / "corrections");
    for (std::size_t k = 0; k < corr.size(); ++k) {
      const ptr c = p / "corrections" / k;
      scan::Correction x;
      x.type = f.string(c / "type");
      x.accepted = flag(f, c / "accepted");
      x.residual_before = finite(f, c / "residual_before_mm");
      if (f.has(c / "diverged")) {
        x.diverged = f.string(c / "diverged");
        x.residual_after = NAN;
      } else {
        x.residual_after = finite(f, c / "residual_after_mm");
      }
      if (f.has(c / "found_on")) x.found_on = f.string(c / "found_on");
      for (const auto& [name, v] : f.root()[c / "parameters"].items()) {
        (void)v;
        x.parameters.push_back({name, finite(f, c / "parameters" / name)});
      }
      // A JSON object keeps no order: back in the order the fit gives them (the turn or scale
      // first, then the move, then the centre), so that the report reads as the run's did.
      static const std::vector<std::string> kOrder{
          "rotation_deg", "scale", "direction_x", "direction_y", "direction_z", "dx_mm",
          "dy_mm",        "dz_mm", "centre_x_mm", "centre_y_mm", "centre_z_mm"};
      const auto rank = [](const std::string& name) {
        return std::find(kOrder.begin(), kOrder.end(), name) - kOrder.begin();
      };
      std::stable_sort(x.parameters.begin(), x.parameters.end(),
                       [&](const auto& a, const auto& b) { return rank(a.first) < rank(b.first); });
      s.corrections.push_back(std::move(x));
    }
    const auto& pts = f.array(p / "points");
    const auto& nrm = f.array(p / "normals");
    const Eigen::VectorXd ts = f.numbers(p / "times_s");
    if (nrm.size() != pts.size() || static_cast<std::size_t>(ts.size()) != pts.size())
      f.fail(p / "normals", "one normal and one time per point");
    for (std::size_t k = 0; k < pts.size(); ++k) {
      scan::Sample x;
      x.surface = xyz_at(f, p / "points" / k);
      x.normal = xyz_at(f, p / "normals" / k);
      x.t = ts[static_cast<Eigen::Index>(k)];
      x.contact = true;
      s.points.push_back(x);
    }
    const auto& tr = f.array(p / "traces");
    for (std::size_t k = 0; k < tr.size(); ++k) {
      const ptr t = p / "traces" / k;
      scan::Trace x;
      x.label = f.string(t / "label");
      x.completed = flag(f, t / "completed");
      const Eigen::VectorXd a = f.numbers(t / "arc_mm"), d = f.numbers(t / "delta_l_mm");
      if (a.size() != d.size()) f.fail(t / "delta_l_mm", "one trajectory error per arc");
      x.arc.assign(a.data(), a.data() + a.size());
      x.delta_l.assign(d.data(), d.data() + d.size());
      s.traces.push_back(std::move(x));
    }
    r.sections.push_back(std::move(s));
  }
  const auto& nr = f.array(root / "not_reachable");
  for (std::size_t k = 0; k < nr.size(); ++k) {
    const ptr u = root / "not_reachable" / k;
    r.unreachable.push_back({f.string(u / "section"), finite(f, u / "from_arc_mm"),
                             finite(f, u / "to_arc_mm"), xyz_at(f, u / "start_mm"),
                             xyz_at(f, u / "end_mm"), f.string(u / "reason")});
  }
  const auto& ev = f.array(root / "events");
  for (std::size_t k = 0; k < ev.size(); ++k) {
    const ptr e = root / "events" / k;
    r.events.push_back({finite(f, e / "t_s"), f.string(e / "section"), finite(f, e / "arc_mm"),
                        finite(f, e / "delta_l_mm"), f.string(e / "mode"), f.string(e / "event"),
                        f.string(e / "decision")});
  }
  return out;
}

}  // namespace trueaxis::io
