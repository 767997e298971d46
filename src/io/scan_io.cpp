// Results of a scanning run: scan.json, points.csv, events.csv.
#include <fmt/format.h>

#include "trueaxis/io/files.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/scan.hpp"

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
      corr.push_back(std::move(one));
    }
    ojson pts = ojson::array();
    for (const auto& p : s.points) pts.push_back({p.surface.x(), p.surface.y(), p.surface.z()});
    ojson sec{{"name", s.name}};
    if (!s.source.empty()) sec["stretch_of"] = s.source;
    sec.update(ojson{{"status", s.status()},
                     {"reason", s.reason},
                     {"machine_time_s", times(s.time)},
                     {"corrections", corr},
                     {"autonomous_count", s.autonomous_count},
                     {"trajectory_errors", s.trajectory_errors},
                     {"points", pts}});
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
            {"not_reachable", blocked}});
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

}  // namespace trueaxis::io
