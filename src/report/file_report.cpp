// The report of any result file, by its kind (files.hpp).
#include <fmt/format.h>

#include <filesystem>
#include <type_traits>

#include "trueaxis/error.hpp"
#include "trueaxis/io/result_file.hpp"
#include "trueaxis/report/acceptance.hpp"
#include "trueaxis/report/ballgauge.hpp"
#include "trueaxis/report/circular.hpp"
#include "trueaxis/report/files.hpp"
#include "trueaxis/report/fit.hpp"
#include "trueaxis/report/guideway.hpp"
#include "trueaxis/report/positioning.hpp"
#include "trueaxis/report/scan.hpp"
#include "trueaxis/report/surface.hpp"

namespace trueaxis::report {

FileReport file_report(const std::string& path) {
  io::ResultFile file = io::read_result_file(path);
  FileReport r;
  r.kind = file.kind;
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, separation::Result>) {
          r.title = "trueaxis straightness report";
          r.section = separation_section("Straightness of a workpiece and its guide", v);
        } else if constexpr (std::is_same_v<T, surface::Result>) {
          r.title = "trueaxis surface report";
          r.section = surface_section("Flatness of a surface", v);
        } else if constexpr (std::is_same_v<T, io::SpaceFile>) {
          r.title = "trueaxis error space report";
          r.section = space_section("Error space of a machine", v.space,
                                    v.verification ? &*v.verification : nullptr);
        } else if constexpr (std::is_same_v<T, guideway::Result>) {
          r.title = "trueaxis guideway report";
          r.section = guideway_section("Five motion errors of a guideway", v);
        } else if constexpr (std::is_same_v<T, io::PositioningFile>) {
          r.title = "trueaxis positioning report";
          r.section = positioning_section("Positioning accuracy of a linear axis", v.result,
                                          v.standard, v.verdicts);
        } else if constexpr (std::is_same_v<T, ballgauge::Result>) {
          r.title = "trueaxis ball-gauge map";
          r.section = ballgauge_section("CMM error map from ball-gauge placements", v);
        } else if constexpr (std::is_same_v<T, ballgauge::ParametricResult>) {
          throw Error(fmt::format(
              "{}: a parametric model is drawn with its map: 'trueaxis ballgauge --parametric "
              "model.json --report map.html'",
              path));
        } else if constexpr (std::is_same_v<T, std::vector<ballgauge::LengthVerification>>) {
          r.title = "trueaxis length verification";
          r.section = lengths_section("Gauge-block verification (ISO 10360-2 positions)", v);
        } else if constexpr (std::is_same_v<T, geometry::Fit>) {
          r.title = "trueaxis fit report";
          r.section = fit_section("Fit of a geometric element", v);
        } else if constexpr (std::is_same_v<T, io::CircularFile>) {
          if (v.trace.angle.size() == 0)
            throw Error(fmt::format("{}: the file holds no trace to draw", path));
          r.title = "trueaxis circular test report";
          r.section = circular_section(
              fmt::format("Circular test in {} (ISO 230-4)", v.result.plane.name()), v.result,
              v.trace);
        } else if constexpr (std::is_same_v<T, acceptance::E0Result>) {
          r.title = "trueaxis CMM acceptance: length measuring error";
          r.section = e0_section("Length measuring error (ISO 10360-2)", v);
        } else if constexpr (std::is_same_v<T, acceptance::ProbingResult>) {
          r.title = "trueaxis CMM acceptance: probing errors";
          r.section = probing_section("Probing errors on the reference sphere (ISO 10360-5)", v);
        } else {
          static_assert(std::is_same_v<T, io::ScanFile>);
          r.title = "trueaxis scanning report";
          r.section =
              scan_section("Error-tolerant scanning", v.result, v.result.planned, v.tolerance);
        }
      },
      file.result);
  std::string p = path;
  while (p.size() > 1 && p.back() == '/') p.pop_back();
  r.section.source = std::filesystem::path(p).filename().string();
  return r;
}

}  // namespace trueaxis::report
