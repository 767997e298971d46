// trueaxis::io — the circular test's files: the ballbar trace and the result.
//
// trace.csv: a header naming the columns `direction`, `angle_deg`, `deviation_um` (any order;
// a unit may be written in a name as elsewhere: `deviation (nm)`), then one sample per line:
// `ccw` or `cw`; the commanded angle from the plane's first axis towards its second (degrees,
// any real value); the ballbar's reading less its calibrated length. `#` lines are comments;
// spreadsheets' dialects (';', decimal commas, "sep=;") are read as plain CSV. Bad fields are
// refused with file:line:col.
//
// circular.json (`"kind": "circular"`): the plane, radius and feed, `G_um` and `F_um` per
// direction, `H_um`, the diagnosis (one {"value", "u"} per cause, grouped as the causes' keys
// are, µm, µm/m or ms; `"separated": false` and `"not_separated_from"` where the data cannot
// tell causes apart, with a null value), the unexplained RMS, and the trace with its fitted
// model.
#pragma once

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "trueaxis/circular/circular.hpp"
#include "trueaxis/sim/circular.hpp"

namespace trueaxis::io {

// A raw time series instead: a header `t_s`, `deviation_um` (a unit in a name as above), one
// sample per line in time order, the runs one after another. A new run starts where the time goes
// back or jumps by more than five median sample intervals; run i runs in order[i], its first
// sample at `start_angle`, its angle then moving at ω = feed / radius. Refused with file:line:col:
// more runs than the order names, a run going more than two turns (a wrong feed or radius).
struct TimeSeriesOptions {
  double feed = std::numeric_limits<double>::quiet_NaN();    // mm/min
  double radius = std::numeric_limits<double>::quiet_NaN();  // mm
  double start_angle = 0;                                    // rad
  std::vector<circular::Direction> order{circular::Direction::Ccw, circular::Direction::Cw};
  void validate() const;  // throws Error
  // "ccw,cw", "cw,ccw", "ccw" or "cw" (any case); throws Error for anything else.
  static std::vector<circular::Direction> order_of(const std::string& text);
};

// `series`: how to read a time series (without it one is refused, saying what to give).
circular::Trace read_trace(const std::string& path, const TimeSeriesOptions* series = nullptr);
circular::Trace parse_trace(std::string text, const std::string& path,
                            const TimeSeriesOptions* series = nullptr);
void write_trace(const std::string& path, const circular::Trace& trace);

// servo.json: per machine axis ("X", "Y", "Z"; any may be left out) {"gain_per_s",
// "backlash_um", "spike_um", "spike_decay_deg", "cyclic_um", "pitch_mm"} (each optional).
std::array<sim::ServoAxis, 3> read_servo(const std::string& path);

// The truth of a simulated test as JSON, in the result's units and names.
void write_circular_truth(const std::string& path, const sim::CircularTruth& truth,
                          const circular::Plane& plane);

// With `trace` (the one evaluated), its samples and the fitted model are written too.
void write_circular_result(const std::string& path, const circular::Result& result,
                           const circular::Trace* trace = nullptr);

// A result file read back: the result, and the trace when the file holds it (else empty).
// Throws Error (file:line:col) for a file that is not one.
struct CircularFile {
  circular::Result result;
  circular::Trace trace;
};
CircularFile read_circular_result(const std::string& path);

}  // namespace trueaxis::io
