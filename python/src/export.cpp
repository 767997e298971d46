// Python bindings: controller compensation tables from a positioning result or an error space
// (trueaxis.export), the files `trueaxis export linuxcnc|sinumerik|heidenhain|fanuc` writes.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>
#include <set>

#include "bindings.hpp"
#include "trueaxis/compensation/table.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/compensation/controller.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/results.hpp"
#include "trueaxis/io/surface/space.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

// The options a format takes, as keyword names; any other is refused naming them.
void check_options(const std::string& format, const py::dict& options,
                   const std::set<std::string>& known) {
  for (const auto& item : options) {
    const auto key = py::cast<std::string>(item.first);
    if (!known.count(key))
      throw Error(fmt::format("export(format='{}'): no option '{}' (it takes: {})", format, key,
                              fmt::join(known, ", ")));
  }
}

template <class T>
void take(const py::dict& options, const char* key, T& into) {
  if (options.contains(key)) into = py::cast<T>(options[key]);
}

std::string export_table(const std::string& file, const std::string& output,
                         const std::string& format, const std::string& axis_text,
                         const std::optional<std::vector<double>>& at, bool unidirectional,
                         const py::dict& options) {
  if (axis_text != "x" && axis_text != "y" && axis_text != "z")
    throw Error(fmt::format("axis must be 'x', 'y' or 'z', not '{}'", axis_text));
  const int axis = axis_text[0] - 'x';
  const std::string upper(1, static_cast<char>('X' + axis));
  const std::string kind = io::read_kind(file);
  if (kind != "positioning" && kind != "space")
    throw Error(fmt::format(
        "a compensation table comes from a positioning result or an error space, not a '{}'",
        kind));
  const bool positioning = kind == "positioning";
  if (positioning && at) throw Error("at= belongs to an error space (the grid line it picks)");
  if (!positioning && unidirectional)
    throw Error("unidirectional= belongs to a positioning result");
  Eigen::Vector3d line = Eigen::Vector3d::Zero();
  std::optional<map::ErrorMap> m;
  std::optional<io::PositioningFile> p;
  if (positioning) {
    p = io::read_positioning_result(file);
  } else {
    m = io::read_error_map(file);
    if (at && at->size() != 3) throw Error("at= needs x, y, z (mm)");
    line = at ? Eigen::Vector3d((*at)[0], (*at)[1], (*at)[2]) : compensation::grid_centre(*m);
  }
  // A table of both directions where the format holds them, else their mean.
  auto table = [&](bool both) {
    return positioning ? compensation::from_positioning(p->result, both && !unidirectional)
                       : compensation::from_map(*m, axis, line);
  };
  if (format == "linuxcnc") {
    check_options(format, options, {"type"});
    int type = 1;
    take(options, "type", type);
    const int n = positioning ? io::write_linuxcnc(output, table(true), type)
                              : io::write_linuxcnc(output, *m, axis, line, type);
    return fmt::format("{} points, type {}", n, type);
  }
  if (format == "sinumerik") {
    check_options(format, options, {"axis_name", "encoder", "step", "max_points"});
    io::SinumerikOptions o;
    o.axis = upper + "1";
    take(options, "axis_name", o.axis);
    take(options, "encoder", o.encoder);
    take(options, "step", o.step);
    take(options, "max_points", o.max_points);
    return fmt::format("{} points, axis {}", io::write_sinumerik(output, table(false), o), o.axis);
  }
  if (format == "heidenhain") {
    check_options(format, options, {"axis_name", "name"});
    io::HeidenhainOptions o;
    o.axis = upper;
    take(options, "axis_name", o.axis);
    take(options, "name", o.name);
    return fmt::format("{} points, column {}", io::write_heidenhain(output, table(true), o),
                       o.axis);
  }
  if (format == "fanuc") {
    check_options(format, options,
                  {"axis_number", "axis_name", "reference", "interval", "first_number",
                   "max_number", "magnification", "detection_unit", "max_feedrate"});
    io::FanucOptions o;
    o.axis_name = upper;
    take(options, "axis_number", o.axis_number);
    take(options, "axis_name", o.axis_name);
    take(options, "reference", o.reference);
    take(options, "interval", o.interval);
    take(options, "first_number", o.first_number);
    take(options, "max_number", o.max_number);
    take(options, "magnification", o.magnification);
    take(options, "detection_unit", o.detection_unit);
    take(options, "max_feedrate", o.max_feedrate);
    const io::FanucTable f = io::write_fanuc(output, table(false), o);
    return fmt::format("points {} to {}, reference at {}, interval {:g} mm, magnification {}",
                       f.negative_number, f.positive_number, f.reference_number, f.interval,
                       f.magnification);
  }
  throw Error(
      fmt::format("format must be linuxcnc, sinumerik, heidenhain or fanuc, not '{}'", format));
}

}  // namespace

void bind_export(py::module_& m) {
  m.def("_export", &export_table, py::arg("file"), py::arg("output"), py::arg("format"),
        py::arg("axis"), py::arg("at"), py::arg("unidirectional"), py::arg("options"));
}

}  // namespace trueaxis::python
