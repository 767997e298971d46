// The headline figures of each kind of result file (records.hpp): the numbers a calibration
// history is followed by, read from the file's own JSON.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <nlohmann/json.hpp>

#include "trueaxis/error.hpp"
#include "trueaxis/records/records.hpp"

namespace trueaxis::records {
namespace {

using json = nlohmann::json;

// The number at `key` of `j`, when there is one (null or absent: none).
std::optional<double> number_at(const json& j, const char* key) {
  if (!j.is_object()) return std::nullopt;
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return std::nullopt;
  return it->get<double>();
}

void put(std::vector<Figure>& out, std::string name, std::string axis, std::optional<double> value,
         std::optional<double> u, std::string unit) {
  if (!value) return;  // not in the file: no figure, not a zero
  out.push_back({std::move(name), std::move(axis), *value, u, std::move(unit)});
}

// Straightness or flatness {"ls", "min_zone", "U_um", "resolved"}: the minimum zone with u = U/2.
void zone(std::vector<Figure>& out, const std::string& name, const std::string& axis,
          const json& j) {
  if (!j.is_object()) return;
  // Not resolved (the data cannot support it): no figure. Not stated (null): the figure, no u.
  if (const auto it = j.find("resolved"); it != j.end() && it->is_boolean() && !it->get<bool>())
    return;
  const auto U = number_at(j, "U_um");
  put(out, name, axis, number_at(j, "min_zone"), U ? std::optional<double>(*U / 2) : std::nullopt,
      "µm");
}

}  // namespace

std::vector<Figure> headline_figures(const std::string& kind, const std::string& text,
                                     const std::string& axis) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception&) {
    throw Error("not a JSON result file");
  }
  if (!j.is_object() || !j.contains("kind") || j["kind"] != kind)
    throw Error(fmt::format("not a '{}' result", kind));
  std::vector<Figure> out;
  // Machine axes by their upper-case letters, as on the machine.
  const std::string axis_name =
      axis.size() == 1
          ? std::string(1, static_cast<char>(std::toupper(static_cast<unsigned char>(axis[0]))))
          : axis;
  if (kind == "positioning") {
    // ISO 230-2: accuracy A, reversal value B, systematic deviation E, mean deviation range M,
    // repeatability R (µm); no uncertainty stated in the file.
    for (const char* k : {"A", "B", "E", "M", "R"})
      put(out, k, axis_name, number_at(j, k), {}, "µm");
  } else if (kind == "circular") {
    // ISO 230-4: circular deviation G per direction, hysteresis H.
    const std::string plane =
        j.contains("plane") && j["plane"].is_string() ? j["plane"].get<std::string>() : "";
    if (j.contains("G_um") && j["G_um"].is_object())
      for (const auto& [dir, v] : j["G_um"].items())
        if (v.is_number()) put(out, "G_" + dir, plane, v.get<double>(), {}, "µm");
    put(out, "H", plane, number_at(j, "H_um"), {}, "µm");
  } else if (kind == "acceptance-e0") {
    const std::string test =
        j.contains("test") && j["test"].is_string() ? j["test"].get<std::string>() : "E0";
    put(out, test, "", number_at(j, "E0_max_um"), {}, "µm");
    put(out, "R0", "", number_at(j, "R0_max_um"), {}, "µm");
  } else if (kind == "acceptance-probing") {
    const auto uf = number_at(j, "U_form_um"), us = number_at(j, "U_size_um");
    put(out, "PForm", "", number_at(j, "PForm_um"),
        uf ? std::optional<double>(*uf / 2) : std::nullopt, "µm");
    put(out, "PSize", "", number_at(j, "PSize_um"),
        us ? std::optional<double>(*us / 2) : std::nullopt, "µm");
  } else if (kind == "separation") {
    if (j.contains("straightness") && j["straightness"].is_object())
      for (const auto& [part, v] : j["straightness"].items())
        zone(out, "straightness_" + part, axis_name, v);
  } else if (kind == "guideway") {
    // Peak-to-valley of each error motion: straightness in µm, angles in µrad, u = U/2.
    if (j.contains("summary") && j["summary"].is_object())
      for (const auto& [motion, v] : j["summary"].items()) {
        if (!v.is_object()) continue;
        if (const auto it = v.find("resolved");
            it != v.end() && it->is_boolean() && !it->get<bool>())
          continue;
        const bool angle = motion == "pitch" || motion == "yaw" || motion == "roll";
        const auto U = number_at(v, "U");
        put(out, motion, axis_name, number_at(v, "pv"),
            U ? std::optional<double>(*U / 2) : std::nullopt, angle ? "µrad" : "µm");
      }
  } else if (kind == "surface") {
    if (j.contains("flatness")) zone(out, "flatness", "", j["flatness"]);
  } else if (kind == "space") {
    if (j.contains("verification") && j["verification"].is_object()) {
      const auto& v = j["verification"];
      put(out, "residual_max", "", number_at(v, "after_max"), {}, "µm");
      put(out, "residual_rms", "", number_at(v, "after_rms"), {}, "µm");
      put(out, "error_max", "", number_at(v, "before_max"), {}, "µm");
    }
  } else if (kind == "length verification") {
    if (j.contains("e0") && j["e0"].is_object() && j["e0"].contains("before"))
      put(out, "E_worst_fraction_of_mpe", "", number_at(j["e0"]["before"], "worst_fraction_of_mpe"),
          {}, "1");
  } else if (kind == "ballgauge map") {
    // The largest mapped error |(ex, ey, ez)| over the grid.
    if (j.contains("grid") && j["grid"].is_object()) {
      const auto& g = j["grid"];
      double worst = -1;
      if (g.contains("ex") && g.contains("ey") && g.contains("ez") && g["ex"].is_array() &&
          g["ey"].is_array() && g["ez"].is_array() && g["ex"].size() == g["ey"].size() &&
          g["ex"].size() == g["ez"].size())
        for (std::size_t i = 0; i < g["ex"].size(); ++i) {
          if (!g["ex"][i].is_number() || !g["ey"][i].is_number() || !g["ez"][i].is_number())
            continue;
          const double x = g["ex"][i].get<double>(), y = g["ey"][i].get<double>(),
                       z = g["ez"][i].get<double>();
          worst = std::max(worst, std::sqrt(x * x + y * y + z * z));
        }
      if (worst >= 0) put(out, "error_max", "", worst, {}, "µm");
    }
  } else if (kind == "fit") {
    // The form (mm in the file) by its name (cylindricity, roundness, ...), with U/2 when stated.
    if (j.contains("form") && j["form"].is_object()) {
      const auto& f = j["form"];
      const auto v = number_at(f, "value"), U = number_at(f, "U");
      put(out, f.contains("name") && f["name"].is_string() ? f["name"].get<std::string>() : "form",
          j.contains("element") && j["element"].is_string() ? j["element"].get<std::string>() : "",
          v ? std::optional<double>(*v * 1e3) : std::nullopt,
          U ? std::optional<double>(*U * 1e3 / 2) : std::nullopt, "µm");
    }
  } else if (kind == "scan") {
    // Machine time: the total (the file also splits it by kind of motion).
    if (j.contains("machine_time_s"))
      put(out, "machine_time", "",
          j["machine_time_s"].is_object() ? number_at(j["machine_time_s"], "total")
                                          : number_at(j, "machine_time_s"),
          {}, "s");
  }
  // Other kinds (a parametric model) are stored with their file and no headline figure.
  return out;
}

}  // namespace trueaxis::records
