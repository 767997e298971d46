// A circular test's compensation in four controllers' files, each read back; compensation.json.
#include "trueaxis/io/circular/compensation.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>

#include "trueaxis/compensation/table.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/compensation/controller.hpp"
#include "trueaxis/io/compensation/parameters.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::io {
namespace {

using ojson = nlohmann::ordered_json;

ojson value_json(const circular::CompensationValue& v, double scale) {
  auto num = [&](double x) { return std::isfinite(x) ? ojson(x * scale) : ojson(nullptr); };
  ojson j{{"value", num(v.value)},
          {"active", num(v.active)},
          {"diagnosed", num(v.diagnosed)},
          {"u", v.u ? num(*v.u) : ojson(nullptr)},
          {"changed", v.changed}};
  if (!v.changed) j["reason"] = v.reason;
  return j;
}

// The largest difference between what was meant and what a file gives back, over the axes meant.
double difference(const AxisValues& meant, const AxisValues& got, const std::string& path) {
  double worst = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    if (meant[k].has_value() != got[k].has_value())
      throw Error(fmt::format("{}: read back with axis {} {}", path, "XYZ"[k],
                              meant[k] ? "missing" : "that was not written"));
    if (meant[k]) worst = std::max(worst, std::abs(*meant[k] - *got[k]));
  }
  return worst;
}

void check(double diff, double resolution, const std::string& path) {
  if (diff > resolution)
    throw Error(fmt::format("{}: reads back {:.3g} µm from what was written", path, diff * 1e3));
}

}  // namespace

CompensationFiles write_compensation_files(const std::string& folder,
                                           const circular::Compensation& c,
                                           const CompensationFilesOptions& o) {
  if (o.table_points < 2) throw Error("compensation: a table needs at least two points");
  if (o.travel && !((*o.travel)[1] > (*o.travel)[0]))
    throw Error("compensation: the travel is LOW,HIGH with HIGH > LOW (mm)");
  std::filesystem::create_directories(folder);
  const std::string dir = folder.empty() ? "." : folder;
  auto in = [&](const char* name) { return (std::filesystem::path(dir) / name).string(); };
  const int a = c.plane.a, b = c.plane.b;
  const char A = "XYZ"[a], B = "XYZ"[b];
  const std::vector<std::string> note{
      fmt::format("backlash from a circular test (ISO 230-4) in {} by trueaxis", c.plane.name())};
  CompensationFiles out;
  AxisValues backlash;
  backlash[static_cast<std::size_t>(a)] = c.backlash[0].value;
  backlash[static_cast<std::size_t>(b)] = c.backlash[1].value;

  // Backlash, four controllers: each file written, read back and compared within the format's
  // resolution (mm).
  struct Format {
    const char *controller, *what, *file;
    std::function<void(const std::string&)> write;
    std::function<AxisValues(const std::string&)> read;
    double resolution;
    bool takes_negative;  // a backlash < 0 (the axis overshoots) has a value in this format
  };
  const double unit = o.fanuc_detection_unit;
  const std::vector<Format> formats{
      {"LinuxCNC", "backlash ([JOINT_n] BACKLASH)", "linuxcnc-backlash.ini",
       [&](const std::string& p) { write_linuxcnc_backlash(p, backlash, note); },
       [](const std::string& p) { return read_linuxcnc_backlash(p); }, 1e-6, false},
      {"HEIDENHAIN", "backlash (MP710.x / backLash)", "heidenhain-backlash.mp",
       [&](const std::string& p) { write_heidenhain_backlash(p, backlash, note); },
       [](const std::string& p) { return read_heidenhain_backlash(p); }, 0.5e-4, true},
      {"FANUC", "backlash (No. 1851, rounded to the detection unit)", "fanuc-backlash.txt",
       [&](const std::string& p) { write_fanuc_backlash(p, backlash, unit, note); },
       [&](const std::string& p) { return read_fanuc_backlash(p, unit); }, unit / 2 * (1 + 1e-9),
       true},
      {"Siemens", "backlash (MD32450 BACKLASH)", "siemens-backlash.ini",
       [&](const std::string& p) { write_sinumerik_backlash(p, backlash, note); },
       [](const std::string& p) { return read_sinumerik_backlash(p); }, 1e-6, true}};
  for (const Format& f : formats) {
    if (!f.takes_negative && (c.backlash[0].value < 0 || c.backlash[1].value < 0)) {
      out.not_written.push_back(
          {f.controller, "backlash",
           fmt::format("a negative backlash (the axis overshoots) has no {} value", f.controller)});
      continue;
    }
    const std::string p = in(f.file);
    f.write(p);
    const double d = difference(backlash, f.read(p), p);
    check(d, f.resolution, p);
    out.written.push_back({f.controller, f.what, p, d});
  }

  // Squareness: a cross-axis table, a's correction over b's position.
  const std::string what = fmt::format("squareness ({} corrected over {})", A, B);
  out.not_written.push_back({"LinuxCNC", what, "LinuxCNC has no cross-axis compensation"});
  out.not_written.push_back(
      {"FANUC", what, "FANUC's straightness compensation (an option) is not written by trueaxis"});
  if (!o.travel) {
    const std::string why = fmt::format("the travel of {} was not given (the table's span)", B);
    out.not_written.push_back({"Siemens", what, why});
    out.not_written.push_back({"HEIDENHAIN", what, why});
  } else {
    const double lo = (*o.travel)[0], hi = (*o.travel)[1];
    const double step = (hi - lo) / (o.table_points - 1);
    const double S = c.squareness.value;
    io::CrossTable t;
    t.input = b;
    t.output = a;
    t.min = lo;
    t.step = step;
    compensation::AxisTable h;
    for (int k = 0; k < o.table_points; ++k) {
      const double x = lo + k * step;
      t.values.push_back(S * x);
      h.position.push_back(x);
      h.forward.push_back(S * x);
    }
    h.reverse = h.forward;
    const std::vector<std::string> sq_note{fmt::format(
        "squareness of {} and {} from a circular test (ISO 230-4) by trueaxis: {:+.2f} µm/m", A, B,
        S * 1e6)};
    // Each table's largest difference from S·position, over its points: rad (per mm of travel).
    const double span = std::max(std::abs(lo), std::abs(hi));
    {
      const std::string p = in("siemens-squareness.ini");
      write_sinumerik_cec(p, t, sq_note);
      const io::CrossTable back = read_sinumerik_cec(p);
      if (back.input != b || back.output != a || back.values.size() != t.values.size())
        throw Error(fmt::format("{}: reads back another table than written", p));
      double d = 0;
      for (int k = 0; k < o.table_points; ++k)
        d = std::max(d, std::abs(back.at(lo + k * step) - S * (lo + k * step)));
      check(d, 1e-6, p);
      out.written.push_back({"Siemens", what + " (sag and angularity compensation)", p, d / span});
    }
    {
      const std::string p = in("heidenhain-squareness.com");
      HeidenhainOptions ho;
      ho.axis = std::string(1, A);
      write_heidenhain(p, h, ho);
      std::string col;
      const compensation::AxisTable back = read_heidenhain(p, &col);
      if (col != ho.axis || back.position.size() != h.position.size())
        throw Error(fmt::format("{}: reads back another table than written", p));
      double d = 0;
      for (std::size_t k = 0; k < h.position.size(); ++k)
        d = std::max(d, std::abs(back.forward[k] - h.forward[k]));
      check(d, 0.5e-4, p);
      out.written.push_back(
          {"HEIDENHAIN",
           what + fmt::format(" ({} column over {} positions; assign in the *.CMA)", A, B), p,
           d / span});
    }
  }

  ojson j;
  j["kind"] = "circular compensation";
  j["plane"] = c.plane.name();
  j["backlash_um"] = {{std::string(1, A), value_json(c.backlash[0], 1e3)},
                      {std::string(1, B), value_json(c.backlash[1], 1e3)}};
  j["squareness_um_per_m"] = value_json(c.squareness, 1e6);
  j["squareness_table"] = fmt::format("{} += squareness·{} (zero at {} = 0)", A, B, B);
  ojson files = ojson::array(), skipped = ojson::array();
  for (const auto& w : out.written) {
    const bool table = w.what.rfind("squareness", 0) == 0;
    files.push_back({{"controller", w.controller},
                     {"what", w.what},
                     {"file", std::filesystem::path(w.path).filename().string()},
                     {"read_back", true},
                     {table ? "max_difference_um_per_m" : "max_difference_um",
                      w.max_difference * (table ? 1e6 : 1e3)}});
  }
  for (const auto& n : out.not_written)
    skipped.push_back({{"controller", n.controller}, {"what", n.what}, {"reason", n.reason}});
  j["files"] = files;
  j["not_written"] = skipped;
  out.json_path = in("compensation.json");
  write_json(out.json_path, j);
  return out;
}

AppliedCompensation read_compensation_json(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  using P = JsonFile::pointer;
  if (!f.has(P("/kind")) || f.string(P("/kind")) != "circular compensation")
    f.fail(P("/kind"), "not a circular test's compensation (\"kind\": \"circular compensation\")");
  AppliedCompensation c;
  try {
    c.plane = circular::Plane::parse(f.string(P("/plane")));
  } catch (const Error& e) {
    f.fail(P("/plane"), e.what());
  }
  for (int i = 0; i < 2; ++i) {
    const std::string axis(1, "XYZ"[i == 0 ? c.plane.a : c.plane.b]);
    c.backlash[static_cast<std::size_t>(i)] = f.number(P("/backlash_um") / axis / "value") * 1e-3;
  }
  c.squareness = f.number(P("/squareness_um_per_m/value")) * 1e-6;
  c.path = path;
  return c;
}

void AppliedCompensation::apply(sim::CircularOptions& o) const {
  if (plane.name() != o.plane.name())
    throw Error(fmt::format("{}: a compensation for {}; this test runs in {}", path, plane.name(),
                            o.plane.name()));
  o.compensation.backlash[static_cast<std::size_t>(plane.a)] = backlash[0];
  o.compensation.backlash[static_cast<std::size_t>(plane.b)] = backlash[1];
  o.compensation.cross_output = plane.a;
  o.compensation.cross_input = plane.b;
  o.compensation.cross_slope = squareness;
}

}  // namespace trueaxis::io
