// trueaxis::io — any result file trueaxis writes, read by the reader of its "kind": the one
// dispatch behind `trueaxis report FILE` and Python's trueaxis.load and trueaxis.report.
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/circular/circular.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/results.hpp"
#include "trueaxis/io/scan/scan.hpp"
#include "trueaxis/separation/separation.hpp"

namespace trueaxis::io {

// A space with its compensation check, when the file has one.
struct SpaceFile {
  surface::SpaceResult space;
  std::optional<surface::Verification> verification;
};

using AnyResult = std::variant<separation::Result, surface::Result, SpaceFile, guideway::Result,
                               PositioningFile, ballgauge::Result, ballgauge::ParametricResult,
                               std::vector<ballgauge::LengthVerification>, geometry::Fit, ScanFile,
                               CircularFile, acceptance::E0Result, acceptance::ProbingResult>;

struct ResultFile {
  std::string kind;  // as the file states it ("separation", "ballgauge map", ...)
  AnyResult result;
};

// Reads any result file. Throws Error: a file that is not JSON or not a result (naming the
// kinds there are), or one its kind's reader refuses (file:line:col).
ResultFile read_result_file(const std::string& path);

}  // namespace trueaxis::io
