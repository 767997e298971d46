// design.json: planar section curves of a part.
#include "trueaxis/io/design/design.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <set>

#include "../grid_json.hpp"
#include "design_json.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/sim/part.hpp"

namespace trueaxis::io {
namespace {

using ptr = JsonFile::pointer;
using ojson = nlohmann::ordered_json;
using detail::xyz;

Eigen::Vector3d triple(const JsonFile& f, const ptr& p, const char* what) {
  const Eigen::VectorXd v = f.numbers(p);
  if (v.size() != 3) f.fail(p, fmt::format("'{}' needs [{}]", dotted(p), what));
  return v;
}

Eigen::Matrix3Xd point_list(const JsonFile& f, const ptr& p) {
  const auto& a = f.array(p);
  Eigen::Matrix3Xd m(3, static_cast<Eigen::Index>(a.size()));
  for (std::size_t i = 0; i < a.size(); ++i)
    m.col(static_cast<Eigen::Index>(i)) = triple(f, p / i, "x, y, z (mm)");
  return m;
}

void only(const JsonFile& f, const ptr& p, std::initializer_list<const char*> keys) {
  for (const auto& [key, value] : f.object(p).items()) {
    (void)value;
    bool known = false;
    std::string list;
    for (const char* k : keys) {
      known = known || key == k;
      list += (list.empty() ? "" : ", ") + std::string(k);
    }
    if (!known) f.fail(p / key, fmt::format("unknown key '{}' ({})", key, list));
  }
}

void need(const JsonFile& f, const ptr& p, const char* key) {
  if (!f.has(p / key)) f.fail(p, fmt::format("'{}' is missing", dotted(p / key)));
}

design::Section read_section(const JsonFile& f, const ptr& p) {
  only(f, p,
       {"name", "plane", "closed", "curve", "material", "normals", "joined_gap_mm", "probe",
        "solid_placement"});
  // A space curve (surface normals per point) has no plane and no material side.
  const bool space = f.has(p / "normals");
  for (const char* k : {"name", "closed", "curve"}) need(f, p, k);
  if (!space)
    for (const char* k : {"plane", "material"}) need(f, p, k);
  if (space)
    for (const char* k : {"plane", "material"})
      if (f.has(p / k))
        f.fail(p / k, fmt::format("a space curve (with 'normals') has no '{}': its surface "
                                  "normals say where the material is",
                                  k));
  design::Section s;
  s.name = f.string(p / "name");
  if (s.name.empty()) f.fail(p / "name", "a section needs a name");
  if (!space) {
    only(f, p / "plane", {"origin", "normal"});
    need(f, p / "plane", "origin");
    need(f, p / "plane", "normal");
    s.plane.origin = triple(f, p / "plane" / "origin", "x, y, z (mm)");
    s.plane.normal = triple(f, p / "plane" / "normal", "i, j, k");
  }
  if (f.has(p / "probe")) {
    if (space) f.fail(p / "probe", "a space curve is scanned with the stylus vertical: no 'probe'");
    only(f, p / "probe", {"a_deg", "b_deg"});
    if (f.has(p / "probe" / "a_deg")) s.probe.a_deg = f.number(p / "probe" / "a_deg");
    if (f.has(p / "probe" / "b_deg")) s.probe.b_deg = f.number(p / "probe" / "b_deg");
    if (const std::string why = design::head_refusal(s.probe); !why.empty())
      f.fail(p / "probe", fmt::format("section '{}': the probe head cannot take {}", s.name, why));
  }
  if (f.has(p / "solid_placement")) {
    // Three rows of four numbers: x_part = [A | t] · [x_solid; 1], A with a positive determinant.
    const ptr q = p / "solid_placement";
    const auto& rows = f.root()[q];
    if (!rows.is_array() || rows.size() != 3)
      f.fail(q, "'solid_placement' is three rows of four numbers (a 3 × 4 matrix [A | t], mm)");
    Eigen::Matrix<double, 3, 4> m;
    for (int r = 0; r < 3; ++r) {
      const Eigen::VectorXd row = f.numbers(q / std::to_string(r));
      if (row.size() != 4) f.fail(q / std::to_string(r), "each row has four numbers");
      m.row(r) = row.transpose();
    }
    const double det = m.leftCols<3>().determinant();
    if (!(det > 1e-3 && det < 1e3))
      f.fail(q, fmt::format("the placement's 3 × 3 part has determinant {:.6g}: it must keep the "
                            "solid's handedness and scale it by 0.1 to 10",
                            det));
    s.solid_placement.matrix().topRows<3>() = m;
  }
  if (f.has(p / "joined_gap_mm")) {
    s.joined_gap = f.number(p / "joined_gap_mm");
    if (!(s.joined_gap >= 0 && s.joined_gap <= 1))
      f.fail(p / "joined_gap_mm", "the gap closed to join the cut's edges must be 0 to 1 mm");
  }
  if (!f.root()[p / "closed"].is_boolean()) f.fail(p / "closed", "'closed' must be true or false");
  s.closed = f.root()[p / "closed"].get<bool>();
  if (space) {
    s.normals = point_list(f, p / "normals");
  } else {
    const std::string side = f.string(p / "material");
    if (side == "left")
      s.material = design::Side::Left;
    else if (side == "right")
      s.material = design::Side::Right;
    else
      f.fail(p / "material", fmt::format("material '{}': use \"left\" or \"right\" (seen from "
                                         "the plane normal, along the curve)",
                                         side));
  }
  const ptr c = p / "curve";
  only(f, c, {"nurbs", "polyline"});
  const bool has_n = f.has(c / "nurbs"), has_p = f.has(c / "polyline");
  if (has_n == has_p) f.fail(c, "'curve' needs exactly one of 'nurbs' or 'polyline'");
  if (has_n) {
    const ptr n = c / "nurbs";
    only(f, n, {"degree", "knots", "weights", "control_points"});
    for (const char* k : {"degree", "knots", "control_points"}) need(f, n, k);
    design::Nurbs nu;
    const double deg = f.number(n / "degree");
    if (deg != std::floor(deg) || deg < 1 || deg > 25)
      f.fail(n / "degree", "the degree must be a whole number from 1 to 25");
    nu.degree = static_cast<int>(deg);
    nu.knots = f.numbers(n / "knots");
    nu.control_points = point_list(f, n / "control_points");
    nu.weights = f.has(n / "weights") ? f.numbers(n / "weights")
                                      : Eigen::VectorXd::Ones(nu.control_points.cols());
    s.nurbs = std::move(nu);
  } else {
    s.polyline = point_list(f, c / "polyline");
  }
  if (auto pr = design::check(s)) {
    // Map the problem's field (as design.json spells it) to its place in the file.
    ptr at = p;
    std::string field = pr->field;
    for (std::size_t a = 0; a <= field.size();) {
      const std::size_t b = std::min(field.find('/', a), field.size());
      at /= field.substr(a, b - a);
      a = b + 1;
    }
    if (pr->index >= 0) at /= static_cast<std::size_t>(pr->index);
    f.fail(at, fmt::format("section '{}': {}", s.name, pr->what));
  }
  return s;
}

// The folder a file's relative paths start from.
std::filesystem::path folder_of(const std::string& file) {
  const std::filesystem::path p(file);
  return p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
}

design::Design design_at(const JsonFile& f, const ptr& base) {
  only(f, base, {"sections", "solid"});
  need(f, base, "sections");
  std::string solid;
  if (f.has(base / "solid")) {
    only(f, base / "solid", {"step"});
    need(f, base / "solid", "step");
    const std::string given = f.string(base / "solid" / "step");
    std::filesystem::path at(given);
    if (at.is_relative()) at = folder_of(f.path()) / at;
    at = at.lexically_normal();
    std::error_code ec;
    if (given.empty() || !std::filesystem::is_regular_file(at, ec))
      f.fail(base / "solid" / "step",
             fmt::format("the part's solid '{}' ({}) is not there: scanning plans its moves "
                         "against it; put the STEP file there, or remove 'solid'",
                         given, at.string()));
    solid = at.string();
  }
  const auto& a = f.array(base / "sections");
  if (a.empty()) f.fail(base / "sections", "no sections: nothing to scan");
  design::Design d;
  d.solid = solid;
  std::set<std::string> names;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d.sections.push_back(read_section(f, base / "sections" / i));
    if (!names.insert(d.sections.back().name).second)
      f.fail(base / "sections" / i / "name",
             fmt::format("section name '{}' is used twice", d.sections.back().name));
  }
  return d;
}

design::Design design_from(const JsonFile& f) {
  return design_at(f, ptr());
}

ojson design_json(const design::Design& d, const std::filesystem::path& folder);

sim::Part part_from(const JsonFile& f) {
  only(f, ptr(), {"design", "deviation"});
  need(f, ptr(), "design");
  need(f, ptr(), "deviation");
  sim::Part part;
  part.design = design_at(f, ptr() / "design");
  const ptr v = ptr() / "deviation";
  only(f, v,
       {"scale", "scale_about", "scale_direction", "directional_scale", "rotation_deg",
        "translation", "bumps", "noise_um", "seed"});
  sim::PartDeviation& d = part.deviation;
  if (f.has(v / "scale")) d.scale = f.number(v / "scale");
  if (f.has(v / "scale_about")) {
    d.scale_about = triple(f, v / "scale_about", "x, y, z (mm)");
    d.scale_about_given = true;
  }
  if (f.has(v / "scale_direction")) d.scale_direction = triple(f, v / "scale_direction", "i, j, k");
  if (f.has(v / "directional_scale")) d.directional_scale = f.number(v / "directional_scale");
  if (f.has(v / "rotation_deg")) d.rotation_deg = triple(f, v / "rotation_deg", "ax, ay, az (°)");
  if (f.has(v / "translation")) d.translation = triple(f, v / "translation", "dx, dy, dz (mm)");
  if (f.has(v / "noise_um")) d.noise = f.number(v / "noise_um") * 1e-3;
  if (f.has(v / "seed")) {
    const double seed = f.number(v / "seed");
    if (seed < 0 || seed != std::floor(seed) || seed > 9e15)
      f.fail(v / "seed", "the seed must be a whole number ≥ 0");
    d.seed = static_cast<std::uint64_t>(seed);
  }
  if (f.has(v / "bumps")) {
    const auto& b = f.array(v / "bumps");
    for (std::size_t i = 0; i < b.size(); ++i) {
      const ptr q = v / "bumps" / i;
      only(f, q, {"section", "arc_mm", "height_mm", "width_mm"});
      for (const char* k : {"section", "arc_mm", "height_mm", "width_mm"}) need(f, q, k);
      d.bumps.push_back({f.string(q / "section"), f.number(q / "arc_mm"), f.number(q / "height_mm"),
                         f.number(q / "width_mm")});
      try {
        sim::validate(d.bumps.back(), part.design);
      } catch (const Error& e) {
        f.fail(q, e.what());
      }
    }
  }
  try {
    part.validate();
  } catch (const Error& e) {
    f.fail(v, e.what());
  }
  return part;
}

}  // namespace

namespace detail {
nlohmann::ordered_json design_object(const design::Design& d, const std::filesystem::path& folder) {
  return design_json(d, folder);
}
design::Design design_object_at(const JsonFile& f, const JsonFile::pointer& at) {
  return design_at(f, at);
}
}  // namespace detail

design::Design parse_design(std::string text, const std::string& path) {
  return design_from(JsonFile::parse(std::move(text), path));
}

design::Design read_design(const std::string& path) {
  return design_from(JsonFile::read(path));
}

sim::Part read_part(const std::string& path) {
  return part_from(JsonFile::read(path));
}

sim::Part parse_part(std::string text, const std::string& path) {
  return part_from(JsonFile::parse(std::move(text), path));
}

void write_part(const std::string& path, const sim::Part& part) {
  const sim::PartDeviation& d = part.deviation;
  ojson bumps = ojson::array();
  for (const auto& b : d.bumps)
    bumps.push_back({{"section", b.section},
                     {"arc_mm", b.arc},
                     {"height_mm", b.height},
                     {"width_mm", b.width}});
  ojson dev{{"scale", d.scale}};
  if (d.scale_about_given) dev["scale_about"] = xyz(d.scale_about);
  dev["scale_direction"] = xyz(d.scale_direction);
  dev["directional_scale"] = d.directional_scale;
  dev["rotation_deg"] = xyz(d.rotation_deg);
  dev["translation"] = xyz(d.translation);
  dev["bumps"] = bumps;
  dev["noise_um"] = d.noise * 1e3;
  dev["seed"] = d.seed;
  write_json(path,
             ojson{{"design", design_json(part.design, folder_of(path))}, {"deviation", dev}});
}

void write_design(const std::string& path, const design::Design& d) {
  write_json(path, design_json(d, folder_of(path)));
}

namespace {
ojson design_json(const design::Design& d, const std::filesystem::path& folder) {
  ojson secs = ojson::array();
  for (const auto& s : d.sections) {
    ojson curve;
    if (s.nurbs) {
      ojson cps = ojson::array();
      for (Eigen::Index i = 0; i < s.nurbs->control_points.cols(); ++i)
        cps.push_back(xyz(s.nurbs->control_points.col(i)));
      curve["nurbs"] = {
          {"degree", s.nurbs->degree},
          {"knots", std::vector<double>(s.nurbs->knots.begin(), s.nurbs->knots.end())},
          {"weights", std::vector<double>(s.nurbs->weights.begin(), s.nurbs->weights.end())},
          {"control_points", cps}};
    } else {
      ojson pts = ojson::array();
      for (Eigen::Index i = 0; i < s.polyline.cols(); ++i) pts.push_back(xyz(s.polyline.col(i)));
      curve["polyline"] = pts;
    }
    if (s.space_curve()) {
      ojson normals = ojson::array();
      for (Eigen::Index i = 0; i < s.normals.cols(); ++i) normals.push_back(xyz(s.normals.col(i)));
      secs.push_back(
          ojson{{"name", s.name}, {"closed", s.closed}, {"curve", curve}, {"normals", normals}});
      continue;
    }
    ojson o{{"name", s.name},
            {"plane", {{"origin", xyz(s.plane.origin)}, {"normal", xyz(s.plane.normal)}}},
            {"closed", s.closed},
            {"curve", curve},
            {"material", design::to_string(s.material)}};
    if (s.joined_gap > 1e-9) o["joined_gap_mm"] = s.joined_gap;
    if (!s.probe.vertical() || s.probe.b_deg != 0)
      o["probe"] = {{"a_deg", s.probe.a_deg}, {"b_deg", s.probe.b_deg}};
    if (!s.solid_placement.isApprox(Eigen::Affine3d::Identity(), 1e-15)) {
      ojson rows = ojson::array();
      for (int r = 0; r < 3; ++r) {
        ojson row = ojson::array();
        for (int c = 0; c < 4; ++c) row.push_back(s.solid_placement.matrix()(r, c));
        rows.push_back(row);
      }
      o["solid_placement"] = rows;
    }
    secs.push_back(std::move(o));
  }
  ojson out{{"sections", secs}};
  if (!d.solid.empty()) {
    // Relative to the file's folder when it lies there or below, so that the two move
    // together; else where it is.
    std::error_code ec;
    const auto abs = std::filesystem::absolute(d.solid, ec);
    const auto rel = std::filesystem::proximate(abs, std::filesystem::absolute(folder, ec), ec);
    const bool below = !ec && rel.is_relative() && *rel.begin() != "..";
    out["solid"] = {{"step", below ? rel.generic_string() : abs.generic_string()}};
  }
  return out;
}
}  // namespace

}  // namespace trueaxis::io
