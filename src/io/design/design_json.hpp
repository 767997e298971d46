// design.json's object inside other files (part.json, scan.json): its writer and its reader at a
// place in a file, with the same checks and the same file:line:col messages as design.json.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "trueaxis/design/design.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::io::detail {

// The solid's STEP path is written relative to `folder` when the file lies there or below.
nlohmann::ordered_json design_object(const design::Design& d, const std::filesystem::path& folder);
design::Design design_object_at(const JsonFile& f, const JsonFile::pointer& at);

}  // namespace trueaxis::io::detail
