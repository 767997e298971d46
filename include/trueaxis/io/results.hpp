// trueaxis::io — reading back the result files trueaxis writes, so that `trueaxis report FILE`
// can draw any of them. Every result JSON carries a "kind":
//   "separation" (separate), "surface" (surface), "space" (space), "guideway" (guideway),
//   "ballgauge map" (ballgauge), "length verification" (verify-lengths), "fit" (fit),
//   "parametric model" (ballgauge --parametric).
// Readers refuse malformed files with file:line:col like every other reader. Units as written
// (see each writer); values come back in library units (mm, rad).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/geometry/fit.hpp"
#include "trueaxis/guideway/guideway.hpp"
#include "trueaxis/surface/space.hpp"
#include "trueaxis/surface/surface.hpp"

namespace trueaxis::io {

// The file's "kind"; files from before kinds were written are recognised by their keys.
std::string read_kind(const std::string& path);

surface::Result read_surface(const std::string& path);
// The space and, if the file has one, its compensation check (summary figures only: the
// per-point residuals are not in space.json).
surface::SpaceResult read_space(const std::string& path,
                                std::optional<surface::Verification>* verification = nullptr);
guideway::Result read_guideway_result(const std::string& path);
ballgauge::Result read_ballgauge_map(const std::string& path);
std::vector<ballgauge::LengthVerification> read_length_verification(const std::string& path);
geometry::Fit read_fit(const std::string& path);

}  // namespace trueaxis::io
