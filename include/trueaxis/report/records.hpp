// trueaxis::report — a machine's history of one figure: every calibration's value on its date
// (as found and as left marked apart), the fitted drift with its ±2u band, the limit, and the
// date the trend reaches it.
#pragma once

#include <optional>
#include <string>

#include "trueaxis/records/records.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::report {

// `trend` as records::Database::trend gives it; `tolerance` the limit it was fitted against
// (drawn as a line), in the figure's unit.
Section trend_section(const records::Trend& trend, const std::string& machine,
                      std::optional<double> tolerance);

}  // namespace trueaxis::report
