// The laboratory's statements for a certificate, read from its JSON file (certificate.hpp).
//
// {"name", "address", "accreditation", "certificate_number", "customer", "customer_address",
//  "machines": {"VMC-3": {"description", "maker", "model", "serial", "location"}},
//  "instruments": [{"id", "description", "serial", "certificate", "calibrated", "due"}],
//  "limits": {"A@X": 20, "E0": 3.5}, "decision_rule": "ISO 14253-1" | "simple",
//  "compensation", "environment", "performed_by", "approved_by",
//  "laser": {"device_U_per_m", "misalignment_mrad", "temperature_u_K", "expansion_coefficient",
//            "expansion_u_relative", "temperature_C", "eve_um", "setup_u_um"}}
#include <fmt/format.h>

#include <fstream>
#include <iterator>
#include <set>

#include "trueaxis/certificate/certificate.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::certificate {
namespace {

using ptr = io::JsonFile::pointer;

// The string at key `k` of the object at `at` ("" when absent).
std::string text_at(const io::JsonFile& f, const ptr& at, const char* k) {
  const ptr p = at / k;
  return f.has(p) ? f.string(p) : std::string();
}

void refuse_unknown(const io::JsonFile& f, const ptr& at, const std::set<std::string>& known) {
  for (const auto& [k, v] : f.object(at).items()) {
    (void)v;
    if (!known.count(k))
      f.fail(at / k, fmt::format("unknown key '{}' (known: {})", k, [&] {
               std::string s;
               for (const auto& n : known) s += (s.empty() ? "" : ", ") + n;
               return s;
             }()));
  }
}

void check_date(const io::JsonFile& f, const ptr& p, const std::string& d) {
  if (d.empty()) return;
  try {
    (void)records::day_number(d);
  } catch (const Error&) {
    f.fail(p, fmt::format("'{}' is not an ISO 8601 date (YYYY-MM-DD)", d));
  }
}

}  // namespace

Lab parse_lab(const std::string& json, const std::string& name) {
  const auto f = io::JsonFile::parse(json, name);
  const ptr root;
  (void)f.object(root);
  refuse_unknown(f, root,
                 {"name", "address", "accreditation", "certificate_number", "customer",
                  "customer_address", "machines", "instruments", "limits", "decision_rule",
                  "compensation", "environment", "performed_by", "approved_by", "laser"});
  Lab lab;
  lab.name = text_at(f, root, "name");
  lab.address = text_at(f, root, "address");
  lab.accreditation = text_at(f, root, "accreditation");
  lab.certificate_number = text_at(f, root, "certificate_number");
  lab.customer = text_at(f, root, "customer");
  lab.customer_address = text_at(f, root, "customer_address");
  lab.compensation = text_at(f, root, "compensation");
  lab.environment = text_at(f, root, "environment");
  lab.performed_by = text_at(f, root, "performed_by");
  lab.approved_by = text_at(f, root, "approved_by");
  if (f.has(root / "machines"))
    for (const auto& [id, v] : f.object(root / "machines").items()) {
      (void)v;
      const ptr at = root / "machines" / id;
      (void)f.object(at);
      refuse_unknown(f, at, {"description", "maker", "model", "serial", "location"});
      lab.machines[id] = {text_at(f, at, "description"), text_at(f, at, "maker"),
                          text_at(f, at, "model"), text_at(f, at, "serial"),
                          text_at(f, at, "location")};
    }
  if (f.has(root / "instruments")) {
    const auto& a = f.array(root / "instruments");
    for (std::size_t i = 0; i < a.size(); ++i) {
      const ptr at = root / "instruments" / i;
      (void)f.object(at);
      refuse_unknown(f, at, {"id", "description", "serial", "certificate", "calibrated", "due"});
      Instrument in{f.string(at / "id"),          text_at(f, at, "description"),
                    text_at(f, at, "serial"),     text_at(f, at, "certificate"),
                    text_at(f, at, "calibrated"), text_at(f, at, "due")};
      check_date(f, at / "calibrated", in.calibrated);
      check_date(f, at / "due", in.due);
      lab.instruments.push_back(std::move(in));
    }
  }
  if (f.has(root / "limits"))
    for (const auto& [k, v] : f.object(root / "limits").items()) {
      (void)v;
      const double limit = f.number(root / "limits" / k);
      try {
        const auto l = records::Limit::parse(fmt::format("{}={:.17g}", k, limit));
        lab.limits[l.axis.empty() ? l.figure : l.figure + "@" + l.axis] = l.value;
      } catch (const Error& e) {
        f.fail(root / "limits" / k, e.what());
      }
    }
  if (f.has(root / "decision_rule")) {
    const std::string r = f.string(root / "decision_rule");
    if (r == "ISO 14253-1" || r == "iso14253-1")
      lab.rule = Rule::Iso14253;
    else if (r == "simple")
      lab.rule = Rule::Simple;
    else
      f.fail(root / "decision_rule",
             fmt::format("'{}': the decision rule is \"ISO 14253-1\" or \"simple\"", r));
  }
  if (f.has(root / "laser")) {
    const ptr at = root / "laser";
    (void)f.object(at);
    refuse_unknown(
        f, at,
        {"device_U_per_m", "misalignment_mrad", "temperature_u_K", "expansion_coefficient",
         "expansion_u_relative", "temperature_C", "eve_um", "setup_u_um"});
    auto& l = lab.laser;
    auto num = [&](const char* k, double& out) {
      if (f.has(at / k)) out = f.number(at / k);
    };
    num("device_U_per_m", l.device_U_per_m);
    num("misalignment_mrad", l.misalignment_mrad);
    num("temperature_u_K", l.temperature_u_K);
    num("expansion_coefficient", l.expansion_coefficient);
    num("expansion_u_relative", l.expansion_u_relative);
    num("setup_u_um", l.setup_u_um);
    if (f.has(at / "temperature_C")) l.temperature_C = f.number(at / "temperature_C");
    if (f.has(at / "eve_um")) l.eve_um = f.number(at / "eve_um");
    try {
      l.validate();
    } catch (const Error& e) {
      f.fail(at, e.what());
    }
  }
  return lab;
}

Lab read_lab(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(fmt::format("{}: cannot open the laboratory file", path));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_lab(text, path);
}

}  // namespace trueaxis::certificate
