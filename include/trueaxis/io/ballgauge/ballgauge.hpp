// trueaxis::io — ball-gauge files (gauge.json, placements, lengths).
//
// gauge.json: {"ball_diameter": mm, "balls": [[u, v, w], ...]} (gauge frame, mm), or for a ball
//   plate {"ball_diameter": mm, "plate": {"rows": n, "columns": m, "pitch": mm | [along a row,
//   between rows]}} (balls numbered row by row from 0); optional "frame": [origin, axis, plane],
//   the three balls of the 3-2-1 frame (default: Gauge::frame_balls, e.g. 0, 4, 20 on a 5 × 5
//   plate).
// measurements.json: {"placements": [{"name": str, "alignment": "321" | "ls" | "stitch",
//   "tip_radius": mm, "balls": [{"index": i, "points": [[x, y, z], ...]}, ...]}, ...]}
//   (probed stylus-tip centres, mm, machine frame; index into gauge.json, 0-based). A ball the
//   CMM's software already fitted: {"index": i, "centre": [x, y, z]} (mm; "center" too), with
//   "u_um": [ux, uy, uz] its standard uncertainty when known. Each "321" or "ls" placement starts
//   a frame of its own; "stitch" joins the last one.
// map.json: {"points": [{"placement", "ball", "nominal": [mm], "measured": [mm], "error": [µm],
//   "uncertainty": [µm]}], "placements": [...], "grid": {...} (as in space.json, when the points
//   form a lattice)}. `trueaxis correct` reads its grid.
// lengths.csv: columns x1,y1,z1,x2,y2,z2 (measured end points, mm) and nominal (mm); other
//   columns are ignored. One calibrated length per row (gauge-block verification).
// verify.json: per correction (grid, parametric), every length's errors before and after (µm),
//   their statistics, the repeatability and the expected level after correction.
// model.json (parametric model): a machine.json (io/machine.hpp: usable by every machine command)
//   plus "identification": degree, basis centre and half span (mm), the Chebyshev parameters
//   (mm, rad), their covariance, residual and sigma (µm).
// balls.csv: columns x,y,z (a ball's true centre, mm, machine coordinates) and diameter (mm):
//   where a gauge's balls stand in the machine (`trueaxis serve --balls`).
// Errors name file:line:col.
#pragma once

#include <string>
#include <vector>

#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/ballgauge/parametric.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::io {

ballgauge::Gauge read_gauge(const std::string& path);
void write_gauge(const std::string& path, const ballgauge::Gauge& gauge);

// With `gauge`, ball indices outside it and balls measured twice in one placement are refused
// here, at their file:line:col (calibrate() refuses them too, without a location).
std::vector<ballgauge::Placement> read_measurements(const std::string& path,
                                                    const ballgauge::Gauge* gauge = nullptr);
void write_measurements(const std::string& path,
                        const std::vector<ballgauge::Placement>& placements);

void write_ballgauge_map(const std::string& path, const ballgauge::Result& result);

// Refuses non-positive nominals and coincident end points at their file:line:col.
std::vector<ballgauge::LengthMeasurement> read_lengths(const std::string& path);
void write_lengths(const std::string& path,
                   const std::vector<ballgauge::LengthMeasurement>& lengths);
void write_length_verification(const std::string& path,
                               const std::vector<ballgauge::LengthVerification>& results,
                               const ballgauge::Mpe* mpe = nullptr);

// Refuses an empty file and non-positive diameters at their file:line:col.
std::vector<sim::Ball> read_balls(const std::string& path);
void write_balls(const std::string& path, const std::vector<sim::Ball>& balls);

void write_parametric(const std::string& path, const ballgauge::ParametricResult& result);
ballgauge::ParametricResult read_parametric(const std::string& path);

}  // namespace trueaxis::io
