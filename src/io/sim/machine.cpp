#include "trueaxis/io/sim/machine.hpp"

#include <fmt/format.h>

#include <map>

#include "trueaxis/error.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::io {
namespace {

using ptr = JsonFile::pointer;

constexpr double kUm = 1e-3;    // µm → mm
constexpr double kUrad = 1e-6;  // µrad → rad

// Scale of component c (0..2 linear in µm, 3..5 angular in µrad) into library units.
double scale_of(int c) {
  return c < 3 ? kUm : kUrad;
}

std::vector<double> numbers(const JsonFile& f, const ptr& p, double scale) {
  const Eigen::VectorXd v = f.numbers(p, scale);
  return {v.data(), v.data() + v.size()};
}

sim::ErrorFunction read_function(const JsonFile& f, const ptr& p, double scale) {
  const auto& o = f.object(p);
  sim::ErrorFunction fn;
  for (const auto& [key, value] : o.items()) {
    (void)value;
    if (key != "polynomial" && key != "sines" && key != "table")
      f.fail(p / key, fmt::format("unknown key '{}' in an error function (polynomial, sines, "
                                  "table)",
                                  key));
  }
  if (o.contains("polynomial")) fn.polynomial = numbers(f, p / "polynomial", scale);
  if (o.contains("sines")) {
    const auto& s = f.array(p / "sines");
    for (std::size_t i = 0; i < s.size(); ++i) {
      f.object(p / "sines" / i);
      fn.sines.push_back({f.number(p / "sines" / i / "amplitude") * scale,
                          f.number(p / "sines" / i / "period"),
                          s[i].contains("phase") ? f.number(p / "sines" / i / "phase") : 0.0});
      if (!(fn.sines.back().period > 0))
        f.fail(p / "sines" / i / "period", "the period must be positive (mm)");
    }
  }
  if (o.contains("table")) {
    f.object(p / "table");
    fn.table_u = numbers(f, p / "table" / "u", 1.0);
    fn.table_value = numbers(f, p / "table" / "value", scale);
    if (fn.table_u.size() != fn.table_value.size())
      f.fail(p / "table" / "value",
             fmt::format("'{}' has {} values for {} positions", dotted(p / "table" / "value"),
                         fn.table_value.size(), fn.table_u.size()));
  }
  return fn;
}

nlohmann::ordered_json write_function(const sim::ErrorFunction& fn, double scale) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  if (!fn.polynomial.empty()) {
    auto& a = j["polynomial"] = nlohmann::ordered_json::array();
    for (double c : fn.polynomial) a.push_back(c / scale);
  }
  if (!fn.sines.empty()) {
    auto& a = j["sines"] = nlohmann::ordered_json::array();
    for (const auto& s : fn.sines)
      a.push_back({{"amplitude", s.amplitude / scale}, {"period", s.period}, {"phase", s.phase}});
  }
  if (!fn.table_u.empty()) {
    auto& t = j["table"];
    t["u"] = fn.table_u;
    auto& v = t["value"] = nlohmann::ordered_json::array();
    for (double x : fn.table_value) v.push_back(x / scale);
  }
  return j;
}

}  // namespace

sim::Machine read_machine(const std::string& path) {
  return read_machine(JsonFile::read(path));
}

sim::Machine read_machine(const JsonFile& f) {
  const ptr root;
  f.object(root);
  sim::Machine m;
  if (f.has(ptr("/name"))) m.name = f.string(ptr("/name"));
  if (f.has(ptr("/chain"))) {
    m.chain = f.string(ptr("/chain"));
    try {
      sim::Machine probe;
      probe.chain = m.chain;
      probe.validate();
    } catch (const Error& e) {
      f.fail(ptr("/chain"), e.what());
    }
  }
  f.object(ptr("/ranges"));
  const char* names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    const ptr p = ptr("/ranges") / names[k];
    const auto& a = f.array(p);
    if (a.size() != 2) f.fail(p, fmt::format("'{}' must be [min, max] in mm", dotted(p)));
    const double lo = f.number(p / 0), hi = f.number(p / 1);
    if (!(hi > lo)) f.fail(p, fmt::format("'{}': min {} must be below max {}", dotted(p), lo, hi));
    m.range[static_cast<std::size_t>(k)] = {lo, hi};
  }
  if (f.has(ptr("/offset"))) {
    const auto v = numbers(f, ptr("/offset"), 1.0);
    if (v.size() != 3) f.fail(ptr("/offset"), "'offset' must be [x, y, z] in mm");
    m.offset = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  if (f.has(ptr("/errors"))) {
    const auto& errs = f.object(ptr("/errors"));
    std::map<std::string, std::pair<int, int>> axis_errors;
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 6; ++c)
        axis_errors[sim::error_name(k, static_cast<sim::Component>(c))] = {k, c};
    for (const auto& [key, value] : errs.items()) {
      (void)value;
      const ptr p = ptr("/errors") / key;
      if (key == "EC0Y" || key == "EB0Z" || key == "EA0Z") {
        const double v = f.number(p);
        // The rotations are exact, but a squareness of a tenth of a radian is no machine.
        if (std::abs(v) > 1e5)
          f.fail(p, fmt::format("squareness {} = {:g} µrad: must be below 100000 µrad (0.1 rad)",
                                key, v));
        (key == "EC0Y"   ? m.squareness_c0y
         : key == "EB0Z" ? m.squareness_b0z
                         : m.squareness_a0z) = v * kUrad;
      } else if (auto it = axis_errors.find(key); it != axis_errors.end()) {
        const auto [k, c] = it->second;
        auto& fn = m.errors[static_cast<std::size_t>(k)][static_cast<std::size_t>(c)];
        fn = read_function(f, p, scale_of(c));
        try {
          const auto& r = m.range[static_cast<std::size_t>(k)];
          fn.validate(key, r[0], r[1]);
        } catch (const Error& e) {
          f.fail(p, e.what());
        }
      } else {
        f.fail(p, fmt::format("unknown error '{}': expected E[XYZABC][XYZ] (e.g. EXX, EBY) or "
                              "the squareness errors EC0Y, EB0Z, EA0Z",
                              key));
      }
    }
  }
  try {
    m.validate();
  } catch (const Error& e) {
    f.fail(root, e.what());
  }
  return m;
}

void write_machine(const std::string& path, const sim::Machine& m) {
  write_json(path, machine_json(m));
}

nlohmann::ordered_json machine_json(const sim::Machine& m) {
  m.validate();
  nlohmann::ordered_json j;
  j["name"] = m.name;
  j["chain"] = m.chain;
  j["units"] =
      "mm for positions, µm for linear errors, µrad for angular errors; polynomial "
      "coefficient k multiplies (u / 1000 mm)^k";
  auto& r = j["ranges"];
  const char* names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k)
    r[names[k]] = {m.range[static_cast<std::size_t>(k)][0],
                   m.range[static_cast<std::size_t>(k)][1]};
  j["offset"] = {m.offset.x(), m.offset.y(), m.offset.z()};
  auto& e = j["errors"];
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 6; ++c) {
      const auto& fn = m.errors[static_cast<std::size_t>(k)][static_cast<std::size_t>(c)];
      if (!fn.empty())
        e[sim::error_name(k, static_cast<sim::Component>(c))] = write_function(fn, scale_of(c));
    }
  e["EC0Y"] = m.squareness_c0y / kUrad;
  e["EB0Z"] = m.squareness_b0z / kUrad;
  e["EA0Z"] = m.squareness_a0z / kUrad;
  return j;
}

Eigen::Matrix3Xd read_points(const std::string& path, const sim::Machine* machine) {
  CsvTable t = CsvTable::read(path);
  const int cols[3] = {t.require("x", Unit::Millimetre), t.require("y", Unit::Millimetre),
                       t.require("z", Unit::Millimetre)};
  if (t.rows() == 0) throw Error(fmt::format("{}: no points", path));
  Eigen::Matrix3Xd p(3, static_cast<Eigen::Index>(t.rows()));
  for (int k = 0; k < 3; ++k) p.row(k) = t.column(cols[k]).transpose();
  if (machine != nullptr) {
    const char* names = "xyz";
    for (Eigen::Index i = 0; i < p.cols(); ++i)
      for (int k = 0; k < 3; ++k) {
        const auto& r = machine->range[static_cast<std::size_t>(k)];
        if (!(p(k, i) >= r[0] && p(k, i) <= r[1]))
          throw Error(fmt::format("{}{} = {} mm is outside the machine's range [{}, {}]",
                                  t.where(static_cast<long>(i), cols[k]), names[k], p(k, i), r[0],
                                  r[1]));
      }
  }
  return p;
}

void write_points(const std::string& path, const Eigen::Matrix3Xd& p) {
  const Eigen::VectorXd x = p.row(0).transpose(), y = p.row(1).transpose(),
                        z = p.row(2).transpose();
  write_csv(path, {"x", "y", "z"}, {&x, &y, &z});
}

}  // namespace trueaxis::io
