// A calibration certificate from a machine's records of one visit (certificate.hpp).
#include "trueaxis/certificate/certificate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "trueaxis/error.hpp"

namespace trueaxis::certificate {
namespace {

constexpr const char* kIso14253 =
    "ISO 14253-1:2017, Geometrical product specifications: inspection by measurement of "
    "workpieces and measuring equipment, Part 1: decision rules for verifying conformity or "
    "nonconformity with specifications.";
constexpr const char* kIso230_9 =
    "ISO/TR 230-9:2005, Test code for machine tools, Part 9: estimation of measurement "
    "uncertainty for machine tool tests according to series ISO 230, basic equations.";
constexpr const char* kIso230_3 =
    "ISO 230-3:2020, Test code for machine tools, Part 3: determination of thermal effects "
    "(the environmental variation error E_VE).";
constexpr const char* kIlacG8 =
    "ILAC-G8:09/2019, Guidelines on decision rules and statements of conformity (4.2.1, simple "
    "acceptance).";

int state_order(records::State s) {
  return s == records::State::AsFound ? 0 : s == records::State::None ? 1 : 2;
}

std::string state_title(records::State s) {
  return s == records::State::AsFound  ? "as found (before any adjustment)"
         : s == records::State::AsLeft ? "as left (after adjustment or compensation)"
                                       : "state not stated";
}

std::string num(double v) {
  return fmt::format("{:.3g}", v);
}

// A positioning result's measured length (the span of its targets, mm) and the material
// temperature its readings carried (their mean, °C), from the stored file.
struct PositioningFacts {
  double length_mm = 0;
  std::optional<double> material_C;
  std::map<std::string, double> tolerances;  // the limits the evaluation was given
};

PositioningFacts positioning_facts(const std::string& content) {
  PositioningFacts f;
  const auto j = nlohmann::json::parse(content, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return f;
  double lo = INFINITY, hi = -INFINITY;
  if (const auto t = j.find("targets"); t != j.end() && t->is_array())
    for (const auto& target : *t)
      if (target.is_object() && target.contains("position") && target["position"].is_number()) {
        lo = std::min(lo, target["position"].get<double>());
        hi = std::max(hi, target["position"].get<double>());
      }
  if (hi > lo) f.length_mm = hi - lo;
  // The material temperatures' range, [min, max] °C, when the readings carried them.
  if (const auto t = j.find("temperature"); t != j.end() && t->is_object())
    if (const auto m = t->find("material"); m != t->end() && m->is_array() && m->size() == 2 &&
                                            (*m)[0].is_number() && (*m)[1].is_number())
      f.material_C = ((*m)[0].get<double>() + (*m)[1].get<double>()) / 2;
  if (const auto t = j.find("tolerances"); t != j.end() && t->is_object())
    for (const auto& [name, v] : t->items())
      if (v.is_object() && v.contains("limit") && v["limit"].is_number())
        f.tolerances[name] = v["limit"].get<double>();
  return f;
}

// The verdicts an acceptance result carries by its own rule (ISO 10360 with ISO 14253-1).
struct OwnVerdict {
  std::string decision;
  std::optional<double> limit;
};
std::optional<OwnVerdict> own_verdict(const std::string& kind, const std::string& figure,
                                      const std::string& content) {
  const auto j = nlohmann::json::parse(content, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return std::nullopt;
  auto text = [&](const char* k) {
    return j.contains(k) && j[k].is_string() ? j[k].get<std::string>() : std::string();
  };
  auto number = [&](const char* k) -> std::optional<double> {
    if (j.contains(k) && j[k].is_number()) return j[k].get<double>();
    return std::nullopt;
  };
  if (kind == "acceptance-e0" && (figure == "E0" || figure == "E150") && !text("verdict").empty())
    return OwnVerdict{
        fmt::format("{} (MPE {} µm, the test's own rule)", text("verdict"), text("mpe")),
        std::nullopt};
  if (kind == "acceptance-probing" && figure == "PForm" && !text("form_verdict").empty())
    return OwnVerdict{text("form_verdict") + " (the test's own rule)", number("mpe_form_um")};
  if (kind == "acceptance-probing" && figure == "PSize" && !text("size_verdict").empty())
    return OwnVerdict{text("size_verdict") + " (the test's own rule)", number("mpe_size_um")};
  return std::nullopt;
}

}  // namespace

Certificate make(const records::Database& db, const Lab& lab, const Options& options) {
  options.validate();
  lab.laser.validate();
  const std::string to = options.to.empty() ? options.date : options.to;
  records::ListFilter filter;
  filter.machine = options.machine;
  filter.from = options.date;
  filter.to = to;
  auto recs = db.list(filter);
  if (recs.empty()) {
    std::string seen;
    for (const auto& m : db.machines())
      if (m.id == options.machine)
        seen = m.records ? fmt::format(" (its records run from {} to {})", m.first, m.last)
                         : " (it has no records)";
    throw Error(fmt::format("machine '{}' has no records from {} to {}{}", options.machine,
                            options.date, to,
                            seen.empty() ? " (no such machine in the records)" : seen));
  }
  std::stable_sort(recs.begin(), recs.end(), [](const auto& a, const auto& b) {
    return state_order(a.state) < state_order(b.state);
  });
  Certificate c;
  const std::string issued = options.issued.empty() ? records::today_utc() : options.issued;
  const std::string number = lab.certificate_number.empty()
                                 ? fmt::format("{}-{}", options.machine, options.date)
                                 : lab.certificate_number;
  const std::string visit = to == options.date ? options.date : options.date + " to " + to;
  c.title = "Calibration certificate " + number;
  c.meta = {
      {"certificate", number}, {"machine", options.machine}, {"visit", visit}, {"issued", issued}};
  if (!lab.name.empty()) c.meta.push_back({"laboratory", lab.name});

  // Who, what, where.
  report::Section head;
  head.title = "Certificate";
  head.table.push_back({"", ""});
  head.table.push_back({"certificate number", number});
  head.table.push_back({"issued", issued});
  if (!lab.name.empty())
    head.table.push_back(
        {"calibrated by", lab.name + (lab.address.empty() ? "" : ", " + lab.address)});
  if (!lab.accreditation.empty()) head.table.push_back({"accreditation", lab.accreditation});
  if (!lab.customer.empty())
    head.table.push_back(
        {"customer",
         lab.customer + (lab.customer_address.empty() ? "" : ", " + lab.customer_address)});
  head.table.push_back({"machine", options.machine});
  if (const auto m = lab.machines.find(options.machine); m != lab.machines.end()) {
    const auto& i = m->second;
    for (const auto& [k, v] : {std::pair{"description", i.description},
                               {"maker", i.maker},
                               {"model", i.model},
                               {"serial number", i.serial},
                               {"location", i.location}})
      if (!v.empty()) head.table.push_back({k, v});
  } else {
    c.warnings.push_back(fmt::format(
        "the laboratory file does not describe machine '{}' (maker, model, serial number)",
        options.machine));
  }
  head.table.push_back({"visit", visit});
  std::string operators;
  for (const auto& r : recs)
    if (!r.operator_name.empty() && operators.find(r.operator_name) == std::string::npos)
      operators += (operators.empty() ? "" : ", ") + r.operator_name;
  head.table.push_back({"measured by", operators.empty() ? "not stated" : operators});
  head.table.push_back({"tests", fmt::format("{} results (records {} … {})", recs.size(),
                                             recs.front().id, recs.back().id)});
  head.intro_html =
      "<p>The results below were measured on the machine named, on the dates of the visit, and "
      "are stored in its calibration records with the files they come from. Each figure is "
      "given with its expanded uncertainty U (coverage factor k = 2, about 95 %) where one can "
      "be stated, and the decision against its limit by the rule stated below.</p>";
  c.sections.push_back(std::move(head));

  // Instruments.
  report::Section inst;
  inst.title = "Instruments and their calibration";
  inst.table.push_back(
      {"instrument", "description", "serial number", "certificate", "calibrated", "due"});
  std::vector<std::string> ids;
  for (const auto& r : recs)
    if (!r.instrument.empty() && std::find(ids.begin(), ids.end(), r.instrument) == ids.end())
      ids.push_back(r.instrument);
  for (const auto& id : ids) {
    const auto it = std::find_if(lab.instruments.begin(), lab.instruments.end(),
                                 [&](const Instrument& i) { return i.id == id; });
    if (it == lab.instruments.end()) {
      inst.table.push_back({id, "not described in the laboratory file", "", "", "", ""});
      c.warnings.push_back(fmt::format(
          "instrument '{}' is not described in the laboratory file: its calibration cannot be "
          "stated",
          id));
      continue;
    }
    inst.table.push_back({it->id, it->description, it->serial, it->certificate, it->calibrated,
                          it->due.empty() ? "not stated" : it->due});
    if (!it->due.empty() && records::day_number(it->due) < records::day_number(to))
      c.warnings.push_back(fmt::format(
          "instrument '{}' was due for calibration on {}, before this visit ended ({}): its "
          "results are not traceable as stated",
          it->id, it->due, to));
  }
  if (ids.empty()) {
    inst.intro_html = "<p>No record of this visit names its instrument.</p>";
    c.warnings.push_back("no record of this visit names the instrument it was measured with");
  }
  c.sections.push_back(std::move(inst));

  // Environment.
  report::Section env;
  env.title = "Environment";
  double tmin = INFINITY, tmax = -INFINITY;
  for (const auto& r : recs)
    if (r.temperature) {
      tmin = std::min(tmin, *r.temperature);
      tmax = std::max(tmax, *r.temperature);
    }
  env.table.push_back({"", ""});
  env.table.push_back({"temperature during the tests",
                       tmax >= tmin
                           ? (tmax - tmin < 0.05 ? fmt::format("{:.1f} °C", tmin)
                                                 : fmt::format("{:.1f} … {:.1f} °C", tmin, tmax))
                           : "not stated"});
  if (!lab.environment.empty()) env.table.push_back({"conditions", lab.environment});
  c.sections.push_back(std::move(env));

  // Results, by state, and the positioning budgets.
  std::vector<report::Section> budgets;
  bool any_found = false, any_left = false;
  for (const auto state : {records::State::AsFound, records::State::None, records::State::AsLeft}) {
    report::Section s;
    s.title = "Results " + state_title(state);
    s.table.push_back({"record", "test", "figure", "value", "U (k = 2)", "limit", "decision"});
    Tally count;
    for (const auto& r : recs) {
      if (r.state != state) continue;
      any_found = any_found || state == records::State::AsFound;
      any_left = any_left || state == records::State::AsLeft;
      const std::string content = db.content(r.id);
      std::optional<PositioningBudget> budget;
      PositioningFacts facts;
      if (r.kind == "positioning") {
        facts = positioning_facts(content);
        if (facts.length_mm > 0) {
          budget = positioning_budget(facts.length_mm,
                                      r.temperature ? r.temperature : facts.material_C, lab.laser);
          report::Section b;
          const std::string axis = r.figures.empty() ? "" : r.figures.front().axis;
          b.title = fmt::format("Uncertainty of positioning{} (record {}, {})",
                                axis.empty() ? "" : " on " + axis, r.id, to_string(r.state));
          b.references = {report::refs::kIso230_2, kIso230_9, kIso230_3, report::refs::kGum};
          b.table.push_back({"contribution", "source", "u (µm)", "in U(B), U(R)"});
          for (const auto& k : budget->contributions)
            b.table.push_back(
                {k.name, k.what, fmt::format("{:.3f}", k.u_um), k.in_B_R ? "yes" : "no"});
          b.intro_html = fmt::format(
              "<p>The contributions of ISO 230-2:2014 Annex A over the measured length, {:g} mm, "
              "combined by the root sum of squares (ISO/TR 230-9, GUM) and expanded with k = "
              "2. B and R compare readings at one target minutes apart: the terms that grow "
              "with the length are common to both and cancel, and only the environmental "
              "variation and the set-up remain.</p>",
              facts.length_mm);
          if (budget->U_EAM_um)
            b.table.push_back(
                {"U(E), U(A), U(M)", "k = 2", fmt::format("{:.2f}", *budget->U_EAM_um), ""});
          if (budget->U_BR_um)
            b.table.push_back({"U(B), U(R)", "k = 2", fmt::format("{:.2f}", *budget->U_BR_um), ""});
          if (!budget->not_estimated.empty())
            b.warnings.push_back("no expanded uncertainty: " + budget->not_estimated);
          budgets.push_back(std::move(b));
        }
      }
      for (const auto& f : r.figures) {
        Line l;
        l.record = r.id;
        l.kind = r.kind;
        l.state = to_string(r.state);
        l.figure = f.axis.empty() ? f.name : f.name + "@" + f.axis;
        l.unit = f.unit;
        l.value = f.value;
        if (budget && (f.name == "E" || f.name == "A" || f.name == "M")) {
          l.U = budget->U_EAM_um;
          l.U_source = "ISO/TR 230-9 budget";
        } else if (budget && (f.name == "B" || f.name == "R")) {
          l.U = budget->U_BR_um;
          l.U_source = "ISO/TR 230-9 budget";
        } else if (f.u) {
          l.U = 2 * *f.u;
          l.U_source = "the result's own";
        }
        if (const auto it = lab.limits.find(l.figure); it != lab.limits.end())
          l.limit = it->second;
        else if (const auto it2 = lab.limits.find(f.name); it2 != lab.limits.end())
          l.limit = it2->second;
        else if (const auto it3 = facts.tolerances.find(f.name); it3 != facts.tolerances.end())
          l.limit = it3->second;
        const auto own = own_verdict(r.kind, f.name, content);
        if (own && !l.limit) {
          l.decision = own->decision;
          l.limit = own->limit;
        } else if (l.limit) {
          l.decision = decide(l.value, l.U, *l.limit, lab.rule);
        } else {
          l.decision = "no limit stated";
        }
        count.add(l);
        s.table.push_back({fmt::format("{}", r.id), r.kind, l.figure, num(l.value) + " " + l.unit,
                           l.U ? fmt::format("{:.2g} {}", *l.U, l.unit) : "not stated",
                           l.limit ? fmt::format("{:g} {}", *l.limit, l.unit) : "none",
                           l.decision});
        c.lines.push_back(std::move(l));
      }
    }
    if (s.table.size() == 1) continue;
    s.summary = fmt::format("{} conform, {} do not, {} without a decision", count.conform,
                            count.fail, count.undecided);
    c.sections.push_back(std::move(s));
  }

  report::Section comp;
  comp.title = "Compensation and adjustment";
  comp.table.push_back({"", ""});
  comp.table.push_back({"applied between as found and as left",
                        lab.compensation.empty() ? "not stated" : lab.compensation});
  if (any_found && any_left && lab.compensation.empty())
    c.warnings.push_back(
        "the visit has results as found and as left, but the laboratory file does not say what "
        "was adjusted or compensated between them");
  c.sections.push_back(std::move(comp));
  for (auto& b : budgets) c.sections.push_back(std::move(b));

  report::Section rule;
  rule.title = "Decision rule";
  if (lab.rule == Rule::Iso14253) {
    rule.references = {kIso14253, report::refs::kGum};
    rule.intro_html =
        "<p>ISO 14253-1: conformity with an upper limit is proven when the value plus its "
        "expanded uncertainty U lies within the limit, nonconformity when the value minus U lies "
        "beyond it. Between the two no decision is given; nor is one without an uncertainty. "
        "CMM acceptance results carry their own decisions by the same rule against their MPE "
        "(ISO 10360).</p>";
  } else {
    rule.references = {kIlacG8};
    rule.intro_html =
        "<p>Simple acceptance (ILAC-G8, 4.2.1): a value within its limit conforms, whatever its "
        "uncertainty; the risk of a wrong decision is shared between the laboratory and the "
        "customer. The uncertainties are stated for the reader to judge that risk.</p>";
  }
  c.sections.push_back(std::move(rule));

  report::Section sig;
  sig.title = "Signatures";
  auto line = [](const std::string& role, const std::string& name) {
    return fmt::format(
        "<div class=\"signature\" style=\"display:inline-block;width:45%;margin:2.5em 4% 0 "
        "0\"><div style=\"border-bottom:1px solid #000;height:2.5em\"></div><p>{}: {}</p><p>date: "
        "</p></div>",
        report::escape(role), report::escape(name.empty() ? std::string("") : name));
  };
  sig.intro_html = line("performed by", lab.performed_by.empty() ? operators : lab.performed_by) +
                   line("approved by", lab.approved_by);
  c.sections.push_back(std::move(sig));
  if (!c.warnings.empty()) c.sections.front().warnings = c.warnings;
  return c;
}

std::string Certificate::html() const {
  return report::render(title, sections, 4000, meta);
}

}  // namespace trueaxis::certificate
