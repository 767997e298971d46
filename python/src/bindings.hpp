// Python bindings, shared declarations. Units follow trueaxis' files: positions in mm,
// deviations in µm, angles in µrad. Every trueaxis::Error becomes trueaxis.Error (module.cpp).
#pragma once

#include <pybind11/pybind11.h>

namespace trueaxis::python {

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

}  // namespace trueaxis::python
