// Python bindings for the five guideway errors and the virtual carriage. Readings in µm
// (spots) as numpy arrays of shape (positions, 2m): dx, dy per detector in layout order.
#include "trueaxis/guideway/guideway.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/guideway/guideway.hpp"
#include "trueaxis/sim/guideway.hpp"
#include "trueaxis/sim/machine.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

// A layout from a layout.json path or a list of dicts like its "detectors".
guideway::Layout layout_in(const py::object& o) {
  if (py::isinstance<py::str>(o)) return io::read_layout(py::cast<std::string>(o)).layout;
  guideway::Layout l;
  std::size_t i = 0;
  for (auto item : o) {
    const auto d = py::cast<py::dict>(item);
    const std::string where = fmt::format("layout[{}]", i++);
    guideway::Detector det;
    for (auto kv : d) {
      const std::string key = py::cast<std::string>(kv.first);
      if (key == "name") {
        det.name = py::cast<std::string>(kv.second);
      } else if (key == "kind") {
        const std::string k = py::cast<std::string>(kv.second);
        if (k != "position" && k != "angle")
          throw Error(fmt::format("{}: kind must be 'position' or 'angle', not '{}'", where, k));
        det.kind = k == "angle" ? guideway::Kind::Angle : guideway::Kind::Position;
      } else if (key == "position") {
        const auto p = py::cast<std::vector<double>>(kv.second);
        if (p.size() != 3) throw Error(where + ": position needs [x, y, z] (mm)");
        det.position = {p[0], p[1], p[2]};
      } else if (key == "focal_length") {
        det.focal_length = py::cast<double>(kv.second);
      } else {
        throw Error(
            fmt::format("{}: unknown key '{}' (name, kind, position, focal_length)", where, key));
      }
    }
    l.detectors.push_back(std::move(det));
  }
  l.validate();
  return l;
}

}  // namespace

void bind_guideway(py::module_& m) {
  m.def(
      "guideway",
      [](const py::object& layout, const Eigen::VectorXd& s, const Eigen::MatrixXd& readings,
         std::optional<double> sigma) {
        const guideway::Layout l = layout_in(layout);
        guideway::Options o;
        if (sigma) o.sigma = *sigma * 1e-3;
        guideway::Result r;
        {
          py::gil_scoped_release release;
          r = guideway::solve(l, s, readings * 1e-3, o);
        }
        py::dict d, obs, unc, sum;
        d["s"] = r.s;
        for (int j = 0; j < guideway::kErrors; ++j) {
          const auto k = static_cast<std::size_t>(j);
          const double sc = j < 2 ? 1e3 : 1e6;
          const bool have = r.value[k].size() > 0;
          d[guideway::kErrorNames[j]] = have
                                            ? py::object(py::cast(Eigen::VectorXd(r.value[k] * sc)))
                                            : py::object(py::none());
          obs[guideway::kErrorNames[j]] = r.layout.observable[k];
          unc[guideway::kErrorNames[j]] = have && r.sigma > 0
                                              ? py::object(py::float_(r.uncertainty[k] * sc))
                                              : py::object(py::none());
          const std::optional<double> U = r.pv_U(k);
          const std::optional<bool> resolved = r.resolved(k);
          sum[guideway::kErrorNames[j]] =
              have
                  ? py::object(py::dict(
                        py::arg("pv") = r.pv[k] * sc, py::arg("rms") = r.rms[k] * sc,
                        py::arg("U") = U ? py::object(py::float_(*U * sc)) : py::object(py::none()),
                        py::arg("resolved") =
                            resolved ? py::object(py::bool_(*resolved)) : py::object(py::none())))
                  : py::object(py::none());
        }
        d["residual"] = Eigen::VectorXd(r.residual * 1e3);
        d["straightness"] = py::dict(
            py::arg("horizontal") =
                r.horizontal_straightness.size()
                    ? py::object(py::cast(Eigen::VectorXd(r.horizontal_straightness * 1e3)))
                    : py::object(py::none()),
            py::arg("vertical") =
                r.vertical_straightness.size()
                    ? py::object(py::cast(Eigen::VectorXd(r.vertical_straightness * 1e3)))
                    : py::object(py::none()));
        d["observable"] = obs;
        d["uncertainty"] = unc;
        d["summary"] = sum;
        d["condition_number"] = r.layout.condition_number;
        d["observable_condition_number"] = r.layout.observable_condition_number;
        d["singular_values"] = r.layout.singular_values;
        d["sigma"] = r.sigma > 0 ? py::object(py::float_(r.sigma * 1e3)) : py::object(py::none());
        d["no_uncertainty"] = r.no_uncertainty.empty() ? py::object(py::none())
                                                       : py::object(py::str(r.no_uncertainty));
        d["sigma_estimated"] = r.sigma_estimated;
        d["message"] = r.layout.message;
        d["report"] = r.summary();
        savable(d, [r](const std::string& path) { io::write_guideway_result(path, r); });
        return d;
      },
      py::arg("layout"), py::arg("s"), py::arg("readings"), py::kw_only(),
      py::arg("sigma") = py::none(),
      R"doc(Five motion errors of a guideway from laser spots on quadrant detectors.

layout: a layout.json path or a list of dicts {'name', 'kind': 'position' | 'angle', 'position':
[x, y, z] (mm; z along the travel, x horizontal, y vertical), 'focal_length' (mm, angle)}; s:
carriage positions (mm); readings: (len(s), 2 × detectors) spot displacements dx, dy in µm in
layout order; sigma: reading noise in µm (default: estimated when the layout is redundant).

Returns {'horizontal', 'vertical' (µm), 'pitch', 'yaw', 'roll' (µrad): arrays, or None when the
layout cannot observe them; 'observable', 'uncertainty', 'summary' ({'pv', 'rms'}),
'straightness' (against the LS line), 'residual', 'condition_number', 'message', 'report'}.)doc");

  m.def(
      "simulate_guideway",
      [](const sim::Machine& machine, const py::object& layout, const std::string& axis,
         long positions, double noise, double pointing_noise, double angle_noise,
         double quantisation, bool exact, std::uint64_t seed) {
        sim::GuidewayOptions o;
        if (axis != "x" && axis != "y" && axis != "z")
          throw Error(fmt::format("axis must be 'x', 'y' or 'z', not '{}'", axis));
        o.axis = axis == "x" ? 0 : axis == "y" ? 1 : 2;
        o.positions = positions;
        o.noise = noise * 1e-3;
        o.pointing_noise = pointing_noise * 1e-3;
        o.angle_noise = angle_noise * 1e-6;
        o.quantisation = quantisation * 1e-3;
        o.exact = exact;
        o.seed = seed;
        const auto c = sim::simulate_guideway(machine, layout_in(layout), o);
        py::dict d, t;
        d["s"] = c.s;
        d["readings"] = Eigen::MatrixXd(c.spots * 1e3);
        for (int j = 0; j < guideway::kErrors; ++j)
          t[guideway::kErrorNames[j]] =
              Eigen::VectorXd(c.truth[static_cast<std::size_t>(j)] * (j < 2 ? 1e3 : 1e6));
        d["truth"] = t;
        return d;
      },
      py::arg("machine"), py::arg("layout"), py::kw_only(), py::arg("axis") = "x",
      py::arg("positions") = 201, py::arg("noise") = 0.0, py::arg("pointing_noise") = 0.0,
      py::arg("angle_noise") = 0.0, py::arg("quantisation") = 0.0, py::arg("exact") = false,
      py::arg("seed") = 1,
      "Virtual guideway carriage on one axis of a Machine: returns {'s', 'readings' (µm, "
      "positions × 2m), 'truth': {'horizontal', 'vertical' (µm), 'pitch', 'yaw', 'roll' "
      "(µrad)}}. noise, pointing_noise, quantisation in µm; angle_noise in µrad.");
}

}  // namespace trueaxis::python
