// Python bindings: reading back any result file the command line writes (trueaxis.load).
#include "trueaxis/io/results.hpp"

#include <fmt/format.h>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/scan/scan.hpp"
#include "trueaxis/io/separation/probes.hpp"
#include "trueaxis/io/surface/surface.hpp"

namespace py = pybind11;

namespace trueaxis::python {

void bind_results(py::module_& m) {
  m.def(
      "_load",
      [](const std::string& path) {
        const std::string kind = io::read_kind(path);
        // The reader of the kind checks the whole file, as `trueaxis report` would.
        if (kind == "separation")
          (void)io::read_result(path);
        else if (kind == "surface")
          (void)io::read_surface(path);
        else if (kind == "space")
          (void)io::read_space(path);
        else if (kind == "guideway")
          (void)io::read_guideway_result(path);
        else if (kind == "positioning")
          (void)io::read_positioning_result(path);
        else if (kind == "ballgauge map")
          (void)io::read_ballgauge_map(path);
        else if (kind == "parametric model")
          (void)io::read_parametric(path);
        else if (kind == "length verification")
          (void)io::read_length_verification(path);
        else if (kind == "fit")
          (void)io::read_fit(path);
        else if (kind == "scan")
          (void)io::read_scan(path);
        else
          throw Error(fmt::format("{}: a '{}' file is not a result trueaxis writes", path, kind));
        return kind;
      },
      py::arg("path"));
}

}  // namespace trueaxis::python
