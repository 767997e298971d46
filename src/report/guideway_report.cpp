#include <fmt/format.h>

#include "../common/figures.hpp"
#include "trueaxis/report/guideway.hpp"

namespace trueaxis::report {
namespace {

// A figure of error j (µm or µrad) to the resolution its PV's uncertainty supports.
std::string figure(const guideway::Result& r, std::size_t j, double v) {
  const double sc = j >= 2 ? 1e6 : 1e3;
  const char* unit = j >= 2 ? "µrad" : "µm";
  const std::optional<double> U = r.pv_U(j);
  return U ? fmt::format("{} {}", trueaxis::detail::rounded_to(v * sc, *U * sc), unit)
           : fmt::format("{:.4g} {}", v * sc, unit);
}

// The PV of error j as the table and the plot's title state it: "not resolved" when its
// uncertainty reaches it.
std::string pv_text(const guideway::Result& r, std::size_t j) {
  const std::optional<double> U = r.pv_U(j);
  return U && !*r.resolved(j) ? std::string("not resolved") : figure(r, j, r.pv[j]);
}

}  // namespace

Section guideway_section(const std::string& title, const guideway::Result& r,
                         const std::array<Eigen::VectorXd, guideway::kErrors>* truth) {
  Section s;
  s.title = title;
  s.references = {refs::kIso230, refs::kGum};
  s.intro_html = fmt::format(
      "<p>{} positions; condition number of the layout's observable part {:.3g}; {}.{}</p>",
      r.s.size(), r.layout.observable_condition_number,
      r.sigma > 0
          ? fmt::format("reading noise {} µm ({})", trueaxis::detail::two_digits(r.sigma * 1e3),
                        r.sigma_estimated ? "estimated from the residuals" : "given")
          : "no uncertainty is stated: " + escape(r.no_uncertainty),
      r.layout.message.empty() ? "" : " " + escape(r.layout.message) + ".");
  if (r.axis >= 0) {
    const auto n = guideway::iso_names(r.axis);
    s.intro_html += fmt::format(
        "<p>The carriage rides the machine's {} axis; its errors are named as ISO 230-1 names "
        "them, in the machine frame: {} and {} (horizontal and vertical straightness), {} "
        "(pitch), {} (yaw), {} (roll).</p>",
        "XYZ"[r.axis], n[0].name, n[1].name, n[2].name, n[3].name, n[4].name);
  }
  std::vector<std::string> head{"error", "observable", "PV", "RMS", "U of PV (95 %)", "u (1σ)"};
  if (truth) head.push_back("max |measured − true|");
  s.table.push_back(head);
  for (std::size_t j = 0; j < guideway::kErrors; ++j) {
    const bool angle = j >= 2;
    const double sc = angle ? 1e6 : 1e3;
    const char* unit = angle ? "µrad" : "µm";
    const bool have = r.value[j].size() > 0;
    std::vector<std::string> row{r.name(j), have ? "yes" : "no"};
    if (have) {
      // A PV the data cannot resolve is not shown as a number; figures to the resolution their
      // uncertainty supports.
      const std::optional<double> U = r.pv_U(j);
      row.push_back(pv_text(r, j));
      row.push_back(figure(r, j, r.rms[j]));
      row.push_back(U ? fmt::format("{} {}", trueaxis::detail::two_digits(*U * sc), unit)
                      : std::string("not stated"));
      row.push_back(
          U ? fmt::format("{} {}", trueaxis::detail::two_digits(r.uncertainty[j] * sc), unit)
            : std::string("-"));
      if (truth && (*truth)[j].size() == r.value[j].size())
        row.push_back(
            fmt::format("{:.3g} {}", (r.value[j] - (*truth)[j]).cwiseAbs().maxCoeff() * sc, unit));
    } else {
      row.insert(row.end(), {"-", "-", "-", "-"});
      if (truth) row.push_back("-");
    }
    s.table.push_back(row);
  }
  for (std::size_t j = 0; j < guideway::kErrors; ++j) {
    if (r.value[j].size() == 0) continue;
    const bool angle = j >= 2;
    const double sc = angle ? 1e6 : 1e3;
    Plot p;
    // On a machine axis: ISO 230-1's name, and the value in the machine frame it means.
    const double sg = r.sign(j);
    const char* carriage = j == 0 ? "δx" : j == 1 ? "δy" : j == 2 ? "εx" : j == 3 ? "εy" : "εz";
    p.title = r.axis < 0 ? fmt::format("{}{} ({})", guideway::kErrorNames[j],
                                       j < 2 ? " straightness" : "", carriage)
                         : fmt::format("{} {}{}", guideway::iso_names(r.axis)[j].name,
                                       guideway::kErrorNames[j], j < 2 ? " straightness" : "");
    p.x_label = r.axis < 0 ? "s (mm)" : fmt::format("{} (mm)", "XYZ"[r.axis]);
    p.y_label = fmt::format(
        "{} ({})",
        r.axis < 0 ? std::string(guideway::kErrorNames[j]) : guideway::iso_names(r.axis)[j].name,
        angle ? "µrad" : "µm");
    p.x = r.s;
    Eigen::VectorXd band;
    if (r.sigma > 0) band = Eigen::VectorXd::Constant(r.s.size(), r.uncertainty[j] * sc);
    // On a machine axis, the machine component's colour (component_colour), as in every plot.
    std::string colour;
    if (r.axis >= 0) {
      const std::string iso = guideway::iso_names(r.axis)[j].name;
      colour = component_colour(static_cast<int>(std::string("XYZABC").find(iso[1])));
    }
    p.series.push_back({"measured", r.value[j] * (sg * sc), band, colour, false});
    // Straightness is about the least-squares line (ISO 230-1): its PV and RMS are the profile's
    // distances from that line, which is drawn with it.
    const Eigen::VectorXd* straight = j == 0   ? &r.horizontal_straightness
                                      : j == 1 ? &r.vertical_straightness
                                               : nullptr;
    if (straight && straight->size() == r.value[j].size() && r.s.size() >= 2) {
      add_reference_lines(p, r.s, r.value[j], sg * sc);
      p.title += " — PV about the least-squares line " + pv_text(r, j);
    }
    if (truth && (*truth)[j].size() == r.value[j].size())
      p.series.push_back({"true", (*truth)[j] * (sg * sc), {}, "#9467bd", true});
    s.plots.push_back(std::move(p));
  }
  return s;
}

}  // namespace trueaxis::report
