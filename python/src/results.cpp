// Python bindings: reading back any result file the command line writes (trueaxis.load), and
// its HTML report (trueaxis.report).
#include <pybind11/stl.h>

#include <optional>

#include "bindings.hpp"
#include "trueaxis/io/result_file.hpp"
#include "trueaxis/report/files.hpp"
#include "trueaxis/report/html.hpp"

namespace py = pybind11;

namespace trueaxis::python {

void bind_results(py::module_& m) {
  // The reader of the file's kind checks the whole file, as `trueaxis report` would.
  m.def(
      "_load", [](const std::string& path) { return io::read_result_file(path).kind; },
      py::arg("path"));
  m.def(
      "_report",
      [](const std::string& path, const std::string& output, const report::Meta& meta,
         const std::optional<std::string>& source, const std::optional<std::string>& title) {
        report::FileReport r = report::file_report(path);
        if (source) r.section.source = *source;
        report::write(output, report::render(title ? *title : r.title, {r.section}, 4000, meta));
        return r.kind;
      },
      py::arg("path"), py::arg("output"), py::arg("meta"), py::arg("source"), py::arg("title"));
}

}  // namespace trueaxis::python
