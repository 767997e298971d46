// Python bindings for the ball-gauge error map (spec 04): calibrate from gauge.json and
// measurements.json (or their contents), and correct points with the resulting grid.
#include "trueaxis/ballgauge/ballgauge.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/ballgauge.hpp"

namespace py = pybind11;

namespace trueaxis::python {

void bind_ballgauge(py::module_& m) {
  m.def(
      "ballgauge",
      [](const std::string& gauge, const std::string& measurements, double match_tolerance,
         long min_points) {
        const auto g = io::read_gauge(gauge);
        const auto p = io::read_measurements(measurements, &g);
        ballgauge::Options o;
        o.match_tolerance = match_tolerance;
        o.min_points = min_points;
        ballgauge::Result r;
        try {
          py::gil_scoped_release release;
          r = ballgauge::calibrate(g, p, o);
        } catch (const Error& e) {
          throw Error(fmt::format("{}: {}", measurements, e.what()));
        }
        const auto n = static_cast<Eigen::Index>(r.points.size());
        Eigen::MatrixXd nominal(n, 3), measured(n, 3), error(n, 3), u(n, 3);
        std::vector<std::string> placement;
        std::vector<int> ball;
        for (Eigen::Index i = 0; i < n; ++i) {
          const auto& q = r.points[static_cast<std::size_t>(i)];
          nominal.row(i) = q.nominal.transpose();
          measured.row(i) = q.measured.transpose();
          error.row(i) = q.error.transpose() * 1e3;
          u.row(i) = q.uncertainty.transpose() * 1e3;
          placement.push_back(q.placement);
          ball.push_back(q.ball);
        }
        py::dict d;
        d["nominal"] = nominal;
        d["measured"] = measured;
        d["error"] = error;
        d["uncertainty"] = u;
        d["placement"] = placement;
        d["ball"] = ball;
        d["map"] = r.grid ? py::cast(*r.grid) : py::object(py::none());
        d["summary"] = r.summary();
        return d;
      },
      py::arg("gauge"), py::arg("measurements"), py::kw_only(), py::arg("match_tolerance") = 1.0,
      py::arg("min_points") = 5,
      R"doc(CMM error-vector map from ball-gauge placements (spec 04).

gauge, measurements: paths of gauge.json and measurements.json. Returns {'nominal', 'measured'
(mm), 'error' (measured − true), 'uncertainty' (µm): arrays (points, 3); 'placement', 'ball';
'map': an ErrorMap when the points form a lattice (use map.correct(points) for X = x − Δ(x)),
else None; 'summary'}.)doc");
}

}  // namespace trueaxis::python
