// trueaxis::report — sections for error surfaces and error spaces (Moody 1955; ISO 230-1).
#pragma once

#include <string>

#include "trueaxis/report/html.hpp"
#include "trueaxis/surface/space.hpp"
#include "trueaxis/surface/surface.hpp"

namespace trueaxis::report {

// A surface: flatness, closure and what the layout could not determine (table); a heat map of the
// heights at every station with the measured lines drawn (and the lattice cells when the layout
// fills one); for least-squares assemblies, the closure residual at every crossing. µm.
Section surface_section(const std::string& title, const surface::Result& result,
                        const std::string& intro_html = "");

// An error space: the campaign and its reference (table); distorted grids of three planes of the
// volume (in-plane errors magnified, the out-of-plane error as colour); the ez surfaces of up to
// six z levels on one colour scale; the uncertainty; and, with a verification, the positioning
// error at the random points before and after compensation as sorted curves against the
// predicted level.
Section space_section(const std::string& title, const surface::SpaceResult& space,
                      const surface::Verification* verification = nullptr);

}  // namespace trueaxis::report
