// Python bindings for the machine records: trueaxis.records.open(db) and its add, machines,
// list and trend, returning lists of dicts (pandas.DataFrame(...) takes them as they are) and
// numpy arrays.
#include "trueaxis/records/records.hpp"

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <variant>

#include "bindings.hpp"
#include "trueaxis/certificate/certificate.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/report/html.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

py::object opt(const std::optional<double>& v) {
  return v ? py::object(py::float_(*v)) : py::none();
}

py::dict record_dict(const records::Record& r) {
  py::dict d;
  d["id"] = r.id;
  d["machine"] = r.machine;
  d["date"] = r.date;
  d["kind"] = r.kind;
  d["state"] = r.state == records::State::None ? py::object(py::none())
                                               : py::object(py::str(to_string(r.state)));
  d["operator"] = r.operator_name;
  d["instrument"] = r.instrument;
  d["temperature_C"] = opt(r.temperature);
  d["note"] = r.note;
  d["file"] = r.file_name;
  d["trueaxis_version"] = r.trueaxis_version;
  py::dict figures;
  for (const auto& f : r.figures) {
    py::dict one;
    one["value"] = f.value;
    one["u"] = opt(f.u);
    one["unit"] = f.unit;
    figures[py::str(f.axis.empty() ? f.name : f.name + "@" + f.axis)] = one;
  }
  d["figures"] = figures;
  return d;
}

records::State state_of(const std::optional<std::string>& s) {
  if (!s) return records::State::None;
  if (*s == "as-found") return records::State::AsFound;
  if (*s == "as-left") return records::State::AsLeft;
  throw Error(fmt::format("state '{}': 'as-found', 'as-left' or None", *s));
}

}  // namespace

void bind_records(py::module_& m) {
  auto sub = m.def_submodule(
      "records",
      "Machine records: every result stored with its machine, date, state, operator and "
      "instrument in an SQLite database, as 'trueaxis record'.");
  auto db_class =
      py::class_<records::Database, std::shared_ptr<records::Database>>(sub, "Database");
  db_class
      .def(
          "add",
          [](records::Database& db,
             const std::variant<std::string, std::vector<std::string>>& files,
             const std::string& machine, const std::optional<std::string>& date,
             const std::optional<std::string>& state, const std::string& operator_name,
             const std::string& instrument, std::optional<double> temperature,
             const std::string& note, const std::string& axis, bool new_machine) {
            records::AddOptions o;
            o.machine = machine;
            o.date = date.value_or("");
            o.state = state_of(state);
            o.operator_name = operator_name;
            o.instrument = instrument;
            o.temperature = temperature;
            o.note = note;
            o.axis = axis;
            o.new_machine = new_machine;
            std::vector<std::string> paths;
            if (const auto* one = std::get_if<std::string>(&files))
              paths.push_back(*one);
            else
              paths = std::get<std::vector<std::string>>(files);
            py::list out;
            for (const auto& p : paths) {
              out.append(record_dict(db.add(p, o)));
              o.new_machine = false;
            }
            return out;
          },
          py::arg("files"), py::kw_only(), py::arg("machine"), py::arg("date") = py::none(),
          py::arg("state") = py::none(), py::arg("operator") = "", py::arg("instrument") = "",
          py::arg("temperature") = py::none(), py::arg("note") = "", py::arg("axis") = "",
          py::arg("new_machine") = false,
          R"doc(Stores result files (a path or a list) for `machine`: date ISO 8601 (default today),
state 'as-found' or 'as-left', temperature in °C, axis for a result whose file does not name it.
Refuses a file that is not a trueaxis result, an unknown machine (unless new_machine) and a file
already stored for the machine. Returns the stored records as dicts.)doc")
      .def("machines",
           [](const records::Database& db) {
             py::list out;
             for (const auto& mm : db.machines()) {
               py::dict d;
               d["machine"] = mm.id;
               d["records"] = mm.records;
               d["first"] = mm.first;
               d["last"] = mm.last;
               out.append(d);
             }
             return out;
           })
      .def(
          "list",
          [](const records::Database& db, const std::string& machine, const std::string& kind,
             const std::string& since, const std::string& until) {
            records::ListFilter f;
            f.machine = machine;
            f.kind = kind;
            f.from = since;
            f.to = until;
            py::list out;
            for (const auto& r : db.list(f)) out.append(record_dict(r));
            return out;
          },
          py::kw_only(), py::arg("machine") = "", py::arg("kind") = "", py::arg("since") = "",
          py::arg("until") = "",
          "The records (dicts, oldest first), filtered by machine, kind and dates (inclusive).")
      .def(
          "trend",
          [](const records::Database& db, const std::string& machine, const std::string& figure,
             const std::string& axis, std::optional<double> tolerance, const std::string& points) {
            records::TrendOptions o;
            o.tolerance = tolerance;
            o.use = records::TrendOptions::use_of(points);
            const auto t = db.trend(machine, figure, axis, o);
            const auto n = static_cast<py::ssize_t>(t.points.size());
            py::array_t<double> value(n), u(n);
            py::list dates, states;
            for (py::ssize_t i = 0; i < n; ++i) {
              const auto& p = t.points[static_cast<std::size_t>(i)];
              value.mutable_at(i) = p.value;
              u.mutable_at(i) = p.u ? *p.u : NAN;
              dates.append(p.date);
              states.append(p.state == records::State::None
                                ? py::object(py::none())
                                : py::object(py::str(to_string(p.state))));
            }
            py::dict d;
            d["kind"] = "trend";
            d["machine"] = machine;
            d["figure"] = figure;
            d["axis"] = axis;
            d["unit"] = t.unit;
            d["dates"] = dates;
            d["values"] = value;
            d["u"] = u;
            d["states"] = states;
            d["drift_per_year"] = opt(t.drift_per_year);
            d["u_drift"] = opt(t.u_drift);
            d["due"] = t.due ? py::object(py::str(*t.due)) : py::none();
            d["u_due_days"] = opt(t.u_due_days);
            d["not_resolved"] = t.not_resolved;
            d["fitted_on"] = t.fitted_on;
            return d;
          },
          py::kw_only(), py::arg("machine"), py::arg("figure"), py::arg("axis") = "",
          py::arg("tolerance") = py::none(), py::arg("points") = "auto",
          R"doc(One figure's history on a machine and its drift per year: {'dates', 'values', 'u' (numpy,
NaN where not stated), 'states', 'drift_per_year', 'u_drift', 'due' (the date the trend reaches
`tolerance`, the figure's upper limit), 'u_due_days', 'not_resolved' (why a figure is None),
'fitted_on'}. points: which are fitted, 'as-found', 'as-left', 'all' or 'auto' (as found when the
history has as-found and as-left points: the machine drifts between adjustments).)doc")
      .def(
          "due",
          [](const records::Database& db, int interval_months, const py::dict& limits,
             const std::string& machine, const std::string& today) {
            records::DueOptions o;
            o.interval_months = interval_months;
            o.machine = machine;
            o.today = today;
            for (const auto& [k, v] : limits)
              o.limits.push_back(
                  records::Limit::parse(fmt::format("{}={}", py::str(k).cast<std::string>(),
                                                    fmt::format("{:.17g}", v.cast<double>()))));
            py::list out;
            for (const auto& d : records::due_dates(db, o)) {
              py::dict e;
              e["machine"] = d.machine;
              e["last_visit"] = d.last_visit;
              e["due"] = d.due;
              e["u_days"] = opt(d.u_days);
              e["because"] = d.because;
              e["overdue"] = d.overdue;
              e["notes"] = d.notes;
              out.append(e);
            }
            return out;
          },
          py::kw_only(), py::arg("interval_months") = 12, py::arg("limits") = py::dict(),
          py::arg("machine") = "", py::arg("today") = "",
          R"doc(When each machine is next due, soonest first: its last visit plus interval_months, or
earlier when a figure's trend reaches its limit ({'A': 25, 'A@X': 20, 'E0': 3.5}, in the figure's
unit). Dicts: 'machine', 'last_visit', 'due', 'u_days' (None unless a trend set the date),
'because', 'overdue', 'notes' (limits whose trend gave no date, and why).)doc");
  db_class.def(
      "certificate",
      [](const records::Database& db, const std::string& machine, const std::string& date,
         const std::string& to, const std::optional<std::string>& lab,
         const std::optional<std::string>& output, const std::string& issued) {
        const certificate::Lab l = lab ? certificate::read_lab(*lab) : certificate::Lab{};
        certificate::Options o;
        o.machine = machine;
        o.date = date;
        o.to = to;
        o.issued = issued;
        const auto c = certificate::make(db, l, o);
        if (output) report::write(*output, c.html());
        py::list lines;
        for (const auto& ln : c.lines) {
          py::dict d;
          d["record"] = ln.record;
          d["kind"] = ln.kind;
          d["state"] = ln.state;
          d["figure"] = ln.figure;
          d["value"] = ln.value;
          d["unit"] = ln.unit;
          d["U"] = opt(ln.U);
          d["limit"] = opt(ln.limit);
          d["decision"] = ln.decision;
          lines.append(d);
        }
        py::dict out;
        out["title"] = c.title;
        out["lines"] = lines;
        out["warnings"] = c.warnings;
        return out;
      },
      py::kw_only(), py::arg("machine"), py::arg("date"), py::arg("to") = "",
      py::arg("lab") = py::none(), py::arg("output") = py::none(), py::arg("issued") = "",
      R"doc(The calibration certificate of one visit (`date`, to `to` for several days): written as
HTML to `output` when given; returns {'title', 'lines': [{'record', 'kind', 'state', 'figure',
'value', 'unit', 'U' (k = 2, None when not stated), 'limit', 'decision'}], 'warnings'}. `lab`: the
laboratory's JSON (machine description, instruments, limits, decision rule, laser budget).)doc");
  sub.def(
      "open",
      [](const std::optional<std::string>& path, bool read_only) {
        return std::make_shared<records::Database>(
            records::database_path(path.value_or("")),
            read_only ? records::Access::ReadOnly : records::Access::ReadWrite);
      },
      py::arg("db") = py::none(), py::kw_only(), py::arg("read_only") = false,
      "Opens the records: `db` (an SQLite file, created when absent, or "
      "postgresql://[user@]host[:port]/dbname), else $TRUEAXIS_DB, else trueaxis-records.db in "
      "the working directory. read_only: nothing is written, a read-only file can be read.");
}

}  // namespace trueaxis::python
