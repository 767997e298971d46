#include <fmt/format.h>

#include "../common/figures.hpp"
#include "trueaxis/report/guideway.hpp"

namespace trueaxis::report {

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
  std::vector<std::string> head{"error", "observable", "PV", "RMS", "U of PV (95 %)", "u (1σ)"};
  if (truth) head.push_back("max |recovered − true|");
  s.table.push_back(head);
  for (std::size_t j = 0; j < guideway::kErrors; ++j) {
    const bool angle = j >= 2;
    const double sc = angle ? 1e6 : 1e3;
    const char* unit = angle ? "µrad" : "µm";
    const bool have = r.value[j].size() > 0;
    std::vector<std::string> row{guideway::kErrorNames[j], have ? "yes" : "no"};
    if (have) {
      // A PV the data cannot resolve is not shown as a number; figures to the resolution their
      // uncertainty supports.
      const std::optional<double> U = r.pv_U(j);
      const auto fig = [&](double v) {
        return U ? fmt::format("{} {}", trueaxis::detail::rounded_to(v * sc, *U * sc), unit)
                 : fmt::format("{:.4g} {}", v * sc, unit);
      };
      row.push_back(U && !*r.resolved(j) ? std::string("not resolved") : fig(r.pv[j]));
      row.push_back(fig(r.rms[j]));
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
    p.title = fmt::format("{}{}", guideway::kErrorNames[j],
                          j == 0   ? " straightness (δx)"
                          : j == 1 ? " straightness (δy)"
                          : j == 2 ? " (εx)"
                          : j == 3 ? " (εy)"
                                   : " (εz)");
    p.x_label = "s (mm)";
    p.y_label = fmt::format("{} ({})", guideway::kErrorNames[j], angle ? "µrad" : "µm");
    p.x = r.s;
    Eigen::VectorXd band;
    if (r.sigma > 0) band = Eigen::VectorXd::Constant(r.s.size(), r.uncertainty[j] * sc);
    p.series.push_back({"recovered", r.value[j] * sc, band, "", false});
    if (truth && (*truth)[j].size() == r.value[j].size())
      p.series.push_back({"true", (*truth)[j] * sc, {}, "#d62728", true});
    s.plots.push_back(std::move(p));
  }
  return s;
}

}  // namespace trueaxis::report
