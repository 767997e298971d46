// trueaxis CLI — machine records: 'record add|machines|list|show|export' on the records database.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cctype>
#include <cmath>
#include <memory>

#include "commands.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/files.hpp"
#include "trueaxis/records/records.hpp"
#include "trueaxis/report/records.hpp"

namespace trueaxis::cli {
namespace {

struct RecordArgs {
  std::string db;
  // add
  std::vector<std::string> files;
  records::AddOptions add;
  bool as_found = false, as_left = false;
  double temperature = NAN;
  // list, export
  records::ListFilter filter;
  std::string output, format = "json";
  long long id = 0;
  bool quiet = false;
  // trend
  std::string figure, axis, plane, report, points = "auto";
  double tolerance = NAN;
  // due
  records::DueOptions due;
  std::vector<std::string> limits;
};

std::string figures_text(const records::Record& r) {
  std::string s;
  for (const auto& f : r.figures) {
    s += fmt::format("{}{}{} {:.3g}{}{}", s.empty() ? "" : ", ", f.name,
                     f.axis.empty() ? "" : "@" + f.axis, f.value,
                     f.u ? fmt::format(" ± {:.2g}", *f.u) : std::string(), " " + f.unit);
  }
  return s.empty() ? "no headline figure" : s;
}

int run_add(RecordArgs& a) {
  if (a.as_found && a.as_left)
    throw CLI::ValidationError("--as-found", "a result is as found or as left, not both");
  a.add.state = a.as_found  ? records::State::AsFound
                : a.as_left ? records::State::AsLeft
                            : records::State::None;
  if (!std::isnan(a.temperature)) a.add.temperature = a.temperature;
  records::Database db(records::database_path(a.db));
  for (const auto& f : a.files) {
    const auto r = db.add(f, a.add);
    a.add.new_machine = false;  // registered by the first file
    if (!a.quiet)
      fmt::print("record {}: {} {} {}{} ({})\n", r.id, r.machine, r.date, r.kind,
                 r.state == records::State::None ? "" : std::string(" ") + to_string(r.state),
                 figures_text(r));
  }
  return 0;
}

int run_machines(const RecordArgs& a) {
  const records::Database db(records::database_path(a.db), records::Access::ReadOnly);
  const auto ms = db.machines();
  if (ms.empty()) fmt::print("no machine in {}\n", records::database_path(a.db));
  for (const auto& m : ms)
    fmt::print("{}: {} record{}{}\n", m.id, m.records, m.records == 1 ? "" : "s",
               m.records ? fmt::format(", {} … {}", m.first, m.last) : std::string());
  return 0;
}

int run_list(const RecordArgs& a) {
  const records::Database db(records::database_path(a.db), records::Access::ReadOnly);
  for (const auto& r : db.list(a.filter))
    fmt::print("{:>5}  {}  {}  {}{}  {}\n", r.id, r.date, r.machine, r.kind,
               r.state == records::State::None ? "" : std::string(" ") + to_string(r.state),
               figures_text(r));
  return 0;
}

int run_show(const RecordArgs& a) {
  const records::Database db(records::database_path(a.db), records::Access::ReadOnly);
  const auto r = db.show(a.id);
  fmt::print("record {}\n  machine: {}\n  date: {}\n  kind: {}\n  state: {}\n  file: {}\n", r.id,
             r.machine, r.date, r.kind,
             r.state == records::State::None ? "not stated" : to_string(r.state), r.file_name);
  if (!r.operator_name.empty()) fmt::print("  operator: {}\n", r.operator_name);
  if (!r.instrument.empty()) fmt::print("  instrument: {}\n", r.instrument);
  if (r.temperature) fmt::print("  temperature: {:g} °C\n", *r.temperature);
  if (!r.note.empty()) fmt::print("  note: {}\n", r.note);
  fmt::print("  trueaxis: {}\n  figures: {}\n", r.trueaxis_version, figures_text(r));
  if (!a.output.empty()) {
    io::write_text(a.output, db.content(r.id));
    fmt::print("  the stored file -> {}\n", a.output);
  }
  return 0;
}

int run_export(const RecordArgs& a) {
  const records::Database db(records::database_path(a.db), records::Access::ReadOnly);
  const auto rs = db.list(a.filter);
  const std::string text = a.format == "csv" ? records::to_csv(rs) : records::to_json(rs);
  io::write_text(a.output, text);
  if (!a.quiet) fmt::print("{} records -> {}\n", rs.size(), a.output);
  return 0;
}

int run_trend(const RecordArgs& a) {
  const records::Database db(records::database_path(a.db), records::Access::ReadOnly);
  std::string axis = a.plane.empty() ? a.axis : a.plane;
  for (char& c : axis) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  records::TrendOptions o;
  if (!std::isnan(a.tolerance)) o.tolerance = a.tolerance;
  o.use = records::TrendOptions::use_of(a.points);
  const auto t = db.trend(a.filter.machine, a.figure, axis, o);
  if (!a.output.empty()) io::write_text(a.output, records::to_json(t, a.filter.machine));
  if (!a.report.empty())
    report::write(a.report,
                  report::render(fmt::format("{}: {} history", a.filter.machine, t.figure),
                                 {report::trend_section(t, a.filter.machine, o.tolerance)}, 4000,
                                 {{"machine", a.filter.machine}, {"records", db.describe()}}));
  if (!a.quiet)
    fmt::print("{}: {}{}{}\n", a.filter.machine, t.summary(),
               a.output.empty() ? std::string() : " -> " + a.output,
               a.report.empty() ? std::string() : " -> " + a.report);
  return 0;
}

// Every figure of one machine: its history, drift and, where a --limit names it, the date the
// trend reaches it; one section each.
int run_report(RecordArgs& a) {
  const records::Database db(records::database_path(a.db), records::Access::ReadOnly);
  std::vector<records::Limit> limits;
  for (const auto& l : a.limits) limits.push_back(records::Limit::parse(l));
  std::vector<report::Section> sections;
  int resolved = 0;
  for (const auto& [name, axis] : db.figures(a.filter.machine)) {
    records::TrendOptions o;
    o.use = records::TrendOptions::use_of(a.points);
    for (const auto& l : limits)
      if (l.applies_to(name, axis)) o.tolerance = l.value;
    const auto t = db.trend(a.filter.machine, name, axis, o);
    resolved += t.drift_per_year.has_value();
    sections.push_back(report::trend_section(t, a.filter.machine, o.tolerance));
  }
  if (sections.empty())
    throw Error(fmt::format("machine '{}' has no records in {}", a.filter.machine, db.describe()));
  io::write_text(a.report,
                 report::render(fmt::format("{}: calibration history", a.filter.machine), sections,
                                4000, {{"machine", a.filter.machine}, {"records", db.describe()}}));
  if (!a.quiet)
    fmt::print("{}: {} figures, {} with a drift -> {}\n", a.filter.machine, sections.size(),
               resolved, a.report);
  return 0;
}

int run_due(RecordArgs& a) {
  const records::Database db(records::database_path(a.db), records::Access::ReadOnly);
  for (const auto& l : a.limits) a.due.limits.push_back(records::Limit::parse(l));
  a.due.machine = a.filter.machine;
  const auto due = records::due_dates(db, a.due);
  if (!a.output.empty()) io::write_text(a.output, records::to_json(due));
  if (a.quiet) return 0;
  if (due.empty()) fmt::print("no machine with records in {}\n", records::database_path(a.db));
  for (const auto& d : due) {
    fmt::print("{}  {}{}  {}  (last visit {}): {}\n", d.due,
               d.u_days ? fmt::format("± {:.0f} d  ", *d.u_days) : std::string(),
               d.overdue ? "OVERDUE" : "due", d.machine, d.last_visit, d.because);
    for (const auto& n : d.notes) fmt::print("      {}\n", n);
  }
  if (!a.output.empty()) fmt::print("-> {}\n", a.output);
  return 0;
}

void add_points(CLI::App* c, RecordArgs& a) {
  c->add_option("--points", a.points,
                "the points fitted: as-found, as-left, all, or auto (as found when the history "
                "has as-found and as-left points, else all)")
      ->check(CLI::IsMember({"auto", "as-found", "as-left", "all"}))
      ->capture_default_str();
}

void add_limits(CLI::App* c, RecordArgs& a) {
  c->add_option("--limit", a.limits,
                "a figure's upper limit in its unit: A=25 (every axis), A@X=20, G_ccw@XY=15 "
                "(repeatable)");
}

void add_db(CLI::App* c, RecordArgs& a) {
  c->add_option("--db", a.db,
                "the records: an SQLite file, or postgresql://[user@]host[:port]/dbname (default: "
                "$TRUEAXIS_DB, else trueaxis-records.db here)");
}

void add_filter(CLI::App* c, RecordArgs& a) {
  c->add_option("--machine", a.filter.machine, "only this machine's records");
  c->add_option("--kind", a.filter.kind, "only results of this kind (positioning, circular, ...)");
  c->add_option("--from", a.filter.from, "only from this date (ISO 8601)");
  c->add_option("--to", a.filter.to, "only up to this date, inclusive (ISO 8601)");
}

}  // namespace

std::vector<Command> add_record_commands(CLI::App& app) {
  auto* group = app.add_subcommand(
      "record",
      "Machine records: every result stored with its machine, date, state (as found, as left), "
      "operator and instrument, in an SQLite database (--db, $TRUEAXIS_DB or "
      "trueaxis-records.db) or on a PostgreSQL server (--db postgresql://host/dbname).");
  group->require_subcommand(1);
  auto a = std::make_shared<RecordArgs>();
  auto* add = group->add_subcommand(
      "add",
      "Store result files (any JSON result trueaxis writes) with their headline figures.\n"
      "Example: trueaxis record add positioning.json --machine VMC-3 --date 2026-11-29 "
      "--as-found --axis X --new-machine");
  add_db(add, *a);
  add->add_option("files", a->files, "result JSON files")->required()->check(existing_file());
  add->add_option("--machine", a->add.machine, "the machine's id")->required();
  add->add_option("--date", a->add.date, "when it was measured, ISO 8601 (default: today)");
  add->add_flag("--as-found", a->as_found, "measured before any adjustment");
  add->add_flag("--as-left", a->as_left, "measured after adjustment or compensation");
  add->add_option("--operator", a->add.operator_name, "who measured");
  add->add_option("--instrument", a->add.instrument, "the instrument's id (laser, ball bar, ...)");
  add->add_option("--temperature", a->temperature, "°C during the test");
  add->add_option("--note", a->add.note, "free text");
  add->add_option("--axis", a->add.axis,
                  "the axis the result is of, when the file does not say (positioning)")
      ->check(machine_axis());
  add->add_flag("--new-machine", a->add.new_machine, "register the machine if it is not known");
  add->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  auto* machines = group->add_subcommand("machines", "The machines and their records' dates.");
  add_db(machines, *a);
  auto* list = group->add_subcommand("list", "The records, one a line, with their figures.");
  add_db(list, *a);
  add_filter(list, *a);
  auto* show = group->add_subcommand("show", "One record in full; -o writes the stored file back.");
  add_db(show, *a);
  show->add_option("id", a->id, "the record's number")->required();
  show->add_option("--output,-o", a->output, "write the stored result file here");
  auto* exp = group->add_subcommand(
      "export",
      "The records as a JSON array (or CSV, a row per figure), for a spreadsheet or a "
      "quality system.\nExample: trueaxis record export --machine VMC-3 -o records.json");
  add_db(exp, *a);
  add_filter(exp, *a);
  exp->add_option("--output,-o", a->output, "where to write")->required();
  exp->add_option("--format", a->format, "json or csv")
      ->check(CLI::IsMember({"json", "csv"}))
      ->capture_default_str();
  exp->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  auto* trend = group->add_subcommand(
      "trend",
      "One figure's history on a machine, its drift per year with its uncertainty (the figures' "
      "own u and their scatter) and the date it reaches --tolerance.\nExample: trueaxis record "
      "trend --machine VMC-3 --figure A --axis X --tolerance 25 -o trend.json");
  add_db(trend, *a);
  trend->add_option("--machine", a->filter.machine, "the machine's id")->required();
  trend->add_option("--figure", a->figure, "the figure's name (A, E0, G_ccw, flatness, ...)")
      ->required();
  trend->add_option("--axis", a->axis, "its axis, when it has one (positioning, straightness)")
      ->check(machine_axis());
  trend->add_option("--plane", a->plane, "its plane, when it has one (circular): XY, YZ or ZX")
      ->check(CLI::IsMember({"XY", "YZ", "ZX"}, CLI::ignore_case))
      ->excludes("--axis");
  trend->add_option("--tolerance", a->tolerance,
                    "the figure's upper limit, in its unit: when the trend reaches it");
  add_points(trend, *a);
  trend->add_option("--output,-o", a->output, "trend.json");
  trend->add_option("--report", a->report,
                    "an HTML report: the history (as found, as left), the drift and its band, "
                    "the limit");
  trend->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  auto* due = group->add_subcommand(
      "due",
      "When each machine is next due: its last visit plus --interval, brought forward when a "
      "figure's trend reaches its --limit sooner (the trend's date and its u).\nExample: "
      "trueaxis record due --interval 12 --limit A=25 --limit E0=3.5");
  add_db(due, *a);
  due->add_option("--machine", a->filter.machine, "only this machine");
  due->add_option("--interval", a->due.interval_months,
                  "the longest time between two visits, in months")
      ->check(CLI::Range(1, 120))
      ->capture_default_str();
  add_limits(due, *a);
  due->add_option("--today", a->due.today, "the date that decides what is overdue (ISO 8601)");
  due->add_option("--output,-o", a->output, "due.json");
  due->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  auto* rep = group->add_subcommand(
      "report",
      "Every figure of one machine over time, in one HTML report: each history (as found, as "
      "left), its drift with its band, and the date it reaches its --limit.\nExample: trueaxis "
      "record report --machine VMC-3 --limit A=25 --limit B@X=6 -o history.html");
  add_db(rep, *a);
  rep->add_option("--machine", a->filter.machine, "the machine's id")->required();
  add_limits(rep, *a);
  add_points(rep, *a);
  rep->add_option("--output,-o", a->report, "the report, HTML")->required();
  rep->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  return {{add, [a] { return run_add(*a); }},           {rep, [a] { return run_report(*a); }},
          {due, [a] { return run_due(*a); }},           {trend, [a] { return run_trend(*a); }},
          {machines, [a] { return run_machines(*a); }}, {list, [a] { return run_list(*a); }},
          {show, [a] { return run_show(*a); }},         {exp, [a] { return run_export(*a); }}};
}

}  // namespace trueaxis::cli
