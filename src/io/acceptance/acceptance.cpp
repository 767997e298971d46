#include "trueaxis/io/acceptance/acceptance.hpp"

#include <fmt/format.h>

#include <cmath>

#include "trueaxis/error.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::io {
namespace {

using ojson = nlohmann::ordered_json;
using P = JsonFile::pointer;

Eigen::Vector3d setup_vector3(const JsonFile& f, const P& at) {
  const Eigen::VectorXd v = f.numbers(at);
  if (v.size() != 3) f.fail(at, fmt::format("{}: three numbers [x, y, z]", dotted(at)));
  return v;
}
Eigen::Vector3d setup_direction(const JsonFile& f, const P& at) {
  const Eigen::Vector3d d = setup_vector3(f, at);
  if (!(d.norm() > 1e-9)) f.fail(at, fmt::format("{}: not a direction (zero length)", dotted(at)));
  return d.normalized();
}
double setup_optional(const JsonFile& f, const P& at, double fallback, double scale = 1) {
  return f.has(at) ? f.number(at) * scale : fallback;
}
// A true/false field; `fallback` when it is absent (none: it is required).
bool setup_boolean(const JsonFile& f, const P& at, std::optional<bool> fallback = std::nullopt) {
  if (!f.has(at)) {
    if (fallback) return *fallback;
    f.fail(at, fmt::format("'{}' is missing", dotted(at)));
  }
  const auto& v = f.root().at(at);
  if (!v.is_boolean()) f.fail(at, fmt::format("{}: true or false", dotted(at)));
  return v.get<bool>();
}
// A field that must be null (a figure there is none of) or present.
bool null_or_missing(const JsonFile& f, const P& at) {
  return !f.has(at) || f.root().at(at).is_null();
}
ojson setup_xyz(const Eigen::Vector3d& v) {
  return ojson::array({v.x(), v.y(), v.z()});
}

}  // namespace

acceptance::Setup read_acceptance_setup(const std::string& path) {
  const auto f = JsonFile::read(path);
  f.object(P(""));
  acceptance::Setup s;
  if (f.has(P("/kind")) && f.string(P("/kind")) != "acceptance-setup")
    f.fail(P("/kind"), fmt::format("kind '{}': an acceptance set-up is \"acceptance-setup\"",
                                   f.string(P("/kind"))));
  s.temperature = setup_optional(f, P("/temperature_C"), s.temperature);
  s.u_temperature = setup_optional(f, P("/u_temperature_K"), s.u_temperature);
  s.u_alignment = setup_optional(f, P("/u_alignment_um"), s.u_alignment, 1e-3);
  s.u_fixturing = setup_optional(f, P("/u_fixturing_um"), s.u_fixturing, 1e-3);
  s.block_width = setup_optional(f, P("/block_width_mm"), s.block_width);
  s.block_height = setup_optional(f, P("/block_height_mm"), s.block_height);
  s.approach = setup_optional(f, P("/approach_mm"), s.approach);
  if (f.has(P("/repetitions"))) {
    const double r = f.number(P("/repetitions"));
    if (r != std::floor(r) || r < 1 || r > 100)
      f.fail(P("/repetitions"), "repetitions: a whole number 1 … 100");
    s.repetitions = static_cast<int>(r);
  }
  if (f.has(P("/blocks"))) {
    const auto& blocks = f.array(P("/blocks"));
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      const P at = P("/blocks") / i;
      f.object(at);
      acceptance::GaugeBlock b;
      b.id = f.string(at / "id");
      b.length = f.number(at / "length_mm");
      if (!(b.length > 0)) f.fail(at / "length_mm", "length_mm: a length > 0");
      b.u = setup_optional(f, at / "u_um", 0, 1e-3);
      b.alpha = setup_optional(f, at / "alpha_per_K", b.alpha);
      b.u_alpha = setup_optional(f, at / "u_alpha_per_K", b.u_alpha);
      if (b.u < 0 || b.u_alpha < 0) f.fail(at, "an uncertainty below 0");
      for (const auto& other : s.blocks)
        if (other.id == b.id) f.fail(at / "id", fmt::format("block '{}' is listed twice", b.id));
      s.blocks.push_back(b);
    }
  }
  if (f.has(P("/placements"))) {
    const auto& placements = f.array(P("/placements"));
    for (std::size_t i = 0; i < placements.size(); ++i) {
      const P at = P("/placements") / i;
      f.object(at);
      acceptance::Placement p;
      p.block = f.string(at / "block");
      bool known = false;
      for (const auto& b : s.blocks) known = known || b.id == p.block;
      if (!known) f.fail(at / "block", fmt::format("block '{}' is not among \"blocks\"", p.block));
      if (f.has(at / "position")) p.position = f.string(at / "position");
      p.centre = setup_vector3(f, at / "centre");
      p.direction = setup_direction(f, at / "direction");
      s.placements.push_back(p);
    }
  }
  if (f.has(P("/sphere"))) {
    const P at("/sphere");
    f.object(at);
    acceptance::ReferenceSphere sp;
    sp.centre = setup_vector3(f, at / "centre");
    sp.diameter = f.number(at / "diameter_mm");
    if (!(sp.diameter > 0)) f.fail(at / "diameter_mm", "diameter_mm: a diameter > 0");
    sp.u_diameter = setup_optional(f, at / "u_um", 0, 1e-3);
    sp.form = setup_optional(f, at / "form_um", 0, 1e-3);
    if (sp.u_diameter < 0 || sp.form < 0) f.fail(at, "u_um and form_um must be ≥ 0");
    if (f.has(at / "pole")) sp.pole = setup_direction(f, at / "pole");
    s.sphere = sp;
  }
  if (s.placements.empty() && !s.sphere)
    f.fail(P(""), "no \"placements\" (with \"blocks\") and no \"sphere\": nothing to test");
  try {
    if (!s.blocks.empty()) s.validate();
  } catch (const Error& e) {
    throw Error(f.where(P("")) + e.what());
  }
  return s;
}

void write_acceptance_setup(const std::string& path, const acceptance::Setup& s) {
  ojson j;
  j["kind"] = "acceptance-setup";
  j["temperature_C"] = s.temperature;
  j["u_temperature_K"] = s.u_temperature;
  j["u_alignment_um"] = s.u_alignment * 1e3;
  j["u_fixturing_um"] = s.u_fixturing * 1e3;
  j["block_width_mm"] = s.block_width;
  j["block_height_mm"] = s.block_height;
  j["approach_mm"] = s.approach;
  j["repetitions"] = s.repetitions;
  j["blocks"] = ojson::array();
  for (const auto& b : s.blocks)
    j["blocks"].push_back({{"id", b.id},
                           {"length_mm", b.length},
                           {"u_um", b.u * 1e3},
                           {"alpha_per_K", b.alpha},
                           {"u_alpha_per_K", b.u_alpha}});
  j["placements"] = ojson::array();
  for (const auto& p : s.placements)
    j["placements"].push_back({{"block", p.block},
                               {"position", p.position},
                               {"centre", setup_xyz(p.centre)},
                               {"direction", setup_xyz(p.direction)}});
  if (s.sphere)
    j["sphere"] = {{"centre", setup_xyz(s.sphere->centre)},
                   {"diameter_mm", s.sphere->diameter},
                   {"u_um", s.sphere->u_diameter * 1e3},
                   {"form_um", s.sphere->form * 1e3},
                   {"pole", setup_xyz(s.sphere->pole)}};
  write_json(path, j);
}

void write_e0_result(const std::string& path, const acceptance::E0Result& r) {
  ojson j;
  j["kind"] = "acceptance-e0";
  j["mpe"] = r.mpe_text;
  j["test"] = r.name();  // E0, or E_L (E150) with a stylus offset
  if (r.stylus_offset) j["stylus_offset_mm"] = setup_xyz(*r.stylus_offset);
  // Nothing measured, or no repetitions: no figure, not a zero.
  j["E0_max_um"] = r.lengths.empty() ? ojson(nullptr) : ojson(r.e0_max * 1e3);
  j["R0_max_um"] = r.r0.empty() ? ojson(nullptr) : ojson(r.r0_max * 1e3);
  if (!r.r0_text.empty()) {
    j["r0_mpe"] = r.r0_text;
    j["r0_pass"] = r.r0_pass.value_or(false);
  }
  j["pass"] = r.verdict == acceptance::Verdict::Conforms && r.r0_pass.value_or(true);
  j["verdict"] = acceptance::to_string(r.verdict);
  j["rule"] = r.rule;
  j["complete"] = r.complete;
  if (!r.complete) j["stopped"] = r.stopped;
  j["positions"] = ojson::array();
  for (const auto& p : r.positions)
    j["positions"].push_back({{"name", p.name},
                              {"direction", setup_xyz(p.direction)},
                              {"space_diagonal", p.space_diagonal}});
  j["r0"] = ojson::array();
  for (const auto& x : r.r0)
    j["r0"].push_back({{"position", x.position},
                       {"block", x.block},
                       {"nominal_mm", x.nominal},
                       {"range_um", x.range * 1e3}});
  j["lengths"] = ojson::array();
  for (const auto& l : r.lengths)
    j["lengths"].push_back({{"position", l.position},
                            {"block", l.block},
                            {"repetition", l.repetition},
                            {"nominal_mm", l.nominal},
                            {"measured_mm", l.measured},
                            {"error_um", l.error * 1e3},
                            {"mpe_um", l.mpe * 1e3},
                            {"U_um", l.U * 1e3},
                            {"endpoints", ojson::array({setup_xyz(l.a), setup_xyz(l.b)})}});
  write_json(path, j);
}

void write_probing_result(const std::string& path, const acceptance::ProbingResult& r) {
  ojson j;
  j["kind"] = "acceptance-probing";
  j["PForm_um"] = r.form * 1e3;
  j["PSize_um"] = r.size * 1e3;
  j["diameter_mm"] = r.diameter;
  j["centre"] = setup_xyz(r.centre);
  j["U_form_um"] = r.U_form * 1e3;
  j["U_size_um"] = r.U_size * 1e3;
  auto verdict = [](const std::optional<acceptance::Verdict>& v) {
    return v ? ojson(acceptance::to_string(*v)) : ojson(nullptr);
  };
  j["mpe_form_um"] = r.mpe_form ? ojson(*r.mpe_form * 1e3) : ojson(nullptr);
  j["mpe_size_um"] = r.mpe_size ? ojson(*r.mpe_size * 1e3) : ojson(nullptr);
  j["form_verdict"] = verdict(r.form_verdict);
  j["size_verdict"] = verdict(r.size_verdict);
  j["pass"] =
      r.form_verdict.value_or(acceptance::Verdict::Conforms) == acceptance::Verdict::Conforms &&
      r.size_verdict.value_or(acceptance::Verdict::Conforms) == acceptance::Verdict::Conforms &&
      (r.form_verdict || r.size_verdict);
  j["rule"] = r.rule;
  j["points"] = ojson::array();
  for (Eigen::Index i = 0; i < r.points.cols(); ++i)
    j["points"].push_back({{"xyz", setup_xyz(r.points.col(i))}, {"radial_um", r.radial[i] * 1e3}});
  write_json(path, j);
}

namespace {

acceptance::Verdict verdict_of(const JsonFile& f, const P& at) {
  const std::string v = f.string(at);
  for (const auto k : {acceptance::Verdict::Conforms, acceptance::Verdict::DoesNotConform,
                       acceptance::Verdict::NotProven})
    if (v == acceptance::to_string(k)) return k;
  f.fail(at, fmt::format("{}: '{}' is not a verdict (conforms, does not conform, not proven)",
                         dotted(at), v));
}

void expect_kind(const JsonFile& f, const char* kind) {
  f.object(P(""));
  if (!f.has(P("/kind")) || f.string(P("/kind")) != kind)
    f.fail(P("/kind"), fmt::format("not a result of this kind: \"kind\" must be \"{}\"", kind));
}

}  // namespace

acceptance::E0Result read_e0_result(const std::string& path) {
  const auto f = JsonFile::read(path);
  expect_kind(f, "acceptance-e0");
  acceptance::E0Result r;
  r.mpe_text = f.string(P("/mpe"));
  // The stylus offset as a vector (mm), or its length alone (along X).
  if (f.has(P("/stylus_offset_mm"))) {
    r.stylus_offset = f.root().at(P("/stylus_offset_mm")).is_number()
                          ? Eigen::Vector3d(f.number(P("/stylus_offset_mm")), 0, 0)
                          : setup_vector3(f, P("/stylus_offset_mm"));
    try {
      acceptance::validate_stylus_offset(*r.stylus_offset);
    } catch (const Error& e) {
      f.fail(P("/stylus_offset_mm"), e.what());
    }
  }
  if (f.has(P("/r0_mpe"))) {
    r.r0_text = f.string(P("/r0_mpe"));
    if (f.has(P("/r0_pass"))) {
      r.r0_pass = setup_boolean(f, P("/r0_pass"));
    }
  }
  r.verdict = verdict_of(f, P("/verdict"));
  r.rule = f.string(P("/rule"));
  r.complete = setup_boolean(f, P("/complete"));
  if (f.has(P("/stopped"))) r.stopped = f.string(P("/stopped"));
  const auto& positions = f.array(P("/positions"));
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const P at = P("/positions") / i;
    acceptance::Position pos;
    pos.name = f.string(at / "name");
    pos.direction = setup_vector3(f, at / "direction");
    pos.space_diagonal = setup_boolean(f, at / "space_diagonal", false);
    r.positions.push_back(pos);
  }
  const auto& lengths = f.array(P("/lengths"));
  for (std::size_t i = 0; i < lengths.size(); ++i) {
    const P at = P("/lengths") / i;
    acceptance::LengthResult l;
    l.position = f.string(at / "position");
    l.block = f.string(at / "block");
    const double rep = f.number(at / "repetition");
    if (rep != std::floor(rep) || rep < 1 || rep > 100)
      f.fail(at / "repetition", "repetition: a whole number 1 … 100");
    l.repetition = static_cast<int>(rep);
    l.nominal = f.number(at / "nominal_mm");
    l.measured = f.number(at / "measured_mm");
    l.error = f.number(at / "error_um") * 1e-3;
    if (std::abs(l.error - (l.measured - l.nominal)) > 1e-9 * std::max(1.0, l.nominal))
      f.fail(at / "error_um", "error_um is not measured_mm less nominal_mm");
    l.mpe = f.number(at / "mpe_um") * 1e-3;
    l.U = f.number(at / "U_um") * 1e-3;
    const auto& ends = f.array(at / "endpoints");
    if (ends.size() != 2) f.fail(at / "endpoints", "endpoints: two points [[x, y, z], [x, y, z]]");
    l.a = setup_vector3(f, at / "endpoints" / 0);
    l.b = setup_vector3(f, at / "endpoints" / 1);
    r.e0_max = std::max(r.e0_max, std::abs(l.error));
    r.lengths.push_back(l);
  }
  if (r.lengths.empty() ? !null_or_missing(f, P("/E0_max_um"))
                        : std::abs(f.number(P("/E0_max_um")) * 1e-3 - r.e0_max) > 1e-9)
    f.fail(P("/E0_max_um"), "E0_max_um is not the largest |error_um| of the lengths (null: none)");
  for (std::size_t i = 0; i < f.array(P("/r0")).size(); ++i) {
    const P at = P("/r0") / i;
    r.r0.push_back({f.string(at / "position"), f.string(at / "block"), f.number(at / "nominal_mm"),
                    f.number(at / "range_um") * 1e-3});
    r.r0_max = std::max(r.r0_max, r.r0.back().range);
  }
  if (r.r0.empty() ? !null_or_missing(f, P("/R0_max_um"))
                   : std::abs(f.number(P("/R0_max_um")) * 1e-3 - r.r0_max) > 1e-9)
    f.fail(P("/R0_max_um"), "R0_max_um is not the largest range_um of r0 (null: none)");
  return r;
}

acceptance::ProbingResult read_probing_result(const std::string& path) {
  const auto f = JsonFile::read(path);
  expect_kind(f, "acceptance-probing");
  acceptance::ProbingResult r;
  r.form = f.number(P("/PForm_um")) * 1e-3;
  r.size = f.number(P("/PSize_um")) * 1e-3;
  r.diameter = f.number(P("/diameter_mm"));
  r.centre = setup_vector3(f, P("/centre"));
  r.U_form = f.number(P("/U_form_um")) * 1e-3;
  r.U_size = f.number(P("/U_size_um")) * 1e-3;
  auto optional_mm = [&](const char* key) -> std::optional<double> {
    const P at = P("/") / key;
    if (!f.has(at) || f.root().at(at).is_null()) return std::nullopt;
    return f.number(at) * 1e-3;
  };
  r.mpe_form = optional_mm("mpe_form_um");
  r.mpe_size = optional_mm("mpe_size_um");
  for (const char* key : {"form_verdict", "size_verdict"}) {
    const P at = P("/") / key;
    if (f.has(at) && !f.root().at(at).is_null())
      (key[0] == 'f' ? r.form_verdict : r.size_verdict) = verdict_of(f, at);
  }
  if (f.has(P("/rule"))) r.rule = f.string(P("/rule"));
  const auto& points = f.array(P("/points"));
  r.points.resize(3, static_cast<Eigen::Index>(points.size()));
  r.radial.resize(static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const P at = P("/points") / i;
    r.points.col(static_cast<Eigen::Index>(i)) = setup_vector3(f, at / "xyz");
    r.radial[static_cast<Eigen::Index>(i)] = f.number(at / "radial_um") * 1e-3;
  }
  if (points.size() > 0 && std::abs(r.radial.maxCoeff() - r.radial.minCoeff() - r.form) > 1e-9)
    f.fail(P("/PForm_um"), "PForm_um is not the range of the points' radial_um");
  return r;
}

}  // namespace trueaxis::io
