// Python bindings: design data from STEP (trueaxis.design) and a part that differs from its
// design (trueaxis.simulate_part), the inputs of trueaxis.scan, as `trueaxis design` and
// `trueaxis simulate part` make them.
#include "trueaxis/design/design.hpp"

#include <fmt/format.h>
#include <pybind11/stl.h>

#include <map>
#include <optional>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/design/design.hpp"
#include "trueaxis/sim/part.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

Eigen::Vector3d triple(const py::handle& v, const std::string& what) {
  const auto x = py::cast<std::vector<double>>(v);
  if (x.size() != 3) throw Error(fmt::format("{} needs three numbers (x, y, z)", what));
  return {x[0], x[1], x[2]};
}

// sections: dicts {"origin": (x, y, z), "normal": (i, j, k), "name": "mid", "probe": (A, B)}.
py::dict design_from_step(const std::string& step, const py::list& sections,
                          const std::string& output) {
  std::vector<design::StepSectionRequest> req;
  std::map<std::string, design::ProbeOrientation> probes;
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const auto s = py::cast<py::dict>(sections[i]);
    for (const auto& item : s) {
      const auto key = py::cast<std::string>(item.first);
      if (key != "origin" && key != "normal" && key != "name" && key != "probe")
        throw Error(fmt::format("section {}: no key '{}' (it takes origin, normal, name, probe)",
                                i + 1, key));
    }
    if (!s.contains("origin") || !s.contains("normal"))
      throw Error(fmt::format("section {}: give both origin and normal", i + 1));
    design::StepSectionRequest r;
    r.name = s.contains("name") ? py::cast<std::string>(s["name"]) : fmt::format("S{}", i + 1);
    r.plane.origin = triple(s["origin"], fmt::format("section '{}': origin", r.name));
    r.plane.normal = triple(s["normal"], fmt::format("section '{}': normal", r.name));
    if (!(r.plane.normal.norm() > 0))
      throw Error(fmt::format("section '{}': the normal is zero", r.name));
    if (s.contains("probe")) {
      const auto ab = py::cast<std::vector<double>>(s["probe"]);
      if (ab.size() != 2) throw Error(fmt::format("section '{}': probe is (A, B) in °", r.name));
      const design::ProbeOrientation p{ab[0], ab[1]};
      if (const std::string why = design::head_refusal(p); !why.empty())
        throw Error(fmt::format("section '{}': the probe head cannot take {}", r.name, why));
      probes[r.name] = p;
    }
    req.push_back(r);
  }
  design::StepCut cut = design::cut_step(step, req);
  // Each contour of a plane is scanned with the plane's probe orientation.
  design::assign_probes(cut.design, probes);
  py::list made, failed;
  for (const auto& s : cut.design.sections) {
    py::dict d;
    d["name"] = s.name;
    d["closed"] = s.closed;
    d["length_mm"] = design::length(s);
    d["material"] = s.space_curve() ? "behind its normals" : design::to_string(s.material);
    d["joined_gap_mm"] = s.joined_gap;
    made.append(d);
  }
  for (const auto& f : cut.failures) {
    py::dict d;
    d["name"] = f.name;
    d["reason"] = f.reason;
    failed.append(d);
  }
  if (cut.design.sections.empty())
    throw Error(fmt::format("{}: no section could be made: {}", step,
                            cut.failures.empty() ? "no plane given" : cut.failures.front().reason));
  if (!output.empty()) io::write_design(output, cut.design);
  py::dict out;
  out["sections"] = made;
  out["failures"] = failed;
  out["solids"] = cut.solids;
  out["join_tolerance_mm"] = cut.join_tolerance;
  out["file_tolerance_mm"] =
      cut.file_tolerance ? py::cast(*cut.file_tolerance) : py::object(py::none());
  out["notes"] = cut.notes;
  return out;
}

// bumps: (section, arc_mm, height_mm, width_mm) each.
py::dict simulate_part(const std::string& design_file, const std::string& output, double scale,
                       const std::optional<std::vector<double>>& scale_about,
                       const std::optional<std::vector<double>>& scale_along,
                       const std::optional<std::vector<double>>& rotate,
                       const std::optional<std::vector<double>>& translate, const py::list& bumps,
                       double noise, std::uint64_t seed) {
  sim::Part p;
  p.design = io::read_design(design_file);
  sim::PartDeviation& d = p.deviation;
  d.scale = scale;
  if (scale_about) {
    d.scale_about = triple(py::cast(*scale_about), "scale_about");
    d.scale_about_given = true;
  }
  if (scale_along) {
    if (scale_along->size() != 4)
      throw Error("scale_along is (i, j, k, factor): a direction and its scale factor");
    d.scale_direction = Eigen::Vector3d((*scale_along)[0], (*scale_along)[1], (*scale_along)[2]);
    d.directional_scale = (*scale_along)[3];
  }
  if (rotate) d.rotation_deg = triple(py::cast(*rotate), "rotate");
  if (translate) d.translation = triple(py::cast(*translate), "translate");
  for (const auto& b : bumps) {
    const auto t = py::cast<py::tuple>(b);
    if (t.size() != 4) throw Error("a bump is (section, arc_mm, height_mm, width_mm)");
    sim::Bump bump;
    bump.section = py::cast<std::string>(t[0]);
    bump.arc = py::cast<double>(t[1]);
    bump.height = py::cast<double>(t[2]);
    bump.width = py::cast<double>(t[3]);
    d.bumps.push_back(bump);
  }
  d.noise = noise * 1e-3;
  d.seed = seed;
  p.validate();
  io::write_part(output, p);
  py::dict out;
  out["sections"] = p.design.sections.size();
  out["bumps"] = d.bumps.size();
  out["centroid_shift_mm"] =
      (sim::transform(p) * sim::centroid(p.design) - sim::centroid(p.design)).norm();
  return out;
}

}  // namespace

void bind_design(py::module_& m) {
  m.def("design", &design_from_step, py::arg("step"), py::arg("sections"), py::kw_only(),
        py::arg("output") = "",
        "Sections of a STEP part (AP203/AP214, mm) as design data for scanning, as 'trueaxis "
        "design --step' makes them. sections: a list of dicts {'origin': (x, y, z), 'normal': (i, "
        "j, k), 'name': 'mid', 'probe': (A, B) in °}. output: the design.json to write (the "
        "input of scan()). Returns a dict: sections (name, closed, length_mm, material, "
        "joined_gap_mm), failures (planes that gave no section, each with its reason), solids, "
        "join_tolerance_mm, file_tolerance_mm (None: the file states none), notes. Raises "
        "trueaxis.Error when no section could be made.");
  m.def("simulate_part", &simulate_part, py::arg("design"), py::arg("output"), py::kw_only(),
        py::arg("scale") = 1.0, py::arg("scale_about") = py::none(),
        py::arg("scale_along") = py::none(), py::arg("rotate") = py::none(),
        py::arg("translate") = py::none(), py::arg("bumps") = py::list(), py::arg("noise") = 0.0,
        py::arg("seed") = 1,
        "A part that differs from its design (design.json), written as part.json for scan(), as "
        "'trueaxis simulate part' makes it: uniform scale about scale_about (x, y, z; default the "
        "centroid), scale_along (i, j, k, factor), rotate (°, about x, y, z), translate (mm), "
        "bumps [(section, arc_mm, height_mm, width_mm)], form noise (µm, standard deviation) "
        "and its seed. Returns a dict: sections, bumps, centroid_shift_mm.");
}

}  // namespace trueaxis::python
