#include <fmt/format.h>

#include <cmath>

#include "grid_json.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/ballgauge.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::io {
namespace {

using ptr = JsonFile::pointer;
using ojson = nlohmann::ordered_json;

Eigen::Vector3d triple(const JsonFile& f, const ptr& p) {
  const Eigen::VectorXd v = f.numbers(p);
  if (v.size() != 3) f.fail(p, fmt::format("'{}' needs [x, y, z] (mm)", dotted(p)));
  return v;
}

const char* alignment_name(ballgauge::Alignment a) {
  return a == ballgauge::Alignment::ThreeTwoOne    ? "321"
         : a == ballgauge::Alignment::LeastSquares ? "ls"
                                                   : "stitch";
}

ojson vec(const Eigen::Vector3d& v, double scale = 1.0) {
  return {v.x() * scale, v.y() * scale, v.z() * scale};
}

}  // namespace

ballgauge::Gauge read_gauge(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  ballgauge::Gauge g;
  for (const auto& [key, value] : f.object(ptr()).items())
    if (key != "ball_diameter" && key != "balls")
      f.fail(ptr() / key, fmt::format("unknown key '{}' (ball_diameter, balls)", key));
  if (!f.has(ptr() / "ball_diameter")) f.fail(ptr(), "'ball_diameter' is missing");
  g.ball_diameter = f.number(ptr() / "ball_diameter");
  if (!(g.ball_diameter > 0)) f.fail(ptr() / "ball_diameter", "ball_diameter must be > 0 (mm)");
  if (!f.has(ptr() / "balls")) f.fail(ptr(), "'balls' is missing");
  const auto& balls = f.array(ptr() / "balls");
  for (std::size_t i = 0; i < balls.size(); ++i) g.balls.push_back(triple(f, ptr() / "balls" / i));
  try {
    g.validate();
  } catch (const Error& e) {
    f.fail(ptr() / "balls", e.what());
  }
  return g;
}

void write_gauge(const std::string& path, const ballgauge::Gauge& g) {
  ojson balls = ojson::array();
  for (const auto& b : g.balls) balls.push_back(vec(b));
  write_json(path, ojson{{"ball_diameter", g.ball_diameter}, {"balls", balls}});
}

std::vector<ballgauge::Placement> read_measurements(const std::string& path,
                                                    const ballgauge::Gauge* gauge) {
  const JsonFile f = JsonFile::read(path);
  for (const auto& [key, value] : f.object(ptr()).items())
    if (key != "placements") f.fail(ptr() / key, fmt::format("unknown key '{}' (placements)", key));
  if (!f.has(ptr() / "placements")) f.fail(ptr(), "'placements' is missing");
  const ptr pl = ptr() / "placements";
  std::vector<ballgauge::Placement> out;
  const auto& arr = f.array(pl);
  if (arr.empty()) f.fail(pl, "no placements");
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const ptr p = pl / i;
    ballgauge::Placement P;
    for (const auto& [key, value] : f.object(p).items()) {
      const ptr k = p / key;
      if (key == "name") {
        P.name = f.string(k);
      } else if (key == "alignment") {
        const std::string a = f.string(k);
        if (a == "321")
          P.alignment = ballgauge::Alignment::ThreeTwoOne;
        else if (a == "ls")
          P.alignment = ballgauge::Alignment::LeastSquares;
        else if (a == "stitch")
          P.alignment = ballgauge::Alignment::Stitch;
        else
          f.fail(k, fmt::format("alignment must be \"321\", \"ls\" or \"stitch\", not \"{}\"", a));
      } else if (key == "tip_radius") {
        P.tip_radius = f.number(k);
        if (P.tip_radius < 0) f.fail(k, "tip_radius must be >= 0 (mm)");
      } else if (key == "balls") {
        const auto& balls = f.array(k);
        for (std::size_t b = 0; b < balls.size(); ++b) {
          const ptr bp = k / b;
          ballgauge::BallPoints B;
          bool has_index = false;
          for (const auto& [bk, bv] : f.object(bp).items()) {
            if (bk == "index") {
              const double v = f.number(bp / bk);
              if (v < 0 || v != std::floor(v))
                f.fail(bp / bk, "index must be a whole number >= 0 (a ball of gauge.json)");
              B.index = static_cast<int>(v);
              has_index = true;
              if (gauge && B.index >= static_cast<int>(gauge->balls.size()))
                f.fail(bp / bk, fmt::format("ball index {} is not in the gauge (0..{})", B.index,
                                            gauge->balls.size() - 1));
              for (const auto& other : P.balls)
                if (gauge && other.index == B.index)
                  f.fail(bp / bk,
                         fmt::format("ball {} is measured twice in this placement", B.index));
            } else if (bk == "points") {
              const auto& pts = f.array(bp / bk);
              B.points.resize(3, static_cast<Eigen::Index>(pts.size()));
              for (std::size_t q = 0; q < pts.size(); ++q)
                B.points.col(static_cast<Eigen::Index>(q)) = triple(f, bp / bk / q);
            } else {
              f.fail(bp / bk, fmt::format("unknown key '{}' (index, points)", bk));
            }
          }
          if (!has_index) f.fail(bp, "ball without an 'index'");
          P.balls.push_back(std::move(B));
        }
      } else {
        f.fail(k, fmt::format("unknown key '{}' (name, alignment, tip_radius, balls)", key));
      }
    }
    if (P.name.empty()) P.name = fmt::format("placement {}", i);
    out.push_back(std::move(P));
  }
  return out;
}

void write_measurements(const std::string& path, const std::vector<ballgauge::Placement>& ps) {
  ojson arr = ojson::array();
  for (const auto& p : ps) {
    ojson balls = ojson::array();
    for (const auto& b : p.balls) {
      ojson pts = ojson::array();
      for (Eigen::Index q = 0; q < b.points.cols(); ++q) pts.push_back(vec(b.points.col(q)));
      balls.push_back({{"index", b.index}, {"points", pts}});
    }
    arr.push_back({{"name", p.name},
                   {"alignment", alignment_name(p.alignment)},
                   {"tip_radius", p.tip_radius},
                   {"balls", balls}});
  }
  write_json(path, ojson{{"placements", arr}});
}

void write_ballgauge_map(const std::string& path, const ballgauge::Result& r) {
  ojson pts = ojson::array();
  for (const auto& p : r.points)
    pts.push_back({{"placement", p.placement},
                   {"ball", p.ball},
                   {"nominal", vec(p.nominal)},
                   {"measured", vec(p.measured)},
                   {"error", vec(p.error, 1e3)},
                   {"uncertainty", vec(p.uncertainty, 1e3)}});
  ojson pl = ojson::array();
  for (const auto& p : r.placements)
    pl.push_back({{"name", p.name},
                  {"alignment", alignment_name(p.alignment)},
                  {"balls", p.balls},
                  {"shared", p.shared},
                  {"registration_rms_um", p.registration_rms * 1e3},
                  {"diameter_error_max_um", p.diameter_error_max * 1e3}});
  ojson j;
  j["frame"] =
      "machine coordinates (mm); error = measured - true ball centre (um); correct with X = x - "
      "error(x)";
  j["points"] = pts;
  j["placements"] = pl;
  if (r.grid) j["grid"] = detail::grid_json(*r.grid);
  write_json(path, j);
}

}  // namespace trueaxis::io
