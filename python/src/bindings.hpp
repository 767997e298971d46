// Python bindings, shared declarations. Units follow trueaxis' files: positions in mm,
// deviations in µm, angles in µrad. Every trueaxis::Error becomes trueaxis.Error (module.cpp).
#pragma once

#include <pybind11/functional.h>
#include <pybind11/pybind11.h>

#include <string>

namespace trueaxis::python {

// A result dict that trueaxis.save() can write as the file the command line writes for it:
// `write(path)` is kept under "__save__", which the Python package takes out of the dict it hands
// to the user (trueaxis.Result). `write` holds copies of what it writes.
template <class Write>
void savable(pybind11::dict& d, Write write) {
  d["__save__"] = pybind11::cpp_function([write](const std::string& path) { write(path); });
}

// trueaxis._load(path): any result file the command line writes, checked by the reader of its
// kind (file:line:col on a bad one); returns its kind.
void bind_results(pybind11::module_& m);
// trueaxis.export: controller compensation tables (export.cpp).
void bind_export(pybind11::module_& m);
// trueaxis.design, trueaxis.simulate_part: scanning inputs (design.cpp).
void bind_design(pybind11::module_& m);

// The virtual machine, error surfaces, error spaces and error maps (space.cpp).
void bind_space(pybind11::module_& m);
// The five guideway errors and the virtual carriage (guideway.cpp).
void bind_guideway(pybind11::module_& m);
// Least-squares fits of geometric elements (fit.cpp).
void bind_fit(pybind11::module_& m);
// The ball-gauge error map (ballgauge.cpp).
void bind_ballgauge(pybind11::module_& m);
// Error-tolerant scanning on the virtual CMM (scan.cpp).
void bind_scan(pybind11::module_& m);
// Positioning accuracy by ISO 230-2 / VDI 3441 and virtual laser runs (positioning.cpp).
void bind_positioning(pybind11::module_& m);
// Circular tests with a ballbar, ISO 230-4, and the virtual test (circular.cpp).
void bind_circular(pybind11::module_& m);
// CMM acceptance tests, ISO 10360-2 and -5, on the virtual CMM (acceptance.cpp).
void bind_acceptance(pybind11::module_& m);
// trueaxis.records (records.cpp).
void bind_records(pybind11::module_& m);

}  // namespace trueaxis::python
