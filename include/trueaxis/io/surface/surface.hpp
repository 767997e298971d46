// trueaxis::io — surface inputs (Moody's files, lines.json) and surface.json output.
#pragma once

#include <string>
#include <vector>

#include "trueaxis/surface/surface.hpp"

namespace trueaxis::io {

// Moody's directory: the eight line files (one reading in arc-seconds per line; lines starting
// with '#' and blank lines are ignored) and Config.txt (first non-comment line "I <inches>" or
// "M <mm>": the foot spacing). Errors name file:line:col.
surface::MoodyData read_moody(const std::string& dir);

// lines.json: {"lines": [{"name", "start": [x, y] (mm), "direction": [dx, dy], "spacing": mm,
// and one of "heights": [um...], "slopes": [urad...] (one per foot; n slopes give n+1 stations)
// or "from": "result.json" (a 'trueaxis separate' result; "curve": "guide" (default) or
// "workpiece"; its spacing is taken from the result's x)}]}. Relative "from" paths are relative
// to the lines file. Errors name file:line:col.
std::vector<surface::Line> read_lines(const std::string& path);

// surface.json (µm for heights, mm for positions); see README.
void write_surface(const std::string& path, const surface::Result& r);

}  // namespace trueaxis::io
