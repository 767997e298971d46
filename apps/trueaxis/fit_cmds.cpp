// trueaxis CLI — least-squares fits of geometric elements: 'fit line|plane|circle|sphere|...'.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <memory>

#include "commands.hpp"
#include "trueaxis/geometry/fit.hpp"
#include "trueaxis/io/geometry/points.hpp"

namespace trueaxis::cli {
namespace {

struct FitArgs {
  std::string input, output;
  bool zone = false, quiet = false;
  double point_u_um = NAN;  // the points' standard uncertainty along the normal
};

int run_fit(geometry::Element e, const FitArgs& a) {
  const Eigen::Matrix3Xd p = io::read_point_set(a.input);
  const geometry::Fit f = a.zone ? geometry::fit_min_zone(e, p) : geometry::fit(e, p);
  const geometry::Form form = geometry::form_of(f, a.point_u_um * 1e-3);
  io::write_fit(a.output, f, form);
  if (!a.quiet) {
    std::string size;
    const bool u = f.has_uncertainty;
    if (f.diameter > 0)
      size = u ? fmt::format(", diameter {:.9g} mm (u = {:.2g} mm)", f.diameter, f.u_diameter)
               : fmt::format(", diameter {:.9g} mm", f.diameter);
    if (e == geometry::Element::Cone)
      size = u ? fmt::format(", apex angle {:.9g} deg (u = {:.2g} deg)", f.apex_angle * 180 / M_PI,
                             f.u_apex_angle * 180 / M_PI)
               : fmt::format(", apex angle {:.9g} deg", f.apex_angle * 180 / M_PI);
    if (a.zone) size += fmt::format(", minimum zone {:.6g} mm", f.zone);
    fmt::print("{} {}fit to {} points{}: residual RMS {:.3g} mm, max {:.3g} mm -> {}\n",
               geometry::to_string(e), a.zone ? "minimum-zone " : "", p.cols(), size, f.rms, f.max,
               a.output);
    fmt::print("  {}\n", form.summary());
  }
  for (const auto& w : f.warnings) fmt::print(stderr, "trueaxis: warning: {}\n", w);
  return 0;
}

}  // namespace

std::vector<Command> add_fit_commands(CLI::App& app) {
  auto* fit = app.add_subcommand(
      "fit",
      "Least-squares (Gaussian, ISO 10360-6) fit of a geometric element to points, checked "
      "against NIST's reference data.\npoints: a NIST .ds file (count, then x y z per line) or a "
      "CSV with x,y,z columns (mm).\nExample: trueaxis fit sphere --input ball.ds --output "
      "fit.json");
  fit->require_subcommand(1);
  std::vector<Command> out;
  for (auto e : {geometry::Element::Line, geometry::Element::Plane, geometry::Element::Circle,
                 geometry::Element::Sphere, geometry::Element::Cylinder, geometry::Element::Cone}) {
    auto a = std::make_shared<FitArgs>();
    const char* what[] = {"a 3-D line (point, direction)",
                          "a plane (point, normal)",
                          "a circle: LS plane, then the circle in it (center, normal, diameter)",
                          "a sphere (center, diameter)",
                          "a cylinder (point on the axis, direction, diameter)",
                          "a cone (point on the axis, direction of opening, distance, apex angle)"};
    auto* c = fit->add_subcommand(geometry::to_string(e),
                                  fmt::format("Fit {}", what[static_cast<int>(e)]));
    c->add_option("--input,-i", a->input, "points: .ds or CSV with x,y,z (mm)")
        ->required()
        ->check(cli::existing_file());
    c->add_option("--output,-o", a->output, "fit JSON to write")->required();
    if (e == geometry::Element::Line || e == geometry::Element::Plane ||
        e == geometry::Element::Circle)
      c->add_flag("--zone", a->zone,
                  "minimum-zone (Chebyshev) fit instead of least squares: the middle of the "
                  "thinnest zone holding all points; fit.json gets its width as \"zone\"");
    c->add_option("--point-u", a->point_u_um,
                  "µm: the points' standard uncertainty along the surface normal (e.g. the CMM's "
                  "probing uncertainty); gives the form figure its expanded uncertainty")
        ->check(positive_number());
    c->add_flag("--quiet,-q", a->quiet, "print nothing on success");
    out.push_back({c, [e, a] { return run_fit(e, *a); }});
  }
  return out;
}

}  // namespace trueaxis::cli
