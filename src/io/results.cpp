#include "trueaxis/io/results.hpp"

#include <fmt/format.h>

#include <cmath>

#include "trueaxis/error.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/surface/space.hpp"

namespace trueaxis::io {
namespace {

using P = JsonFile::pointer;

Eigen::Vector3d vec3(const JsonFile& f, const P& p, double scale = 1.0) {
  const Eigen::VectorXd v = f.numbers(p, scale);
  if (v.size() != 3) f.fail(p, fmt::format("'{}' must have 3 numbers", dotted(p)));
  return v;
}
std::vector<std::string> strings(const JsonFile& f, const P& p) {
  std::vector<std::string> out;
  if (!f.has(p)) return out;
  const auto& a = f.array(p);
  for (std::size_t i = 0; i < a.size(); ++i) out.push_back(f.string(p / i));
  return out;
}
// A number that may be null (not computed): NaN then.
double number_or_nan(const JsonFile& f, const P& p, double scale = 1.0) {
  if (!f.has(p) || f.root().at(p).is_null()) return NAN;
  return f.number(p) * scale;
}

}  // namespace

std::string read_kind(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  f.object(P());
  if (f.has(P("/kind"))) return f.string(P("/kind"));
  // Files written before the kind was.
  if (f.has(P("/workpiece")) && f.has(P("/guide"))) return "separation";
  if (f.has(P("/crossings"))) return "surface";
  if (f.has(P("/surfaces")) && f.has(P("/grid"))) return "space";
  if (f.has(P("/observable")) && f.has(P("/s"))) return "guideway";
  if (f.has(P("/placements")) && f.has(P("/points"))) return "ballgauge map";
  if (f.has(P("/results"))) return "length verification";
  if (f.has(P("/element"))) return "fit";
  if (f.has(P("/identification"))) return "parametric model";
  f.fail(P(), "not a trueaxis result file (no 'kind')");
  return "";
}

surface::Result read_surface(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  surface::Result r;
  r.method = f.string(P("/method"));
  r.reference = f.has(P("/reference")) ? f.string(P("/reference")) : "";
  r.lines = strings(f, P("/lines"));
  auto line_index = [&](const P& p) {
    const std::string name = f.string(p);
    for (std::size_t i = 0; i < r.lines.size(); ++i)
      if (r.lines[i] == name) return static_cast<int>(i);
    f.fail(p, fmt::format("line '{}' is not in 'lines'", name));
    return 0;
  };
  const auto& pts = f.array(P("/points"));
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const P at = P("/points") / i;
    surface::Point q;
    q.line = line_index(at / "line");
    q.station = static_cast<long>(f.number(at / "station"));
    q.xy = {f.number(at / "x"), f.number(at / "y")};
    q.height = f.number(at / "height") * 1e-3;
    r.points.push_back(q);
  }
  if (f.has(P("/grid")) && !f.root().at(P("/grid")).is_null()) {
    surface::Grid g;
    g.x = f.numbers(P("/grid/x"));
    g.y = f.numbers(P("/grid/y"));
    const auto& rows = f.array(P("/grid/height"));
    if (static_cast<Eigen::Index>(rows.size()) != g.y.size())
      f.fail(P("/grid/height"), "one row of heights per y");
    g.height.resize(g.y.size(), g.x.size());
    for (std::size_t a = 0; a < rows.size(); ++a) {
      const Eigen::VectorXd row = f.numbers(P("/grid/height") / a, 1e-3);
      if (row.size() != g.x.size()) f.fail(P("/grid/height") / a, "one height per x in every row");
      g.height.row(static_cast<Eigen::Index>(a)) = row.transpose();
    }
    r.grid = g;
  }
  r.flatness_ls = f.number(P("/flatness/ls")) * 1e-3;
  r.flatness_min_zone = f.number(P("/flatness/min_zone")) * 1e-3;
  r.closure_rms = f.number(P("/closure/rms")) * 1e-3;
  r.closure_max = f.number(P("/closure/max")) * 1e-3;
  if (f.has(P("/crossings"))) {
    const auto& cs = f.array(P("/crossings"));
    for (std::size_t i = 0; i < cs.size(); ++i) {
      const P at = P("/crossings") / i;
      surface::Crossing c;
      f.array(at / "lines");
      c.a = line_index(at / "lines" / 0);
      c.b = line_index(at / "lines" / 1);
      c.xy = {f.number(at / "x"), f.number(at / "y")};
      c.residual = f.number(at / "residual") * 1e-3;
      r.crossings.push_back(c);
    }
  }
  r.unobservable = strings(f, P("/unobservable"));
  r.gauge = f.has(P("/gauge")) ? f.string(P("/gauge")) : "";
  return r;
}

surface::SpaceResult read_space(const std::string& path,
                                std::optional<surface::Verification>* verification) {
  const JsonFile f = JsonFile::read(path);
  surface::SpaceResult s;
  s.map = read_error_map(path);
  if (f.has(P("/surfaces"))) {
    const auto& sf = f.array(P("/surfaces"));
    for (std::size_t i = 0; i < sf.size(); ++i) {
      const P at = P("/surfaces") / i;
      surface::LevelSurface l;
      const std::string c = f.string(at / "component");
      if (c != "ex" && c != "ey" && c != "ez") f.fail(at / "component", "must be ex, ey or ez");
      l.component = c[1] - 'x';
      l.level = f.number(at / "level");
      l.closure_rms = f.number(at / "closure_rms") * 1e-3;
      l.flatness_ls = f.number(at / "flatness_ls") * 1e-3;
      s.surfaces.push_back(l);
    }
  }
  if (f.has(P("/campaign/straightness_runs")))
    s.straightness_runs = static_cast<long>(f.number(P("/campaign/straightness_runs")));
  if (f.has(P("/campaign/laser_runs")))
    s.laser_runs = static_cast<long>(f.number(P("/campaign/laser_runs")));
  s.unobservable = strings(f, P("/unobservable"));
  if (f.has(P("/gauge"))) s.gauge = f.string(P("/gauge"));
  if (f.has(P("/truth/rms"))) s.truth_rms = f.number(P("/truth/rms")) * 1e-3;
  if (f.has(P("/truth/max"))) s.truth_max = f.number(P("/truth/max")) * 1e-3;
  if (verification && f.has(P("/verification"))) {
    const P v("/verification");
    surface::Verification x;
    x.points = static_cast<long>(f.number(v / "points"));
    x.before_rms = f.number(v / "before_rms") * 1e-3;
    x.before_max = f.number(v / "before_max") * 1e-3;
    x.after_rms = f.number(v / "after_rms") * 1e-3;
    x.after_max = f.number(v / "after_max") * 1e-3;
    x.interpolation_rms = f.number(v / "interpolation_rms") * 1e-3;
    x.uncertainty_rms = number_or_nan(f, v / "uncertainty_rms", 1e-3);
    x.uncertainty_known = std::isfinite(x.uncertainty_rms);
    if (!x.uncertainty_known) x.uncertainty_rms = 0;
    x.predicted_rms = x.uncertainty_known ? f.number(v / "predicted_rms") * 1e-3
                                          : std::hypot(x.interpolation_rms, 0.0);
    *verification = x;
  }
  return s;
}

guideway::Result read_guideway_result(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  guideway::Result r;
  r.s = f.numbers(P("/s"));
  for (int e = 0; e < guideway::kErrors; ++e) {
    const auto k = static_cast<std::size_t>(e);
    const P at = P("/") / guideway::kErrorNames[e];
    const double sc = e < 2 ? 1e-3 : 1e-6;
    if (f.has(at) && !f.root().at(at).is_null()) r.value[k] = f.numbers(at, sc);
    r.layout.observable[k] =
        f.has(P("/observable") / guideway::kErrorNames[e]) &&
        f.root().at(P("/observable") / guideway::kErrorNames[e]).is_boolean() &&
        f.root().at(P("/observable") / guideway::kErrorNames[e]).get<bool>();
    const double u = number_or_nan(f, P("/uncertainty") / guideway::kErrorNames[e], sc);
    r.uncertainty[k] = std::isfinite(u) ? u : 0;
    const P sum = P("/summary") / guideway::kErrorNames[e];
    if (f.has(sum) && !f.root().at(sum).is_null()) {
      r.pv[k] = f.number(sum / "pv") * sc;
      r.rms[k] = f.number(sum / "rms") * sc;
    }
    if (r.value[k].size() && r.value[k].size() != r.s.size())
      f.fail(at, "one value per position s");
  }
  if (f.has(P("/residual")) && !f.root().at(P("/residual")).is_null())
    r.residual = f.numbers(P("/residual"), 1e-3);
  if (f.has(P("/straightness/horizontal")) && !f.root().at(P("/straightness/horizontal")).is_null())
    r.horizontal_straightness = f.numbers(P("/straightness/horizontal"), 1e-3);
  if (f.has(P("/straightness/vertical")) && !f.root().at(P("/straightness/vertical")).is_null())
    r.vertical_straightness = f.numbers(P("/straightness/vertical"), 1e-3);
  const double cond = number_or_nan(f, P("/condition_number"));
  r.layout.condition_number = std::isfinite(cond) ? cond : INFINITY;
  if (f.has(P("/observable_condition_number")))
    r.layout.observable_condition_number = f.number(P("/observable_condition_number"));
  if (f.has(P("/sigma_um")) && !f.root().at(P("/sigma_um")).is_null())
    r.sigma = f.number(P("/sigma_um")) * 1e-3;
  if (f.has(P("/sigma_estimated")) && f.root().at(P("/sigma_estimated")).is_boolean())
    r.sigma_estimated = f.root().at(P("/sigma_estimated")).get<bool>();
  if (f.has(P("/no_uncertainty"))) r.no_uncertainty = f.string(P("/no_uncertainty"));
  if (f.has(P("/message"))) r.layout.message = f.string(P("/message"));
  if (f.has(P("/axis"))) {
    const std::string axis = f.string(P("/axis"));
    if (axis != "X" && axis != "Y" && axis != "Z")
      f.fail(P("/axis"), "the machine axis the carriage rides: X, Y or Z");
    r.axis = axis[0] - 'X';
  }
  return r;
}

ballgauge::Result read_ballgauge_map(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  ballgauge::Result r;
  const auto& pts = f.array(P("/points"));
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const P at = P("/points") / i;
    ballgauge::MapPoint q;
    q.placement = f.string(at / "placement");
    q.ball = static_cast<int>(f.number(at / "ball"));
    q.nominal = vec3(f, at / "nominal");
    q.measured = vec3(f, at / "measured");
    q.error = vec3(f, at / "error", 1e-3);
    q.uncertainty = f.root().at(at / "uncertainty").is_null() ? Eigen::Vector3d::Constant(NAN)
                                                              : vec3(f, at / "uncertainty", 1e-3);
    if (f.has(at / "frame")) q.frame = static_cast<int>(f.number(at / "frame"));
    r.points.push_back(q);
  }
  const auto& pl = f.array(P("/placements"));
  for (std::size_t i = 0; i < pl.size(); ++i) {
    const P at = P("/placements") / i;
    ballgauge::PlacementReport p;
    p.name = f.string(at / "name");
    const std::string a = f.string(at / "alignment");
    p.alignment = a == "321"  ? ballgauge::Alignment::ThreeTwoOne
                  : a == "ls" ? ballgauge::Alignment::LeastSquares
                              : ballgauge::Alignment::Stitch;
    p.balls = static_cast<int>(f.number(at / "balls"));
    p.shared = static_cast<int>(f.number(at / "shared"));
    p.registration_rms = f.number(at / "registration_rms_um") * 1e-3;
    if (f.has(at / "frame")) p.frame = static_cast<int>(f.number(at / "frame"));
    if (f.has(at / "given_centres"))
      p.given_centres = static_cast<int>(f.number(at / "given_centres"));
    if (!f.root().at(at / "diameter_error_max_um").is_null())
      p.diameter_error_max = f.number(at / "diameter_error_max_um") * 1e-3;
    r.placements.push_back(p);
  }
  if (f.has(P("/frames"))) r.frames = static_cast<int>(f.number(P("/frames")));
  if (f.has(P("/grid"))) r.grid = read_error_map(path);
  return r;
}

std::vector<ballgauge::LengthVerification> read_length_verification(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  std::vector<ballgauge::LengthVerification> out;
  const auto& rs = f.array(P("/results"));
  for (std::size_t i = 0; i < rs.size(); ++i) {
    const P at = P("/results") / i;
    ballgauge::LengthVerification v;
    v.correction = f.string(at / "correction");
    v.positions = static_cast<int>(f.number(at / "positions"));
    auto stats = [&](const P& s) {
      ballgauge::LengthStats x;
      x.min = f.number(s / "min") * 1e-3;
      x.max = f.number(s / "max") * 1e-3;
      x.mean = f.number(s / "mean") * 1e-3;
      x.rms = f.number(s / "rms") * 1e-3;
      return x;
    };
    v.before = stats(at / "before");
    v.after = stats(at / "after");
    v.repeatability = number_or_nan(f, at / "repeatability", 1e-3);
    v.correction_u_rms = number_or_nan(f, at / "correction_uncertainty_rms", 1e-3);
    v.predicted_after = number_or_nan(f, at / "expected_after_rms", 1e-3);
    // The set-ups' lines (ISO 10360-2 positions): absent from files written before they were
    // found.
    if (f.has(at / "lines")) {
      const auto& lines = f.array(at / "lines");
      for (std::size_t k = 0; k < lines.size(); ++k) {
        const Eigen::Vector3d d = vec3(f, at / "lines" / k);
        if (!(std::abs(d.norm() - 1) < 1e-6))
          f.fail(at / "lines" / k, "a line's direction must be a unit vector");
        v.line_directions.push_back(d);
      }
    }
    const auto& rows = f.array(at / "lengths");
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const P r = at / "lengths" / k;
      ballgauge::LengthRow row;
      row.nominal = f.number(r / "nominal");
      row.position = static_cast<int>(f.number(r / "position"));
      if (f.has(r / "line")) {
        const double line = f.number(r / "line");
        if (!(line >= 0 && line < static_cast<double>(v.line_directions.size())) ||
            line != std::floor(line))
          f.fail(r / "line", fmt::format("a line number 0..{} (the 'lines' given)",
                                         static_cast<long>(v.line_directions.size()) - 1));
        row.line = static_cast<int>(line);
      }
      row.before = f.number(r / "before") * 1e-3;
      row.after = f.number(r / "after") * 1e-3;
      row.uncertainty = f.number(r / "uncertainty") * 1e-3;
      v.rows.push_back(row);
    }
    out.push_back(v);
  }
  return out;
}

geometry::Fit read_fit(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  geometry::Fit x;
  try {
    x.element = geometry::element_from_string(f.string(P("/element")));
  } catch (const Error& e) {
    f.fail(P("/element"), e.what());
  }
  const bool centre = f.has(P("/center"));
  x.point = vec3(f, centre ? P("/center") : P("/point"));
  if (f.has(P("/normal"))) x.direction = vec3(f, P("/normal"));
  if (f.has(P("/direction"))) x.direction = vec3(f, P("/direction"));
  if (f.has(P("/diameter"))) x.diameter = f.number(P("/diameter"));
  if (f.has(P("/distance"))) x.distance = f.number(P("/distance"));
  if (f.has(P("/apex_angle_deg"))) x.apex_angle = f.number(P("/apex_angle_deg")) * M_PI / 180;
  if (f.has(P("/zone"))) x.zone = f.number(P("/zone"));
  x.rms = f.number(P("/rms"));
  x.max = f.number(P("/max"));
  if (f.has(P("/uncertainty"))) {
    const P u("/uncertainty");
    x.has_uncertainty = true;
    x.u_point = vec3(f, f.has(u / "center") ? u / "center" : u / "point");
    if (f.has(u / "normal")) x.u_direction = vec3(f, u / "normal");
    if (f.has(u / "direction")) x.u_direction = vec3(f, u / "direction");
    if (f.has(u / "diameter")) x.u_diameter = f.number(u / "diameter");
    if (f.has(u / "distance")) x.u_distance = f.number(u / "distance");
    if (f.has(u / "apex_angle_deg")) x.u_apex_angle = f.number(u / "apex_angle_deg") * M_PI / 180;
  }
  if (f.has(P("/dof"))) x.dof = static_cast<long>(f.number(P("/dof")));
  if (f.has(P("/condition_number"))) x.condition_number = f.number(P("/condition_number"));
  x.warnings = strings(f, P("/warnings"));
  return x;
}

}  // namespace trueaxis::io
