// trueaxis::io — linear positioning runs in Renishaw's .rtl text file, as written by Renishaw's
// laser calibration software (Laser10, LaserXL) and read by controller and compensation tools.
//
// Layout (plain text, CR LF or LF). Sections start with a line "NAME::"; inside them, lines
// "Key : value" (the spaces around ':' are optional):
//   HEADER::       File type, Owner, Version no
//   TARGET DATA::  Filetype (the kind of test; angular and other non-linear tests are refused),
//                  Target-count : m, "Targets :" followed by the m target positions (mm),
//                  several to a line, then other keys (Flags : ...)
//   USER-TEXT::    free text: Machine, Serial No, Date, Axis, ...
//   RUNS::         Run-count : r
//   DEVIATIONS::   "Run Target Data:" followed by one line per reading: run number (1..r),
//                  target number (1..m, in the order of the Targets list), deviation (µm,
//                  actual − target, as the laser software recorded it: its environmental
//                  compensation applied)
// Other sections (equipment, environment) are kept as text and not interpreted. Sources: the
// section and key names above as read by two independent public readers of .rtl files (a
// machine-controller parameter dialog that averages runs 1, 3, … and 2, 4, … per target, and a
// compensation-table viewer); their layouts agree.
//
// Direction of each run. A run is one pass over the targets in one direction. The file does not
// say which; by default (RunDirections::FromOrder) it is read from the order in which the run
// lists its targets (the order the laser took them): increasing positions are a '+' run,
// decreasing a '-' run. A run that lists its targets in no monotonic order, or a file in which
// every run lists them increasing (a one-direction test, or a file sorted by target), is
// reported; the caller may then say how the runs alternate. The k-th run in a direction is
// cycle k of that direction.
#pragma once

#include <string>
#include <vector>

#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/positioning/positioning.hpp"

namespace trueaxis::io {

enum class RunDirections {
  FromOrder,  // from the order each run lists its targets (default)
  UpDown,     // odd runs '+', even runs '-'
  DownUp,     // odd runs '-', even runs '+'
  AllUp,      // every run '+'
  AllDown     // every run '-'
};

struct RtlOptions {
  RunDirections directions = RunDirections::FromOrder;
};

struct RtlFile {
  PositioningRuns runs;         // readings (mm) with their 1-based lines
  std::vector<double> targets;  // mm, in the file's order
  int run_count = 0;
  std::vector<std::string> warnings;  // what was assumed, in words for the user
  std::vector<std::pair<std::string, std::string>> fields;  // every "Key : value" outside data
};

// Throws Error "path:line:col: why" for what cannot be read (see the layout above).
RtlFile parse_rtl(std::string text, const std::string& path, const RtlOptions& options = {});
RtlFile read_rtl(const std::string& path, const RtlOptions& options = {});

// True when `text` starts (after blank lines) with a "NAME::" section line.
bool looks_like_rtl(const std::string& text);
// True when `path` is named *.rtl (any case).
bool has_rtl_name(const std::string& path);
// True when the file at `path` has such a name or its text looks like an .rtl file.
bool is_rtl_file(const std::string& path);

// "order", "+-", "-+", "+" or "-" (as the CLI and Python take it). Throws Error otherwise.
RunDirections run_directions_from(const std::string& name);

// Writes readings as an .rtl file: the runs in time order of the ISO 230-2 test cycle (cycle c
// in '+' is run 2c − 1, listing its targets increasing; in '-' run 2c, listing them decreasing;
// one-direction data: one run per cycle). `fields` go into USER-TEXT (e.g. {"Axis", "X"}).
// Temperatures are not written: give deviations already corrected to 20 °C, as the laser
// software records them.
void write_rtl(const std::string& path, const std::vector<positioning::Reading>& readings,
               const std::vector<std::pair<std::string, std::string>>& fields = {});

}  // namespace trueaxis::io
