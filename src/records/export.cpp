// The records as JSON or CSV (records.hpp).
#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "trueaxis/records/records.hpp"

namespace trueaxis::records {
namespace {

std::string figure_key(const Figure& f) {
  return f.axis.empty() ? f.name : f.name + "@" + f.axis;
}

// RFC 4180: a field with a comma, a quote or a line break is quoted, its quotes doubled.
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}

}  // namespace

std::string to_json(const std::vector<Record>& records) {
  using ojson = nlohmann::ordered_json;
  ojson a = ojson::array();
  for (const auto& r : records) {
    ojson figures = ojson::object();
    for (const auto& f : r.figures)
      figures[figure_key(f)] = {
          {"value", f.value}, {"u", f.u ? ojson(*f.u) : ojson(nullptr)}, {"unit", f.unit}};
    a.push_back({{"id", r.id},
                 {"machine", r.machine},
                 {"date", r.date},
                 {"kind", r.kind},
                 {"state", r.state == State::None ? ojson(nullptr) : ojson(to_string(r.state))},
                 {"operator", r.operator_name},
                 {"instrument", r.instrument},
                 {"temperature_C", r.temperature ? ojson(*r.temperature) : ojson(nullptr)},
                 {"note", r.note},
                 {"file", r.file_name},
                 {"trueaxis_version", r.trueaxis_version},
                 {"figures", figures}});
  }
  // Invalid UTF-8 in a note or a name is replaced, not refused: the export always completes.
  return a.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string to_csv(const std::vector<Record>& records) {
  std::string out =
      "id,machine,date,kind,state,operator,instrument,temperature_C,file,figure,axis,value,u,"
      "unit\n";
  for (const auto& r : records) {
    const std::string head = fmt::format(
        "{},{},{},{},{},{},{},{},{}", r.id, csv_field(r.machine), csv_field(r.date),
        csv_field(r.kind), to_string(r.state), csv_field(r.operator_name), csv_field(r.instrument),
        r.temperature ? fmt::format("{:g}", *r.temperature) : "", csv_field(r.file_name));
    if (r.figures.empty()) out += head + ",,,,,\n";
    for (const auto& f : r.figures)
      out += fmt::format("{},{},{},{:.17g},{},{}\n", head, csv_field(f.name), csv_field(f.axis),
                         f.value, f.u ? fmt::format("{:.17g}", *f.u) : "", csv_field(f.unit));
  }
  return out;
}

}  // namespace trueaxis::records
