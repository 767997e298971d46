// Python bindings for the least-squares fits of geometric elements (ISO 10360-6; Shakarji 1998).
#include "trueaxis/geometry/fit.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/geometry/points.hpp"

namespace py = pybind11;

namespace trueaxis::python {

void bind_fit(py::module_& m) {
  m.def(
      "fit",
      [](const std::string& element,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& points, bool zone,
         std::optional<double> point_u) {
        if (points.ndim() != 2 || points.shape(1) != 3)
          throw Error("points must have shape (n, 3) (mm)");
        const Eigen::Matrix3Xd p =
            Eigen::Map<const Eigen::Matrix3Xd>(points.data(), 3, points.shape(0));
        const auto e = geometry::element_from_string(element);
        geometry::Fit f;
        {
          py::gil_scoped_release release;
          f = zone ? geometry::fit_min_zone(e, p) : geometry::fit(e, p);
        }
        py::dict d;
        d["element"] = element;
        // The same words as fit.json: center (circle, sphere) or point; normal (plane, circle)
        // or direction (line, cylinder, cone); a sphere has neither.
        const bool centre = e == geometry::Element::Circle || e == geometry::Element::Sphere;
        const bool normal = e == geometry::Element::Plane || e == geometry::Element::Circle;
        const char* where = centre ? "center" : "point";
        const char* axis = normal ? "normal" : "direction";
        d[where] = Eigen::Vector3d(f.point);
        if (e != geometry::Element::Sphere) d[axis] = Eigen::Vector3d(f.direction);
        if (f.diameter > 0) d["diameter"] = f.diameter;
        if (e == geometry::Element::Cone) {
          d["distance"] = f.distance;
          d["apex_angle_deg"] = f.apex_angle * 180 / M_PI;
        }
        if (zone) d["zone"] = f.zone;
        const geometry::Form form = geometry::form_of(f, point_u ? *point_u * 1e-3 : NAN);
        d["form"] = py::dict(py::arg("name") = form.name, py::arg("reference") = form.reference,
                             py::arg("value_um") = form.value * 1e3,
                             py::arg("U_um") = form.U ? py::object(py::float_(*form.U * 1e3))
                                                      : py::object(py::none()),
                             py::arg("resolved") = form.U ? py::object(py::bool_(*form.resolved()))
                                                          : py::object(py::none()),
                             py::arg("no_uncertainty") = form.no_uncertainty,
                             py::arg("summary") = form.summary());
        savable(d, [f, form](const std::string& path) { io::write_fit(path, f, form); });
        // Moved into the array (no copy of n doubles).
        d["residuals"] = py::cast(std::move(f.residuals), py::return_value_policy::move);
        if (f.has_uncertainty) {
          py::dict u;
          u[where] = Eigen::Vector3d(f.u_point);
          if (e != geometry::Element::Sphere) u[axis] = Eigen::Vector3d(f.u_direction);
          if (f.diameter > 0) u["diameter"] = f.u_diameter;
          if (f.element == geometry::Element::Cone) {
            u["distance"] = f.u_distance;
            u["apex_angle_deg"] = f.u_apex_angle * 180 / M_PI;
          }
          d["uncertainty"] = u;
        }
        d["condition_number"] = f.condition_number;
        d["warnings"] = f.warnings;
        d["rms"] = f.rms;
        d["max"] = f.max;
        return d;
      },
      py::arg("element"), py::arg("points"), py::kw_only(), py::arg("zone") = false,
      py::arg("point_u") = py::none(),
      R"doc(Least-squares fit of 'line', 'plane', 'circle', 'sphere', 'cylinder' or 'cone' to points
of shape (n, 3) (mm), as NIST reports it: 'point' (centre, or a point on the line, plane or
axis), 'direction' (unit: line or axis direction, or normal), 'diameter' (circle, sphere,
cylinder), 'distance' and 'apex_angle_deg' (cone), 'residuals' (signed orthogonal distances),
'rms', 'max'. zone=True (line, plane, circle): the minimum-zone (Chebyshev) fit instead, with
its width as 'zone'. 'form': the element's form (straightness, flatness, roundness, ...) as
{'name', 'reference', 'value_um', 'U_um' (95 %), 'resolved', 'no_uncertainty', 'summary'}; U needs
point_u, the points' standard uncertainty along the normal (µm), since residuals alone cannot tell
form from noise. Raises trueaxis.Error for degenerate sets.)doc");
}

}  // namespace trueaxis::python
