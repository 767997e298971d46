// Python bindings for the virtual machine, error surfaces and error spaces
// and error maps. Points are numpy arrays of shape (n, 3) (or a single point of shape (3,)),
// in mm; error vectors in µm; error functions in µm or µrad.
#include "trueaxis/io/surface/space.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cstring>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/io/surface/surface.hpp"
#include "trueaxis/map/error_map.hpp"
#include "trueaxis/sim/machine.hpp"
#include "trueaxis/surface/space.hpp"
#include "trueaxis/surface/surface.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

using InArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Points of shape (n, 3) or (3,) as a 3 × n matrix (the same memory order as numpy's rows).
struct Points {
  Eigen::Matrix3Xd xyz;
  bool single = false;
};

// Checks the shape (n, 3) or (3,); returns n (1 for a single point).
Eigen::Index point_count(const InArray& a, const char* what) {
  if (a.ndim() == 1 && a.shape(0) == 3) return 1;
  if (a.ndim() != 2 || a.shape(1) != 3) {
    std::string shape;
    for (py::ssize_t d = 0; d < a.ndim(); ++d)
      shape += fmt::format("{}{}", d ? ", " : "", a.shape(d));
    throw Error(fmt::format("{} must have shape (n, 3) or (3,), not ({})", what, shape));
  }
  return static_cast<Eigen::Index>(a.shape(0));
}

Points points_in(const InArray& a, const char* what) {
  Points p;
  const Eigen::Index n = point_count(a, what);
  p.single = a.ndim() == 1;
  p.xyz = Eigen::Map<const Eigen::Matrix3Xd>(a.data(), 3, n);
  if (!p.xyz.allFinite()) throw Error(fmt::format("{} contain NaN or infinite values", what));
  return p;
}

// For in-place work on a copy: `fn` is called, with the GIL released, on a 3 × n view of a copy
// of a's points, and the copy is returned. The copy goes to `out` if given (a C-ordered float64
// array of a's shape, which may be the input itself: then nothing is copied), else to a new
// array. One copy at most (the input is changed only when it is `out`).
template <class Fn>
py::array_t<double> on_copy(const InArray& a, const char* what, const py::object& out_arg,
                            Fn&& fn) {
  const Eigen::Index n = point_count(a, what);
  const std::vector<py::ssize_t> shape(a.shape(), a.shape() + a.ndim());
  py::array_t<double> out;
  if (out_arg.is_none()) {
    out = py::array_t<double>(shape);
  } else {
    if (!py::isinstance<py::array_t<double>>(out_arg))
      throw Error("out must be a numpy array of float64");
    out = py::reinterpret_borrow<py::array_t<double>>(out_arg);
    if (!(out.flags() & py::array::c_style) || !out.writeable())
      throw Error("out must be a writeable, C-ordered (row-major) array");
    if (std::vector<py::ssize_t>(out.shape(), out.shape() + out.ndim()) != shape)
      throw Error(fmt::format("out must have the shape of {}", what));
  }
  Eigen::Map<Eigen::Matrix3Xd> xyz(out.mutable_data(), 3, n);
  bool finite = true;
  {
    py::gil_scoped_release release;
    if (xyz.data() != a.data())
      std::memcpy(xyz.data(), a.data(), sizeof(double) * static_cast<std::size_t>(3 * n));
    finite = xyz.allFinite();
    if (finite) fn(xyz);
  }
  if (!finite) throw Error(fmt::format("{} contain NaN or infinite values", what));
  return out;
}

py::array_t<double> points_out(const Eigen::Matrix3Xd& m, bool single, double scale = 1.0) {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(m.cols()), 3};
  if (single) shape = {3};
  py::array_t<double> out(shape);
  Eigen::Map<Eigen::Matrix3Xd>(out.mutable_data(), 3, m.cols()) = m * scale;
  return out;
}

Eigen::Vector3d vector3(const std::vector<double>& v, const char* what) {
  if (v.size() != 3) throw Error(fmt::format("{} needs 3 numbers, not {}", what, v.size()));
  return {v[0], v[1], v[2]};
}

std::array<std::array<double, 2>, 3> ranges_in(const std::vector<std::vector<double>>& r) {
  if (r.size() != 3) throw Error("ranges needs [[xmin, xmax], [ymin, ymax], [zmin, zmax]] (mm)");
  std::array<std::array<double, 2>, 3> out{};
  for (std::size_t k = 0; k < 3; ++k) {
    if (r[k].size() != 2) throw Error("ranges needs [min, max] for every axis (mm)");
    out[k] = {r[k][0], r[k][1]};
  }
  return out;
}

// ISO 230-1 error name → (axis, component), or squareness (axis = -1, component = 0..2).
std::pair<int, int> error_index(const std::string& name) {
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 6; ++c)
      if (sim::error_name(a, static_cast<sim::Component>(c)) == name) return {a, c};
  const char* sq[3] = {"EC0Y", "EB0Z", "EA0Z"};
  for (int i = 0; i < 3; ++i)
    if (name == sq[i]) return {-1, i};
  throw Error(fmt::format("unknown error name '{}' (EXX, EYX, ..., ECZ, EC0Y, EB0Z, EA0Z)", name));
}

// ---------------------------------------------------------------------------------------------
// Error maps. error(i, j, k) in numpy is error[i, j, k, :] for node (x_i, y_j, z_k).

py::array_t<double> node_field(const Eigen::Matrix3Xd& f, const map::ErrorMap& m) {
  const auto nx = m.size(0), ny = m.size(1), nz = m.size(2);
  py::array_t<double> out({static_cast<py::ssize_t>(nx), static_cast<py::ssize_t>(ny),
                           static_cast<py::ssize_t>(nz), py::ssize_t{3}});
  auto r = out.mutable_unchecked<4>();
  for (Eigen::Index k = 0; k < nz; ++k)
    for (Eigen::Index j = 0; j < ny; ++j)
      for (Eigen::Index i = 0; i < nx; ++i)
        for (int c = 0; c < 3; ++c) r(i, j, k, c) = f(c, m.index(i, j, k)) * 1e3;
  return out;
}

Eigen::Matrix3Xd node_field_in(const InArray& a, const map::ErrorMap& m, const char* what) {
  const auto nx = m.size(0), ny = m.size(1), nz = m.size(2);
  if (a.ndim() != 4 || a.shape(0) != nx || a.shape(1) != ny || a.shape(2) != nz || a.shape(3) != 3)
    throw Error(fmt::format("{} must have shape (len(x), len(y), len(z), 3) = ({}, {}, {}, 3)",
                            what, nx, ny, nz));
  Eigen::Matrix3Xd f(3, m.nodes());
  auto r = a.unchecked<4>();
  for (Eigen::Index k = 0; k < nz; ++k)
    for (Eigen::Index j = 0; j < ny; ++j)
      for (Eigen::Index i = 0; i < nx; ++i)
        for (int c = 0; c < 3; ++c) f(c, m.index(i, j, k)) = r(i, j, k, c) * 1e-3;
  return f;
}

map::ErrorMap make_map(const Eigen::VectorXd& x, const Eigen::VectorXd& y, const Eigen::VectorXd& z,
                       const InArray& error, std::optional<InArray> uncertainty) {
  map::ErrorMap m;
  m.axes = {x, y, z};
  for (int k = 0; k < 3; ++k)
    if (m.size(k) < 2) throw Error("every axis of an error map needs at least 2 nodes");
  m.error = node_field_in(error, m, "error");
  if (uncertainty) m.uncertainty = node_field_in(*uncertainty, m, "uncertainty");
  m.validate();
  return m;
}

map::EvalOptions eval_options(const std::string& interpolation, bool clamp) {
  map::EvalOptions o;
  o.interpolation = map::interpolation_from_string(interpolation);
  o.outside = clamp ? map::Outside::Clamp : map::Outside::Refuse;
  return o;
}

// ---------------------------------------------------------------------------------------------
// Surfaces.

surface::Line line_in(const py::dict& d, std::size_t index) {
  surface::Line l;
  const std::string where = fmt::format("lines[{}]", index);
  bool heights = false, slopes = false;
  for (auto item : d) {
    const std::string key = py::cast<std::string>(item.first);
    const py::handle v = item.second;
    if (key == "name") {
      l.name = py::cast<std::string>(v);
    } else if (key == "start") {
      const auto s = py::cast<std::vector<double>>(v);
      if (s.size() != 2) throw Error(where + ".start needs [x, y] (mm)");
      l.start = {s[0], s[1]};
    } else if (key == "direction") {
      const auto s = py::cast<std::vector<double>>(v);
      if (s.size() != 2) throw Error(where + ".direction needs [dx, dy]");
      l.direction = {s[0], s[1]};
    } else if (key == "spacing") {
      l.spacing = py::cast<double>(v);
    } else if (key == "heights") {
      l.heights = py::cast<Eigen::VectorXd>(v) * 1e-3;
      heights = true;
    } else if (key == "slopes") {
      slopes = true;
      l.heights = py::cast<Eigen::VectorXd>(v) * 1e-6;  // converted once the spacing is known
    } else {
      throw Error(fmt::format(
          "{}: unknown key '{}' (name, start, direction, spacing, heights or slopes)", where, key));
    }
  }
  if (heights == slopes)
    throw Error(where + " needs exactly one of 'heights' (µm) or 'slopes' (µrad)");
  if (l.name.empty()) l.name = where;
  if (!(l.spacing > 0)) throw Error(where + ".spacing must be a positive number of mm");
  if (slopes) l.heights = surface::heights_from_slopes(l.heights, l.spacing);
  return l;
}

py::dict surface_out(const surface::Result& r) {
  py::dict d;
  d["method"] = r.method;
  d["lines"] = r.lines;
  const auto n = static_cast<Eigen::Index>(r.points.size());
  Eigen::VectorXi line(n);
  Eigen::VectorXd station(n), x(n), y(n), h(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& p = r.points[static_cast<std::size_t>(i)];
    line[i] = p.line;
    station[i] = static_cast<double>(p.station);
    x[i] = p.xy.x();
    y[i] = p.xy.y();
    h[i] = p.height * 1e3;
  }
  py::dict pts;
  pts["line"] = line;
  pts["station"] = station;
  pts["x"] = x;
  pts["y"] = y;
  pts["height"] = h;
  d["points"] = pts;
  if (r.grid) {
    py::dict g;
    g["x"] = r.grid->x;
    g["y"] = r.grid->y;
    g["height"] = Eigen::MatrixXd(r.grid->height * 1e3);
    d["grid"] = g;
  } else {
    d["grid"] = py::none();
  }
  const auto nc = static_cast<Eigen::Index>(r.crossings.size());
  Eigen::VectorXi ca(nc), cb(nc);
  Eigen::VectorXd cx(nc), cy(nc), cr(nc);
  for (Eigen::Index i = 0; i < nc; ++i) {
    const auto& c = r.crossings[static_cast<std::size_t>(i)];
    ca[i] = c.a;
    cb[i] = c.b;
    cx[i] = c.xy.x();
    cy[i] = c.xy.y();
    cr[i] = c.residual * 1e3;
  }
  py::dict cross;
  cross["a"] = ca;
  cross["b"] = cb;
  cross["x"] = cx;
  cross["y"] = cy;
  cross["residual"] = cr;
  d["crossings"] = cross;
  d["flatness"] = py::dict(
      py::arg("ls") = r.flatness_ls * 1e3, py::arg("min_zone") = r.flatness_min_zone * 1e3,
      py::arg("U_um") = r.U ? py::object(py::float_(*r.U * 1e3)) : py::object(py::none()),
      py::arg("resolved") = r.U ? py::object(py::bool_(*r.resolved())) : py::object(py::none()),
      py::arg("sigma") = r.U ? py::object(py::float_(r.sigma)) : py::object(py::none()),
      py::arg("sigma_unit") = r.sigma_unit, py::arg("no_uncertainty") = r.no_uncertainty());
  d["closure"] =
      py::dict(py::arg("rms") = r.closure_rms * 1e3, py::arg("max") = r.closure_max * 1e3);
  d["reference"] = r.reference;
  d["unobservable"] = r.unobservable;
  d["gauge"] = r.gauge;
  d["summary"] = r.summary();
  return d;
}

py::dict verification_out(const surface::Verification& v) {
  py::dict d;
  d["points"] = v.points;
  d["before_rms"] = v.before_rms * 1e3;
  d["before_max"] = v.before_max * 1e3;
  d["after_rms"] = v.after_rms * 1e3;
  d["after_max"] = v.after_max * 1e3;
  d["interpolation_rms"] = v.interpolation_rms * 1e3;
  // Not computed (no Monte Carlo): None, and the prediction is only its interpolation part.
  d["uncertainty_rms"] = v.uncertainty_known ? py::object(py::float_(v.uncertainty_rms * 1e3))
                                             : py::object(py::none());
  d["predicted_rms"] = v.predicted_rms * 1e3;
  d["predicted_is_lower_bound"] = !v.uncertainty_known;
  d["improvement"] = v.improvement();
  return d;
}

}  // namespace

void bind_space(py::module_& m) {
  // ---- Machine --------------------------------------------------------------------------------
  py::class_<sim::Machine>(m, "Machine",
                           R"doc(A rigid-body virtual 3-axis machine (21 ISO 230-1 errors).

The 21 ISO 230-1 errors (EXX ... ECZ as functions of their axis' coordinate, EC0Y, EB0Z, EA0Z
squareness), exact homogeneous transformations along the kinematic chain (e.g. 'FYXZ', a bridge
CMM). Create one with Machine.random(...) or Machine.load('machine.json').)doc")
      .def_static(
          "random",
          [](std::uint64_t seed, const std::string& chain,
             std::optional<std::vector<std::vector<double>>> ranges,
             std::optional<std::vector<double>> offset, double straightness, double angular,
             double positioning, double squareness, double lead_amplitude, double lead) {
            sim::MachineOptions o;
            o.seed = seed;
            o.chain = chain;
            if (ranges) o.range = ranges_in(*ranges);
            if (offset) o.offset = vector3(*offset, "offset");
            o.straightness = straightness * 1e-3;
            o.angular = angular * 1e-6;
            o.positioning = positioning * 1e-6;
            o.squareness = squareness * 1e-6;
            o.lead_amplitude = lead_amplitude * 1e-3;
            o.lead = lead;
            return sim::random_machine(o);
          },
          py::kw_only(), py::arg("seed") = 1, py::arg("chain") = "FYXZ",
          py::arg("ranges") = py::none(), py::arg("offset") = py::none(),
          py::arg("straightness") = 3.0, py::arg("angular") = 10.0, py::arg("positioning") = 10.0,
          py::arg("squareness") = 20.0, py::arg("lead_amplitude") = 0.0, py::arg("lead") = 10.0,
          R"doc(A seeded machine with realistic errors.

ranges: [[xmin, xmax], [ymin, ymax], [zmin, zmax]] mm (default 800 x 600 x 500 from 0); offset:
stylus/tool offset [x, y, z] mm (default [0, 0, -100]); straightness: µm over 500 mm; angular:
µrad; positioning: µm per m; squareness: µrad (standard deviation); lead_amplitude: µm of a lead
screw term of period `lead` mm.)doc")
      .def_static("load", static_cast<sim::Machine (*)(const std::string&)>(&io::read_machine),
                  py::arg("path"), "Reads a machine.json (errors name file:line:col).")
      .def(
          "save",
          [](const sim::Machine& mc, const std::string& path) { io::write_machine(path, mc); },
          py::arg("path"), "Writes machine.json.")
      .def_readwrite("name", &sim::Machine::name)
      .def_property_readonly("chain", [](const sim::Machine& mc) { return mc.chain; })
      .def_property_readonly(
          "ranges",
          [](const sim::Machine& mc) {
            Eigen::Matrix<double, 3, 2> r;
            for (int k = 0; k < 3; ++k)
              r.row(k) << mc.range[static_cast<std::size_t>(k)][0],
                  mc.range[static_cast<std::size_t>(k)][1];
            return r;
          },
          "Axis ranges (mm), rows x, y, z: [min, max].")
      .def_property_readonly(
          "offset", [](const sim::Machine& mc) { return Eigen::Vector3d(mc.offset); },
          "Stylus/tool offset (mm).")
      .def(
          "error",
          [](const sim::Machine& mc, const InArray& points, bool check_range) {
            const Points p = points_in(points, "points");
            if (check_range)
              for (Eigen::Index i = 0; i < p.xyz.cols(); ++i)
                if (!mc.contains(p.xyz.col(i)))
                  throw Error(
                      fmt::format("point {} ({:g}, {:g}, {:g}) mm is outside the machine's "
                                  "ranges",
                                  i, p.xyz(0, i), p.xyz(1, i), p.xyz(2, i)));
            Eigen::Matrix3Xd e;
            {
              py::gil_scoped_release release;
              e = mc.errors_at(p.xyz);
            }
            return points_out(e, p.single, 1e3);
          },
          py::arg("points"), py::kw_only(), py::arg("check_range") = true,
          "True error vectors actual − nominal (µm) of the tool point at commanded positions "
          "(mm), shape (n, 3) or (3,). Points outside the ranges are refused unless "
          "check_range=False.")
      .def(
          "error_function",
          [](const sim::Machine& mc, const std::string& name, const Eigen::VectorXd& u) {
            const auto [axis, c] = error_index(name);
            Eigen::VectorXd v(u.size());
            if (axis < 0) {
              const double s[3] = {mc.squareness_c0y, mc.squareness_b0z, mc.squareness_a0z};
              v.setConstant(s[c] * 1e6);
              return v;
            }
            const auto& f = mc.errors[static_cast<std::size_t>(axis)][static_cast<std::size_t>(c)];
            const auto& r = mc.range[static_cast<std::size_t>(axis)];
            const double scale = c < 3 ? 1e3 : 1e6;
            for (Eigen::Index i = 0; i < u.size(); ++i) {
              if (!(u[i] >= r[0] - 1e-9 && u[i] <= r[1] + 1e-9))
                throw Error(fmt::format("{}: u = {:g} mm is outside the axis range [{:g}, {:g}]",
                                        name, u[i], r[0], r[1]));
              v[i] = f.empty() ? 0.0 : f(u[i]) * scale;
            }
            return v;
          },
          py::arg("name"), py::arg("u"),
          "One of the 21 errors by its ISO 230-1 name ('EXX', 'EYX', ..., 'EC0Y') at axis "
          "coordinates u (mm): µm for translations, µrad for rotations and squareness.")
      .def("summary", &sim::Machine::summary,
           py::arg("not_determined") = std::vector<std::string>{},
           "A short table of the 21 errors: per axis the span of its positioning and angular "
           "errors over its range (µm, µrad), its straightness errors, and the squareness "
           "errors (ISO 230-1). not_determined: ISO names of errors the data could not determine "
           "(e.g. ['ECX']), which read 'n/d' instead of a number.")
      .def("__repr__", [](const sim::Machine& mc) {
        return fmt::format("<trueaxis.Machine '{}' chain {}>", mc.name, mc.chain);
      });

  // ---- ErrorMap -------------------------------------------------------------------------------
  py::class_<map::ErrorMap>(m, "ErrorMap", R"doc(Error vectors on a 3-D grid, and compensation.

ErrorMap(x, y, z, error, uncertainty=None): node coordinates x, y, z (mm, increasing, >= 2 each);
error[i, j, k, :] = actual − nominal (µm) at node (x[i], y[j], z[k]); uncertainty the same shape
(µm). ErrorMap.load('space.json') reads the grid of a 'trueaxis space' file. Between nodes:
'linear' (trilinear) or 'cubic' (C¹ Hermite) interpolation. Outside the grid: refused, or held
at the nearest face with clamp=True; never extrapolated.)doc")
      .def(py::init(&make_map), py::arg("x"), py::arg("y"), py::arg("z"), py::arg("error"),
           py::arg("uncertainty") = py::none())
      .def_static("load", &io::read_error_map, py::arg("path"),
                  "Reads the grid of a space.json (errors name file:line:col).")
      .def(
          "to_csv",
          [](const map::ErrorMap& mp, const std::string& path) { io::write_map_csv(path, mp); },
          py::arg("path"),
          "Writes the generic table x,y,z (mm), ex,ey,ez (µm)[, ux,uy,uz], one row per node.")
      .def(
          "export_linuxcnc",
          [](const map::ErrorMap& mp, const std::string& path, const std::string& axis,
             std::optional<std::vector<double>> at, int type) {
            const int a = axis == "x" ? 0 : axis == "y" ? 1 : axis == "z" ? 2 : -1;
            if (a < 0) throw Error(fmt::format("axis must be 'x', 'y' or 'z', not '{}'", axis));
            Eigen::Vector3d p;
            for (int k = 0; k < 3; ++k)
              p[k] = 0.5 * (mp.axes[static_cast<std::size_t>(k)][0] +
                            mp.axes[static_cast<std::size_t>(k)][mp.size(k) - 1]);
            if (at) p = vector3(*at, "at");
            return io::write_linuxcnc(path, mp, a, p, type);
          },
          py::arg("path"), py::arg("axis"), py::kw_only(), py::arg("at") = py::none(),
          py::arg("type") = 1,
          "LinuxCNC per-joint compensation file for `axis` along the grid line through `at` "
          "(mm; default the grid's centre); type 0 = actual positions, 1 = trims. Returns the "
          "number of lines.")
      .def_property_readonly("x", [](const map::ErrorMap& mp) { return mp.axes[0]; })
      .def_property_readonly("y", [](const map::ErrorMap& mp) { return mp.axes[1]; })
      .def_property_readonly("z", [](const map::ErrorMap& mp) { return mp.axes[2]; })
      .def_property_readonly(
          "error", [](const map::ErrorMap& mp) { return node_field(mp.error, mp); },
          "error[i, j, k, :] (µm) at node (x[i], y[j], z[k]) (a copy).")
      .def_property_readonly(
          "uncertainty",
          [](const map::ErrorMap& mp) -> py::object {
            if (mp.uncertainty.cols() == 0) return py::none();
            return node_field(mp.uncertainty, mp);
          },
          "Standard uncertainty (µm), same shape as error, or None.")
      .def(
          "evaluate",
          [](const map::ErrorMap& mp, const InArray& points, const std::string& interpolation,
             bool clamp) {
            const Points p = points_in(points, "points");
            const auto o = eval_options(interpolation, clamp);
            Eigen::Matrix3Xd e;
            {
              py::gil_scoped_release release;
              e = map::evaluate(mp, p.xyz, o);
            }
            return points_out(e, p.single, 1e3);
          },
          py::arg("points"), py::kw_only(), py::arg("interpolation") = "linear",
          py::arg("clamp") = false, "Interpolated error vectors (µm) at points (mm).")
      .def(
          "compensate",
          [](const map::ErrorMap& mp, const InArray& points, const std::string& interpolation,
             bool clamp, int iterations, const py::object& out) {
            map::CompensateOptions o;
            o.eval = eval_options(interpolation, clamp);
            o.iterations = iterations;
            return on_copy(points, "commands", out,
                           [&](Eigen::Map<Eigen::Matrix3Xd> c) { map::compensate(mp, c, o); });
          },
          py::arg("commands"), py::kw_only(), py::arg("interpolation") = "linear",
          py::arg("clamp") = false, py::arg("iterations") = 2, py::arg("out") = py::none(),
          "Compensated commands (mm): for wanted tool positions c, the commands c' with "
          "c' + e(c') = c (fixed-point iteration), in parallel with the GIL released. out: as "
          "for correct.")
      .def(
          "correct",
          [](const map::ErrorMap& mp, const InArray& points, const std::string& interpolation,
             bool clamp, const py::object& out) {
            const auto o = eval_options(interpolation, clamp);
            return on_copy(points, "points", out,
                           [&](Eigen::Map<Eigen::Matrix3Xd> p) { map::correct(mp, p, o); });
          },
          py::arg("points"), py::kw_only(), py::arg("interpolation") = "linear",
          py::arg("clamp") = false, py::arg("out") = py::none(),
          "Corrected measured points x − e(x) (mm), in parallel with the GIL released. out: an "
          "array of the points' shape (float64, C order) to write them to, e.g. the points "
          "themselves to correct in place without a copy; returned.")
      .def("__repr__", [](const map::ErrorMap& mp) {
        return fmt::format("<trueaxis.ErrorMap {} x {} x {} nodes{}>", mp.size(0), mp.size(1),
                           mp.size(2), mp.uncertainty.cols() ? " with uncertainty" : "");
      });

  // ---- Surfaces -------------------------------------------------------------------------------
  m.def(
      "surface",
      [](const py::object& lines, const std::string& method) {
        std::vector<surface::Line> ls;
        if (py::isinstance<py::str>(lines)) {
          ls = io::read_lines(py::cast<std::string>(lines));
        } else {
          std::size_t i = 0;
          for (auto item : lines) ls.push_back(line_in(py::cast<py::dict>(item), i++));
        }
        surface::Options o;
        if (method == "lsq")
          o.method = surface::Method::Lsq;
        else if (method == "boundary")
          o.method = surface::Method::Seed;
        else
          throw Error(fmt::format("method must be 'lsq' or 'boundary', not '{}'", method));
        surface::Result r;
        {
          py::gil_scoped_release release;
          r = surface::build(std::move(ls), o);
        }
        py::dict d = surface_out(r);
        savable(d, [r](const std::string& path) { io::write_surface(path, r); });
        return d;
      },
      py::arg("lines"), py::kw_only(), py::arg("method") = "lsq",
      R"doc(Error surface from a network of straightness lines (Moody 1955; least squares over any crossing lines).

lines: a lines.json path, or a list of dicts {'name', 'start': [x, y] (mm), 'direction':
[dx, dy], 'spacing': mm, and 'heights' (µm) or 'slopes' (µrad, one per foot)}. method: 'lsq'
(all lines jointly) or 'boundary' (X lines hung on two boundary Y lines).

Returns {'points': {'line', 'station', 'x', 'y', 'height' (µm)}, 'grid' ({'x', 'y', 'height'
(len(y), len(x))} or None), 'flatness': {'ls', 'min_zone', 'U_um' (95 %, from the readings' noise that the closure at the crossings shows) and 'resolved' (None: the network cannot show the noise, 'no_uncertainty' says why), 'sigma' (one reading's noise, in 'sigma_unit')}, 'closure': {'rms', 'max'},
'crossings', 'unobservable', 'gauge', 'reference', 'summary'}.)doc");
  m.def(
      "moody",
      [](const std::string& dir, const std::string& method) {
        if (method != "classic" && method != "lsq")
          throw Error(fmt::format("method must be 'classic' or 'lsq', not '{}'", method));
        const surface::Result r = surface::moody(io::read_moody(dir), method == "lsq");
        py::dict d = surface_out(r);
        savable(d, [r](const std::string& path) { io::write_surface(path, r); });
        return d;
      },
      py::arg("directory"), py::kw_only(), py::arg("method") = "classic",
      "Moody's Union Jack from a directory of his eight files and Config.txt; 'classic' "
      "reproduces his worksheet, 'lsq' adjusts the same lines jointly and reports the closure. "
      "Returns the same dict as surface().");

  // ---- Error space ----------------------------------------------------------------------------
  m.def(
      "measure_space",
      [](const sim::Machine& mc, std::optional<std::string> plan_path, double spacing,
         const std::string& probes, double probe_noise, double laser_noise, double profile,
         bool diagonals, int monte_carlo, std::uint64_t seed, long verify) {
        surface::SpacePlan p;
        if (plan_path) {
          p = io::read_plan(*plan_path);
        } else {
          p.spacing = spacing;
          if (probes == "three-point")
            p.probes = surface::ProbeMethod::ThreePoint;
          else if (probes == "two-point")
            p.probes = surface::ProbeMethod::TwoPoint;
          else
            throw Error(
                fmt::format("probes must be 'three-point' or 'two-point', not '{}'", probes));
          p.probe_noise = probe_noise * 1e-3;
          p.laser_noise = laser_noise * 1e-3;
          p.profile_amplitude = profile * 1e-3;
          p.diagonals = diagonals;
          p.monte_carlo = monte_carlo;
          p.seed = seed;
          p.validate();
        }
        surface::SpaceResult s;
        std::optional<surface::Verification> v;
        {
          py::gil_scoped_release release;
          s = surface::measure_space(mc, p);
          if (verify > 0) v = surface::verify_compensation(mc, s.map, verify, p.seed);
        }
        py::dict d;
        py::list surfaces;
        for (const auto& l : s.surfaces)
          surfaces.append(py::dict(py::arg("component") = std::string(1, "xyz"[l.component]),
                                   py::arg("level") = l.level,
                                   py::arg("closure_rms") = l.closure_rms * 1e3,
                                   py::arg("flatness_ls") = l.flatness_ls * 1e3));
        d["surfaces"] = surfaces;
        d["straightness_runs"] = s.straightness_runs;
        d["laser_runs"] = s.laser_runs;
        d["unobservable"] = s.unobservable;
        d["gauge"] = s.gauge;
        d["truth"] =
            py::dict(py::arg("rms") = s.truth_rms * 1e3, py::arg("max") = s.truth_max * 1e3);
        d["verification"] = v ? py::object(verification_out(*v)) : py::object(py::none());
        d["summary"] = s.summary();
        savable(d, [s, p, v](const std::string& path) { io::write_space(path, s, p, v); });
        d["map"] = std::move(s.map);
        return d;
      },
      py::arg("machine"), py::kw_only(), py::arg("plan") = py::none(), py::arg("spacing") = 50.0,
      py::arg("probes") = "three-point", py::arg("probe_noise") = 0.0, py::arg("laser_noise") = 0.0,
      py::arg("profile") = 2.0, py::arg("diagonals") = true, py::arg("monte_carlo") = 0,
      py::arg("seed") = 1, py::arg("verify") = 0,
      R"doc(Runs a measuring campaign on the virtual machine and assembles its error space.

plan: a plan.json path (then the other campaign arguments are ignored), or spacing (mm, largest
grid step), probes ('three-point' or 'two-point'), probe_noise and laser_noise (µm, standard
deviations), profile (µm, the straightedges' own form), diagonals (twist lines and squareness
diagonals), monte_carlo (repetitions for the uncertainty), seed. verify: number of random points
of the compensation check (0: none).

Returns {'map': ErrorMap (rigid-body part removed), 'surfaces', 'straightness_runs',
'laser_runs', 'unobservable', 'gauge', 'truth': {'rms', 'max'} (µm, estimate against the
machine's truth), 'verification' (see verify_compensation) or None, 'summary'}.)doc");
  m.def(
      "verify_compensation",
      [](const sim::Machine& mc, const map::ErrorMap& mp, long points, std::uint64_t seed,
         const std::string& interpolation, int iterations) {
        map::CompensateOptions o;
        o.eval = eval_options(interpolation, false);
        o.iterations = iterations;
        surface::Verification v;
        {
          py::gil_scoped_release release;
          v = surface::verify_compensation(mc, mp, points, seed, o);
        }
        return verification_out(v);
      },
      py::arg("machine"), py::arg("map"), py::kw_only(), py::arg("points") = 1000,
      py::arg("seed") = 1, py::arg("interpolation") = "linear", py::arg("iterations") = 2,
      R"doc(Compensation check on the virtual machine at random points in the map's grid.

Returns µm: {'points', 'before_rms', 'before_max', 'after_rms', 'after_max', 'improvement',
'interpolation_rms' (the same grid holding the noise-free truth), 'uncertainty_rms' (the map's
interpolated uncertainty), 'predicted_rms' = sqrt(interpolation² + uncertainty²)}, each residual
set with its own least-squares rigid-body motion removed.)doc");
}

}  // namespace trueaxis::python
