// trueaxis::io — writing whole files.
#pragma once

#include <string>
#include <string_view>

namespace trueaxis::io {

// Writes `text` to `path` atomically: into a temporary file beside it, then renamed into place,
// so that a failed or interrupted write leaves any earlier file as it was. "-" is standard
// output. Throws Error naming the path (a missing folder, no permission, a full disk).
void write_text(const std::string& path, std::string_view text);

}  // namespace trueaxis::io
