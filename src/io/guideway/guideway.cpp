#include "trueaxis/io/guideway/guideway.hpp"

#include <fmt/format.h>

#include <set>

#include "trueaxis/error.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::io {
namespace {

using ptr = JsonFile::pointer;
using ojson = nlohmann::ordered_json;

ojson array_or_null(const Eigen::VectorXd& v, double scale) {
  if (v.size() == 0) return nullptr;
  ojson a = ojson::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i] * scale);
  return a;
}

guideway::Qpd read_qpd(const JsonFile& f, const ptr& at) {
  guideway::Qpd q;
  for (const auto& [key, value] : f.object(at).items()) {
    const ptr k = at / key;
    if (key == "gain_um") {
      q.gain = f.number(k) * 1e-3;
    } else if (key == "min_sum") {
      q.min_sum = f.number(k);
    } else if (key == "max_signal") {
      q.max_signal = f.number(k);
    } else if (key == "table") {
      for (const auto& [tk, tv] : f.object(k).items()) {
        if (tk == "signal")
          q.table_signal = f.numbers(k / tk);
        else if (tk == "displacement_um")
          q.table_displacement = f.numbers(k / tk, 1e-3);
        else
          f.fail(k / tk, fmt::format("unknown key '{}' (signal, displacement_um)", tk));
      }
    } else {
      f.fail(k, fmt::format("unknown key '{}' (gain_um, min_sum, max_signal, table)", key));
    }
  }
  try {
    q.validate();
  } catch (const Error& e) {
    f.fail(at, e.what());
  }
  return q;
}

}  // namespace

GuidewayLayout read_layout(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  GuidewayLayout g;
  for (const auto& [key, value] : f.object(ptr()).items()) {
    if (key != "detectors" && key != "qpd")
      f.fail(ptr() / key, fmt::format("unknown key '{}' (detectors, qpd)", key));
  }
  const ptr dets = ptr() / "detectors";
  if (!f.has(dets)) f.fail(ptr(), "'detectors' is missing");
  const auto& arr = f.array(dets);
  if (arr.empty()) f.fail(dets, "no detectors");
  std::set<std::string> names;
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const ptr d = dets / i;
    guideway::Detector det;
    bool has_position = false;
    for (const auto& [key, value] : f.object(d).items()) {
      const ptr k = d / key;
      if (key == "name") {
        det.name = f.string(k);
        if (det.name.empty() || det.name.find_first_of(", \t\"") != std::string::npos)
          f.fail(k, "detector names must be non-empty, without commas, spaces or quotes");
        if (!names.insert(det.name).second)
          f.fail(k, fmt::format("detector name '{}' is used twice", det.name));
      } else if (key == "kind") {
        const std::string kind = f.string(k);
        if (kind == "position")
          det.kind = guideway::Kind::Position;
        else if (kind == "angle")
          det.kind = guideway::Kind::Angle;
        else
          f.fail(k, fmt::format("kind must be \"position\" or \"angle\", not \"{}\"", kind));
      } else if (key == "position") {
        const Eigen::VectorXd p = f.numbers(k);
        if (p.size() != 3) f.fail(k, "position needs [x, y, z] (mm)");
        det.position = p;
        has_position = true;
      } else if (key == "focal_length") {
        det.focal_length = f.number(k);
      } else {
        f.fail(k, fmt::format("unknown key '{}' (name, kind, position, focal_length)", key));
      }
    }
    if (det.name.empty()) f.fail(d, "detector without a 'name'");
    if (det.kind == guideway::Kind::Position && !has_position)
      f.fail(d, fmt::format("position detector '{}' needs a 'position' [x, y, z] (mm)", det.name));
    if (det.kind == guideway::Kind::Angle && !(det.focal_length > 0))
      f.fail(d, fmt::format("angle detector '{}' needs a positive 'focal_length' (mm)", det.name));
    g.layout.detectors.push_back(std::move(det));
  }
  try {
    g.layout.validate();
  } catch (const Error& e) {
    f.fail(dets, e.what());
  }
  if (f.has(ptr() / "qpd")) g.qpd = read_qpd(f, ptr() / "qpd");
  return g;
}

Spots read_spots(const std::string& path, const GuidewayLayout& g, bool skip_bad) {
  CsvTable t = CsvTable::read(path);
  // Units may be written in the names ("s [mm]", "a_dx [µm]"); s is read in mm, spots in µm.
  if (t.header().empty() || t.find("s", Unit::Millimetre) != 0)
    throw Error(
        fmt::format("{}the first column must be 's' (carriage position, mm)", t.where(-1, 0)));
  const auto& dets = g.layout.detectors;
  // Every column must belong to a known detector.
  for (std::size_t c = 1; c < t.cols(); ++c) {
    const std::string& h = t.header()[c];
    std::string q;
    try {
      q = split_column_name(h).quantity;
    } catch (const Error& e) {
      throw Error(t.where(-1, static_cast<int>(c)) + e.what());
    }
    const auto us = q.rfind('_');
    const std::string name = us == std::string::npos ? q : q.substr(0, us);
    const std::string suffix = us == std::string::npos ? "" : q.substr(us + 1);
    bool known = false;
    for (const auto& d : dets) known |= d.name == name;
    if (!known)
      throw Error(fmt::format("{}column '{}' names no detector of the layout",
                              t.where(-1, static_cast<int>(c)), h));
    if (suffix != "dx" && suffix != "dy" && suffix != "i1" && suffix != "i2" && suffix != "i3" &&
        suffix != "i4")
      throw Error(fmt::format("{}column '{}': expected <name>_dx, _dy (µm) or _i1.._i4 (currents)",
                              t.where(-1, static_cast<int>(c)), h));
  }
  const long n = static_cast<long>(t.rows());
  if (n == 0) throw Error(fmt::format("{}: no positions", path));
  const Eigen::VectorXd& s = t.column(0);
  Eigen::MatrixXd spots(n, 2 * static_cast<Eigen::Index>(dets.size()));
  std::vector<char> bad(static_cast<std::size_t>(n), 0);
  Spots out;
  for (std::size_t i = 0; i < dets.size(); ++i) {
    const std::string& name = dets[i].name;
    const int dx = t.find(name + "_dx", Unit::Micrometre),
              dy = t.find(name + "_dy", Unit::Micrometre);
    int cur[4];
    bool any_current = false, all_current = true;
    for (int q = 0; q < 4; ++q) {
      cur[q] = t.find(fmt::format("{}_i{}", name, q + 1), Unit::Count);
      any_current |= cur[q] >= 0;
      all_current &= cur[q] >= 0;
    }
    const auto c = 2 * static_cast<Eigen::Index>(i);
    if (dx >= 0 || dy >= 0) {
      if (any_current)
        throw Error(fmt::format("{}detector '{}' has both displacement and current columns",
                                t.where(-1, dx >= 0 ? dx : dy), name));
      if (dx < 0 || dy < 0)
        throw Error(fmt::format("{}detector '{}' needs both {}_dx and {}_dy", t.where(-1, 0), name,
                                name, name));
      spots.col(c) = t.column(dx) * 1e-3;
      spots.col(c + 1) = t.column(dy) * 1e-3;
      continue;
    }
    if (!all_current)
      throw Error(
          fmt::format("{}detector '{}' has no columns: give {}_dx,{}_dy (µm) or "
                      "{}_i1..{}_i4 (currents)",
                      t.where(-1, 0), name, name, name, name, name));
    if (!g.qpd)
      throw Error(
          fmt::format("{}detector '{}' gives quadrant currents, but the layout has no "
                      "\"qpd\" calibration (gain_um or table)",
                      t.where(-1, cur[0]), name));
    for (long k = 0; k < n; ++k) {
      try {
        const Eigen::Vector2d d = g.qpd->spot(t.column(cur[0])[k], t.column(cur[1])[k],
                                              t.column(cur[2])[k], t.column(cur[3])[k]);
        spots(k, c) = d.x();
        spots(k, c + 1) = d.y();
      } catch (const Error& e) {
        const std::string msg = fmt::format("{}detector '{}' at s = {:g} mm: {}",
                                            t.where(k, cur[0]), name, s[k], e.what());
        if (!skip_bad) throw Error(msg);
        if (!bad[static_cast<std::size_t>(k)]) out.skipped.push_back(msg);
        bad[static_cast<std::size_t>(k)] = 1;
      }
    }
  }
  const long kept = n - static_cast<long>(out.skipped.size());
  if (kept == 0)
    throw Error(fmt::format("{}: every sample was rejected ({})", path, out.skipped.front()));
  out.s.resize(kept);
  out.spots.resize(kept, spots.cols());
  for (long k = 0, j = 0; k < n; ++k) {
    if (bad[static_cast<std::size_t>(k)]) continue;
    out.s[j] = s[k];
    out.spots.row(j) = spots.row(k);
    ++j;
  }
  return out;
}

void write_guideway_result(const std::string& path, const guideway::Result& r) {
  ojson j;
  j["kind"] = "guideway";
  j["s"] = array_or_null(r.s, 1.0);
  for (int e = 0; e < guideway::kErrors; ++e)
    j[guideway::kErrorNames[e]] =
        array_or_null(r.value[static_cast<std::size_t>(e)], e < 2 ? 1e3 : 1e6);
  j["residual"] = array_or_null(r.residual, 1e3);
  j["straightness"] = {{"horizontal", array_or_null(r.horizontal_straightness, 1e3)},
                       {"vertical", array_or_null(r.vertical_straightness, 1e3)}};
  ojson obs = ojson::object(), unc = ojson::object(), sum = ojson::object();
  for (int e = 0; e < guideway::kErrors; ++e) {
    const auto k = static_cast<std::size_t>(e);
    const double sc = e < 2 ? 1e3 : 1e6;
    obs[guideway::kErrorNames[e]] = r.layout.observable[k];
    const bool have = r.value[k].size() > 0;
    unc[guideway::kErrorNames[e]] =
        have && r.sigma > 0 ? ojson(r.uncertainty[k] * sc) : ojson(nullptr);
    // Each PV with its expanded uncertainty (95 %) and whether the data resolve it; null when
    // no uncertainty is stated (the reason in "no_uncertainty").
    const std::optional<double> U = r.pv_U(k);
    const std::optional<bool> resolved = r.resolved(k);
    sum[guideway::kErrorNames[e]] =
        have ? ojson({{"pv", r.pv[k] * sc},
                      {"rms", r.rms[k] * sc},
                      {"U", U ? ojson(*U * sc) : ojson(nullptr)},
                      {"resolved", resolved ? ojson(*resolved) : ojson(nullptr)}})
             : ojson(nullptr);
  }
  j["observable"] = obs;
  j["condition_number"] =
      std::isfinite(r.layout.condition_number) ? ojson(r.layout.condition_number) : ojson(nullptr);
  j["observable_condition_number"] = r.layout.observable_condition_number;
  j["singular_values"] = array_or_null(r.layout.singular_values, 1.0);
  j["sigma_um"] = r.sigma > 0 ? ojson(r.sigma * 1e3) : ojson(nullptr);
  j["sigma_estimated"] = r.sigma_estimated;
  if (!r.no_uncertainty.empty()) j["no_uncertainty"] = r.no_uncertainty;
  j["uncertainty"] = unc;
  j["summary"] = sum;
  j["message"] = r.layout.message;
  // On a machine axis: ISO 230-1's name of each error and the sign from the carriage frame (the
  // values above) to the machine frame that name means.
  if (r.axis >= 0) {
    j["axis"] = std::string(1, "XYZ"[r.axis]);
    ojson iso = ojson::object();
    const auto names = guideway::iso_names(r.axis);
    for (int e = 0; e < guideway::kErrors; ++e)
      iso[guideway::kErrorNames[e]] = {{"name", names[static_cast<std::size_t>(e)].name},
                                       {"sign", names[static_cast<std::size_t>(e)].sign}};
    j["iso_230_1"] = iso;
  }
  write_json(path, j);
}

void write_layout(const std::string& path, const guideway::Layout& layout) {
  ojson dets = ojson::array();
  for (const auto& d : layout.detectors) {
    ojson o;
    o["name"] = d.name;
    if (d.kind == guideway::Kind::Angle) {
      o["kind"] = "angle";
      o["focal_length"] = d.focal_length;
    } else {
      o["kind"] = "position";
      o["position"] = {d.position.x(), d.position.y(), d.position.z()};
    }
    dets.push_back(o);
  }
  write_json(path, ojson{{"detectors", dets}});
}

void write_spots(const std::string& path, const guideway::Layout& layout, const Eigen::VectorXd& s,
                 const Eigen::MatrixXd& spots) {
  if (spots.cols() != 2 * static_cast<Eigen::Index>(layout.detectors.size()) ||
      spots.rows() != s.size())
    throw Error(fmt::format("{}: spots must be positions x 2 per detector", path));
  std::vector<std::string> header{"s"};
  std::vector<Eigen::VectorXd> cols;
  for (std::size_t i = 0; i < layout.detectors.size(); ++i) {
    header.push_back(layout.detectors[i].name + "_dx");
    header.push_back(layout.detectors[i].name + "_dy");
    cols.push_back(spots.col(2 * static_cast<Eigen::Index>(i)) * 1e3);
    cols.push_back(spots.col(2 * static_cast<Eigen::Index>(i) + 1) * 1e3);
  }
  std::vector<const Eigen::VectorXd*> ptrs{&s};
  for (const auto& c : cols) ptrs.push_back(&c);
  write_csv(path, header, ptrs);
}

}  // namespace trueaxis::io
