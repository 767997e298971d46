// Moody's 1955 surface-plate data (the eight Union Jack line files and Config.txt), embedded in
// the CLI so that `trueaxis demo` can write them out and assemble them like a user would.
#pragma once

#include <string_view>
#include <utility>
#include <vector>

namespace trueaxis::cli {
// (file name, contents) pairs.
const std::vector<std::pair<std::string_view, std::string_view>>& moody_files();
// The README's example inputs (examples/): (file name, contents) pairs.
const std::vector<std::pair<std::string_view, std::string_view>>& example_files();
}  // namespace trueaxis::cli
