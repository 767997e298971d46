#include "trueaxis/io/separation/probes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <vector>

#include "../../common/memory.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/csv.hpp"

namespace trueaxis::io {
namespace {

std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

// A probe's offset written in its column name after '@' ("b@10", "b @ 10 mm"; mm): the offset,
// with `stem` the name before it; nullopt (stem = name) without '@'.
std::optional<double> offset_in_name(const std::string& name, std::string& stem) {
  const auto at = name.rfind('@');
  stem = name;
  if (at == std::string::npos) return std::nullopt;
  stem = trimmed(name.substr(0, at));
  std::string tail = trimmed(name.substr(at + 1));
  if (tail.size() > 2 && tail.compare(tail.size() - 2, 2, "mm") == 0)
    tail = trimmed(tail.substr(0, tail.size() - 2));
  char* end = nullptr;
  const double v = tail.empty() ? NAN : std::strtod(tail.c_str(), &end);
  if (tail.empty() || end != tail.c_str() + tail.size() || !std::isfinite(v))
    throw Error(fmt::format(
        "column '{}': the probe offset after '@' must be a number of mm (e.g. b@10)", name));
  return v;
}

}  // namespace

separation::ProbeData read_probes(const std::string& path, const ProbeReadOptions& opt) {
  CsvTable t = CsvTable::read(path);
  // Units may be written in the names ("x [mm]", "A (µm)", "pitch_urad"); values are read in mm
  // for x, µm for probes and µrad for the angle channel (see units.hpp).
  if (t.cols() < 1 || t.find("x", Unit::Millimetre) != 0)
    throw Error(fmt::format("{}first column must be 'x' (station position, mm), found '{}'",
                            t.where(-1, 0), t.cols() ? t.header()[0] : ""));
  int angle_col = -1;
  if (opt.angle_column) angle_col = t.require(*opt.angle_column, Unit::Microradian);
  std::vector<int> probe_cols;
  // Per probe column: the offset its name states ("b@10"), and the unit its stem states.
  std::vector<std::optional<double>> header_offsets;
  std::vector<std::optional<Unit>> stem_units;
  if (!opt.probe_columns.empty()) {
    // Named probes: exactly these columns, in this order; any other column is left alone.
    for (const std::string& name : opt.probe_columns) {
      // A probe is named as written, or by the stem of a name that states its offset ("b" for
      // "b@10").
      int c = t.find(name);
      for (int k = 1; c < 0 && k < static_cast<int>(t.cols()); ++k) {
        const std::string& h = t.header()[static_cast<std::size_t>(k)];
        const auto at = h.rfind('@');
        if (at != std::string::npos && trimmed(h.substr(0, at)) == name) c = k;
      }
      if (c < 0) c = t.require(name);  // throws, naming the file and the missing column
      if (c == 0 || c == angle_col)
        throw Error(fmt::format("{}column '{}' cannot be a probe (it is the {})", t.where(-1, c),
                                name, c == 0 ? "station position" : "angle channel"));
      for (int q : probe_cols)
        if (q == c) throw Error(fmt::format("--probes names column '{}' twice", name));
      std::string stem;
      const std::string& written = t.header()[static_cast<std::size_t>(c)];
      try {
        header_offsets.push_back(offset_in_name(written, stem));
      } catch (const Error& e) {
        throw Error(t.where(-1, c) + e.what());
      }
      if (header_offsets.back()) {
        stem_units.push_back(split_column_name(stem).unit);  // converted below
      } else {
        t.require(name, Unit::Micrometre);  // converts a column named with its unit
        stem_units.push_back(std::nullopt);
      }
      probe_cols.push_back(c);
    }
  } else {
    for (int c = 1; c < static_cast<int>(t.cols()); ++c) {
      if (c == angle_col) continue;
      // A column that reads as an angle channel is never taken for a probe silently: an angle
      // in µrad read as a displacement in µm would wreck the separation with no sign of it.
      const std::string& name = t.header()[static_cast<std::size_t>(c)];
      ColumnName split;
      std::string stem;
      try {
        header_offsets.push_back(offset_in_name(name, stem));
        split = split_column_name(stem);
      } catch (const Error& e) {
        throw Error(t.where(-1, c) + e.what());
      }
      const bool looks_angle = (split.unit && kind_of(*split.unit) == UnitKind::Angle) ||
                               split.quantity == "angle" || split.quantity == "pitch" ||
                               split.quantity.find("angle") != std::string::npos;
      if (looks_angle)
        throw Error(fmt::format(
            "{}column '{}' looks like an angle channel, not a probe: give --angle {} to use it "
            "(µrad), or --probes to list the probe columns",
            t.where(-1, c), name, split.quantity));
      if (header_offsets.back()) {
        stem_units.push_back(split.unit);  // converted below: the name is not the stem
      } else {
        t.find(split.quantity, Unit::Micrometre);  // converts a column named with its unit
        stem_units.push_back(std::nullopt);
      }
      probe_cols.push_back(c);
    }
    if (!opt.offsets.empty() && probe_cols.size() > opt.offsets.size())
      throw Error(fmt::format(
          "{}unexpected column '{}': {} offsets were given for {} data columns; name the probe "
          "columns with --probes, or an angle channel with --angle",
          t.where(-1, probe_cols[opt.offsets.size()]),
          t.header()[static_cast<std::size_t>(probe_cols[opt.offsets.size()])], opt.offsets.size(),
          probe_cols.size()));
  }
  if (probe_cols.size() < 2)
    throw Error(fmt::format("{}need at least two probe columns after 'x', found {}", t.where(-1, 0),
                            probe_cols.size()));
  const long n = static_cast<long>(t.rows());
  if (n < opt.min_stations)
    throw Error(
        fmt::format("{}: too few stations: {} (need at least {})", path, n, opt.min_stations));
  const Eigen::VectorXd& x = t.column(0);
  const double h = (x[n - 1] - x[0]) / static_cast<double>(n - 1);
  for (long k = 1; k < n; ++k) {
    const double d = x[k] - x[k - 1];
    if (!(d > 0))
      throw Error(
          fmt::format("{}x = {} does not increase (previous {})", t.where(k, 0), x[k], x[k - 1]));
  }
  // Every step equal to the mean one, as in any valid file: nothing more to do. Otherwise the
  // message compares each step with the median spacing, so that one dropped reading is named where
  // it is (at the line after the gap), not as an uneven first step against a mean the gap shifted.
  const auto off_by = [](double d, double step) {
    return std::abs(d - step) > 1e-6 * step + 1e-12;
  };
  bool even = true;
  for (long k = 1; k < n && even; ++k) even = !off_by(x[k] - x[k - 1], h);
  if (!even) {
    std::vector<double> steps(static_cast<std::size_t>(n - 1));
    for (long k = 1; k < n; ++k) steps[static_cast<std::size_t>(k - 1)] = x[k] - x[k - 1];
    const auto mid = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
    std::nth_element(steps.begin(), mid, steps.end());
    const double step = *mid;
    for (long k = 1; k < n; ++k) {
      const double d = x[k] - x[k - 1];
      if (!off_by(d, step)) continue;
      const double m = std::round(d / step);
      if (m >= 2 && std::abs(d - m * step) <= 1e-6 * d + 1e-12)
        throw Error(fmt::format(
            "{}x jumps from {:.6g} to {:.6g} mm: {} station{} missing at a step of {:.6g} mm (a "
            "dropped reading? every station is needed, in order)",
            t.where(k, 0), x[k - 1], x[k], m - 1, m - 1 > 1 ? "s" : "", step));
      throw Error(
          fmt::format("{}uneven step: x goes from {:.6g} to {:.6g} mm ({:.6g} mm; the "
                      "step is {:.6g} mm elsewhere)",
                      t.where(k, 0), x[k - 1], x[k], d, step));
    }
  }
  // The data's arrays in huge pages where the kernel offers them (see common/memory.hpp).
  using trueaxis::detail::resize_in_huge_pages;
  separation::ProbeData d;
  resize_in_huge_pages(d.x, n, 1);
  d.x = x;
  // Offsets: from --offsets, or from the column names ("a@0,b@10,c@30"; the two must agree
  // when both are given), or else assumed 0, h, 2h, … and marked so.
  const auto stated = std::count_if(header_offsets.begin(), header_offsets.end(),
                                    [](const auto& o) { return o.has_value(); });
  if (stated > 0 && stated < static_cast<long>(probe_cols.size())) {
    const auto name_of = [&](std::size_t i) {
      return t.header()[static_cast<std::size_t>(probe_cols[i])];
    };
    std::size_t with = 0, without = 0;
    while (!header_offsets[with]) ++with;
    while (header_offsets[without]) ++without;
    throw Error(fmt::format(
        "{}column '{}' states no probe offset while others do ('{}'): write it as name@mm",
        t.where(-1, probe_cols[without]), name_of(without), name_of(with)));
  }
  std::vector<double> given = opt.offsets;
  if (stated > 0) {
    std::vector<double> named;
    for (const auto& o : header_offsets) named.push_back(*o);
    if (!given.empty()) {
      bool same = given.size() == named.size();
      for (std::size_t i = 0; same && i < named.size(); ++i)
        same = std::abs(given[i] - named[i]) <= 1e-9 * std::max(1.0, std::abs(named[i]));
      if (!same) {
        std::string a, b;
        for (double v : given) a += fmt::format("{}{:g}", a.empty() ? "" : ",", v);
        for (double v : named) b += fmt::format("{}{:g}", b.empty() ? "" : ",", v);
        throw Error(fmt::format(
            "{}the column names state the probe offsets {} mm, but --offsets says {}: which is "
            "right?",
            t.where(-1, probe_cols[0]), b, a));
      }
    }
    given = named;
  }
  if (given.empty()) {
    for (std::size_t i = 0; i < probe_cols.size(); ++i)
      d.offsets.push_back(static_cast<double>(i) * h);
    d.offsets_assumed = true;
  } else {
    if (given.size() != probe_cols.size())
      throw Error(fmt::format("{}{} probe columns but {} offsets given", t.where(-1, probe_cols[0]),
                              probe_cols.size(), given.size()));
    d.offsets = given;
    if (d.offsets[0] != 0)
      throw Error(
          fmt::format("offsets: the first offset must be 0 (probe A), got {}", d.offsets[0]));
    // Probes farther apart than the whole traverse never read one point twice: nothing can be
    // separated. It is what x in metres with offsets in mm looks like.
    const double reach = *std::max_element(d.offsets.begin(), d.offsets.end()) -
                         *std::min_element(d.offsets.begin(), d.offsets.end());
    const double span = x[n - 1] - x[0];
    if (reach >= span)
      throw Error(fmt::format(
          "{}x spans only {:.6g} mm but the probes are {:.6g} mm apart: no point of the "
          "workpiece is read by two probes. Is x in metres? Name the column 'x [m]' (or write "
          "millimetres)",
          t.where(-1, 0), span, reach));
    for (std::size_t i = 0; i < d.offsets.size(); ++i) {
      const double r = d.offsets[i] / h;
      if (std::abs(r - std::round(r)) > 1e-6 * std::max(1.0, std::abs(r)))
        throw Error(fmt::format(
            "offsets: probe '{}' at {} mm is not a whole multiple of the step {} mm (from {})",
            t.header()[static_cast<std::size_t>(probe_cols[i])], d.offsets[i], h, path));
      for (std::size_t j = 0; j < i; ++j)
        if (std::lround(d.offsets[j] / h) == std::lround(r))
          throw Error(fmt::format("offsets: probes '{}' and '{}' share the offset {} mm",
                                  t.header()[static_cast<std::size_t>(probe_cols[j])],
                                  t.header()[static_cast<std::size_t>(probe_cols[i])],
                                  d.offsets[i]));
    }
  }
  const double sign = opt.invert ? -1.0 : 1.0;
  resize_in_huge_pages(d.readings, n, static_cast<Eigen::Index>(probe_cols.size()));
  for (std::size_t i = 0; i < probe_cols.size(); ++i) {
    double unit = 1;  // a unit written in a stem before '@' ("a [nm]@10"), else µm already
    if (stem_units[i]) {
      if (kind_of(*stem_units[i]) != UnitKind::Length)
        throw Error(fmt::format(
            "{}probe column '{}': a probe reads a length, not {}", t.where(-1, probe_cols[i]),
            t.header()[static_cast<std::size_t>(probe_cols[i])], symbol(*stem_units[i])));
      unit = unit_factor(*stem_units[i], Unit::Micrometre);
    }
    d.readings.col(static_cast<Eigen::Index>(i)) = t.column(probe_cols[i]) * (unit * sign * 1e-3);
  }
  if (angle_col >= 0) {
    resize_in_huge_pages(d.angle, n, 1);
    d.angle = t.column(angle_col) * 1e-6;
  }
  return d;
}

void write_probes(const std::string& path, const separation::ProbeData& d,
                  const std::string& angle_column) {
  std::vector<std::string> header{"x"};
  std::vector<Eigen::VectorXd> cols;
  cols.reserve(static_cast<std::size_t>(d.readings.cols()) + 1);
  for (Eigen::Index i = 0; i < d.readings.cols(); ++i) {
    // Each probe's offset in its name ("b@10"), so the file says where its probes stood.
    const std::string name =
        i < 26 ? std::string(1, static_cast<char>('a' + i)) : fmt::format("p{}", i + 1);
    const auto k = static_cast<std::size_t>(i);
    header.push_back(k < d.offsets.size() ? fmt::format("{}@{:g}", name, d.offsets[k]) : name);
    cols.emplace_back(d.readings.col(i) * 1e3);
  }
  if (d.angle.size()) {
    header.push_back(angle_column);
    cols.emplace_back(d.angle * 1e6);
  }
  std::vector<const Eigen::VectorXd*> ptrs{&d.x};
  for (const auto& c : cols) ptrs.push_back(&c);
  write_csv(path, header, ptrs);
}

}  // namespace trueaxis::io
