// trueaxis CLI — design data for scanning: 'design' (STEP sections or design.json -> design.json,
// with the scanning path of each section).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>

#include "commands.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/design/design.hpp"
#include "trueaxis/io/files.hpp"
#include "trueaxis/sim/part.hpp"

namespace trueaxis::cli {
namespace {

struct DesignArgs {
  std::string step, design, output, path_csv;
  std::vector<std::string> sections;
  design::PathOptions path;
  bool quiet = false;
};

struct SectionArg {
  design::StepSectionRequest request;
  design::ProbeOrientation probe;
};

// "origin=X,Y,Z;normal=I,J,K[;name=N][;probe=A<deg>B<deg>]" -> a section request, or a usage
// error.
SectionArg parse_section(const std::string& text, std::size_t index) {
  SectionArg arg;
  design::StepSectionRequest& r = arg.request;
  r.name = fmt::format("S{}", index + 1);
  bool origin = false, normal = false;
  std::stringstream ss(text);
  std::string part;
  auto triple = [&](const std::string& key, const std::string& v) {
    Eigen::Vector3d out;
    std::stringstream vs(v);
    std::string num;
    int k = 0;
    while (std::getline(vs, num, ',')) {
      if (k == 3)
        throw CLI::ValidationError(fmt::format("'{}': {} needs three numbers X,Y,Z", text, key));
      try {
        std::size_t used = 0;
        out[k] = std::stod(num, &used);
        if (used != num.size() || !std::isfinite(out[k])) throw std::invalid_argument(num);
      } catch (const std::exception&) {
        throw CLI::ValidationError(fmt::format("'{}': {} has '{}', not a number", text, key, num));
      }
      ++k;
    }
    if (k != 3)
      throw CLI::ValidationError(fmt::format("'{}': {} needs three numbers X,Y,Z", text, key));
    return out;
  };
  while (std::getline(ss, part, ';')) {
    const auto eq = part.find('=');
    const std::string key = part.substr(0, eq),
                      value = eq == std::string::npos ? "" : part.substr(eq + 1);
    if (key == "origin") {
      r.plane.origin = triple(key, value);
      origin = true;
    } else if (key == "normal") {
      r.plane.normal = triple(key, value);
      if (!(r.plane.normal.norm() > 0))
        throw CLI::ValidationError(fmt::format("'{}': the normal is zero", text));
      normal = true;
    } else if (key == "name" && !value.empty()) {
      r.name = value;
    } else if (key == "probe") {
      // A<deg>B<deg>, e.g. A90B-90
      double a = 0, b = 0;
      int used = 0;
      if (std::sscanf(value.c_str(), "A%lfB%lf%n", &a, &b, &used) != 2 ||
          used != static_cast<int>(value.size()))
        throw CLI::ValidationError(
            fmt::format("'{}': probe=A<degrees>B<degrees>, e.g. probe=A90B-90", text));
      arg.probe = {a, b};
      if (const std::string why = design::head_refusal(arg.probe); !why.empty())
        throw CLI::ValidationError(fmt::format("'{}': the probe head cannot take {}", text, why));
    } else {
      throw CLI::ValidationError(fmt::format(
          "'{}': expected origin=X,Y,Z;normal=I,J,K[;name=N][;probe=A<deg>B<deg>]", text));
    }
  }
  if (!origin || !normal)
    throw CLI::ValidationError(fmt::format("'{}': give both origin=X,Y,Z and normal=I,J,K", text));
  return arg;
}

// "37–100" (slowest and fastest segment), or "100" when all are equal.
std::string speeds(const design::ScanPath& p) {
  double lo = 1e300, hi = 0;
  for (const auto& g : p.segments) {
    lo = std::min(lo, g.speed);
    hi = std::max(hi, g.speed);
  }
  return std::round(lo) == std::round(hi) ? fmt::format("{:.0f}", hi)
                                          : fmt::format("{:.0f}–{:.0f}", lo, hi);
}

int run_design(const DesignArgs& a) {
  design::Design d;
  // What could not be made, one line each (planes that gave no section, sections with no path).
  std::vector<std::string> failed;
  if (!a.step.empty()) {
    std::vector<design::StepSectionRequest> req;
    std::map<std::string, design::ProbeOrientation> probes;
    for (std::size_t i = 0; i < a.sections.size(); ++i) {
      const SectionArg arg = parse_section(a.sections[i], i);
      req.push_back(arg.request);
      probes[arg.request.name] = arg.probe;
    }
    design::StepCut cut = design::cut_step(a.step, req);
    // Each contour of a plane is scanned with the plane's probe orientation.
    design::assign_probes(cut.design, probes);
    if (!a.quiet) {
      fmt::print("{}: {} solid{}; cut edges joined across gaps up to {:.4g} mm ({})\n", a.step,
                 cut.solids, cut.solids == 1 ? "" : "s", cut.join_tolerance,
                 cut.file_tolerance ? fmt::format("the file states {:.4g} mm", *cut.file_tolerance)
                                    : std::string("the file states no tolerance"));
      for (const auto& n : cut.notes) fmt::print("note: {}\n", n);
    }
    for (const auto& f : cut.failures)
      failed.push_back(fmt::format("section '{}': {}", f.name, f.reason));
    d = std::move(cut.design);
  } else {
    d = io::read_design(a.design);
  }
  std::string table =
      "section,segment,length_mm,speed_mm_s,curvature_1_mm,ax,ay,az,bx,by,bz,cx,cy,cz,dx,dy,dz\n";
  for (const auto& s : d.sections) {
    design::ScanPath p;
    try {
      p = design::make_path(s, a.path);
    } catch (const Error& e) {
      failed.push_back(e.what());
      continue;
    }
    if (!a.quiet)
      fmt::print(
          "{}: {} {} of {:.3f} mm, {}{}; scanning path {:.3f} mm in {} {} segments "
          "(chordal error {:.2g} µm), {:.1f} s at {} mm/s\n",
          s.name, s.closed ? "closed" : "open", s.space_curve() ? "space curve" : "contour",
          design::length(s),
          s.space_curve() ? "material behind its surface normals"
                          : fmt::format("material on the {}", design::to_string(s.material)),
          (s.joined_gap > 1e-7 ? fmt::format(", cut edges joined across {:.2g} mm", s.joined_gap)
                               : std::string()) +
              (s.probe.a_deg != 0 || s.probe.b_deg != 0
                   ? fmt::format(", probe at A{:g}° B{:g}°", s.probe.a_deg, s.probe.b_deg)
                   : std::string()),
          p.length(), p.segments.size(), s.space_curve() ? "straight" : "cubic",
          p.chordal_error * 1e3, p.nominal_time(), speeds(p));
    for (std::size_t i = 0; i < p.segments.size(); ++i) {
      const auto& g = p.segments[i];
      table += fmt::format("{},{},{:.9g},{:.6g},{:.6g}", s.name, i, g.length, g.speed, g.curvature);
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) table += fmt::format(",{:.12g}", g.coeff(r, c));
      table += '\n';
    }
  }
  if (!a.output.empty() && !d.sections.empty()) {
    io::write_design(a.output, d);
    if (!a.quiet) fmt::print("wrote {} ({} sections)\n", a.output, d.sections.size());
  }
  if (!a.path_csv.empty()) {
    io::write_text(a.path_csv, table);
    if (!a.quiet) fmt::print("wrote {}\n", a.path_csv);
  }
  for (const auto& f : failed) fmt::print(stderr, "trueaxis: error: {}\n", f);
  if (!failed.empty() && !a.output.empty())
    fmt::print(stderr, "trueaxis: {} of the requested sections could not be made{}\n",
               failed.size(),
               d.sections.empty() ? "; nothing written" : "; " + a.output + " holds the others");
  return failed.empty() ? 0 : 1;
}

struct PartArgs {
  std::string design, output;
  // Comma-separated numbers; CLI11 checks their count and that they are numbers.
  std::vector<double> scale_about, rotate, translate, scale_along;
  std::vector<std::string> bumps;
  double scale = 1, noise_um = 0;
  std::uint64_t seed = 1;
  bool quiet = false;
};

int run_simulate_part(const PartArgs& a) {
  sim::Part p;
  p.design = io::read_design(a.design);
  sim::PartDeviation& d = p.deviation;
  d.scale = a.scale;
  auto vec = [](const std::vector<double>& v) { return Eigen::Vector3d(v[0], v[1], v[2]); };
  if (!a.scale_about.empty()) {
    d.scale_about = vec(a.scale_about);
    d.scale_about_given = true;
  }
  if (!a.scale_along.empty()) {
    d.scale_direction = vec(a.scale_along);
    d.directional_scale = a.scale_along[3];
  }
  if (!a.rotate.empty()) d.rotation_deg = vec(a.rotate);
  if (!a.translate.empty()) d.translation = vec(a.translate);
  for (const auto& b : a.bumps) {
    // SECTION,ARC_MM,HEIGHT_MM,WIDTH_MM (the section name may itself hold no comma)
    std::vector<std::string> f;
    std::stringstream ss(b);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (f.size() != 4)
      throw CLI::ValidationError("--bump",
                                 fmt::format("'{}': give SECTION,ARC_MM,HEIGHT_MM,WIDTH_MM", b));
    sim::Bump bump;
    bump.section = f[0];
    try {
      bump.arc = std::stod(f[1]);
      bump.height = std::stod(f[2]);
      bump.width = std::stod(f[3]);
    } catch (const std::exception&) {
      throw CLI::ValidationError("--bump",
                                 fmt::format("'{}': arc, height and width are numbers (mm)", b));
    }
    d.bumps.push_back(bump);
  }
  d.noise = a.noise_um * 1e-3;
  d.seed = a.seed;
  p.validate();
  io::write_part(a.output, p);
  if (!a.quiet) {
    const Eigen::Affine3d T = sim::transform(p);
    const std::string along =
        d.directional_scale != 1
            ? fmt::format(" × {:g} along ({:g}, {:g}, {:g})", d.directional_scale,
                          d.scale_direction.x(), d.scale_direction.y(), d.scale_direction.z())
            : "";
    fmt::print(
        "part of {} sections: scale {:g}{}, rotation ({:g}, {:g}, {:g})°, translation ({:g}, "
        "{:g}, {:g}) mm, {} bumps, form noise {:g} µm; the design's centroid moves by "
        "{:.4f} mm -> {}\n",
        p.design.sections.size(), d.scale, along, d.rotation_deg.x(), d.rotation_deg.y(),
        d.rotation_deg.z(), d.translation.x(), d.translation.y(), d.translation.z(), d.bumps.size(),
        a.noise_um, (T * sim::centroid(p.design) - sim::centroid(p.design)).norm(), a.output);
  }
  return 0;
}

Command simulate_part(CLI::App& simulate) {
  auto a = std::make_shared<PartArgs>();
  auto* c = simulate.add_subcommand(
      "part",
      "A part that differs from its design, for scanning: scaled, rotated, moved, with bumps and "
      "form noise. Writes part.json (the design and the deviations).\n"
      "Example: trueaxis simulate part --design design.json --translate 2,0,0 --bump "
      "mid.1,150,0.5,20 --seed 1 -o part.json");
  c->add_option("--design", a->design, "design.json of the part")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--scale", a->scale, "uniform scale factor (about --scale-about)")
      ->capture_default_str();
  c->add_option("--scale-about", a->scale_about,
                "X,Y,Z: centre of scaling (mm; default: the design's centroid)")
      ->delimiter(',')
      ->expected(3);
  c->add_option("--scale-along", a->scale_along,
                "I,J,K,FACTOR: a further scale along one direction")
      ->delimiter(',')
      ->expected(4);
  c->add_option("--rotate", a->rotate,
                "AX,AY,AZ: rotation (degrees) about x, y, z at the design's centroid")
      ->delimiter(',')
      ->expected(3);
  c->add_option("--translate", a->translate, "DX,DY,DZ: translation (mm)")
      ->delimiter(',')
      ->expected(3);
  c->add_option("--bump", a->bumps,
                "SECTION,ARC_MM,HEIGHT_MM,WIDTH_MM: a smooth bump along the outward normal "
                "centred at that arc length (negative height: a dent); repeatable");
  c->add_option("--noise", a->noise_um, "form noise along the normal, standard deviation (µm)")
      ->capture_default_str();
  c->add_option("--seed", a->seed, "random seed of the form noise")->capture_default_str();
  c->add_option("--output,-o", a->output, "part.json to write")->required();
  c->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  return {c, [a] { return run_simulate_part(*a); }};
}

}  // namespace

std::vector<Command> add_design_commands(CLI::App& app, CLI::App& simulate) {
  auto a = std::make_shared<DesignArgs>();
  auto* c = app.add_subcommand(
      "design",
      "Design data for scanning: cut a STEP part with planes into section contours (or check a "
      "hand-written design.json), and compute each section's scanning path: the contour offset "
      "by the tip radius less the pushing amount, as cubic segments with a speed from curvature.\n"
      "Examples:\n"
      "  trueaxis design --step part.stp --section \"origin=0,0,25;normal=0,0,1\" -o design.json\n"
      "  trueaxis design --design design.json --tip-radius 1.5 --path path.csv");
  auto* step = c->add_option("--step", a->step, "STEP file (AP203/AP214) of the part (mm)")
                   ->check(cli::existing_file());
  auto* des = c->add_option("--design", a->design, "design.json to check and convert instead")
                  ->check(cli::existing_file());
  step->excludes(des);
  c->add_option("--section", a->sections,
                "a cutting plane \"origin=X,Y,Z;normal=I,J,K[;name=N][;probe=A<deg>B<deg>]\" (mm; "
                "repeat for more sections). A plane that cuts several contours gives sections "
                "N.1, N.2, ... (longest first). probe: the orientation of the probe head for "
                "its contours, e.g. probe=A90B-90 (default: the stylus vertical)")
      ->needs(step)
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            try {
              parse_section(v, 0);
            } catch (const CLI::ValidationError& e) {
              return e.what();
            }
            return {};
          },
          "PLANE"));
  c->add_option("--output,-o", a->output, "design.json to write");
  c->add_option("--path", a->path_csv,
                "CSV of the scanning paths' cubic segments: p(u) = a + b u + c u² + d u³, "
                "u in [0, 1] (mm), with length, speed and curvature");
  c->add_option("--tip-radius", a->path.tip_radius, "stylus tip radius (mm)")
      ->capture_default_str();
  c->add_option("--pushing", a->path.pushing, "pushing amount: probe deflection on the path (mm)")
      ->capture_default_str();
  c->add_option("--chordal-tolerance", a->path.chordal_tolerance,
                "largest distance of the cubic segments from the exact path (mm)")
      ->capture_default_str();
  c->add_option("--max-speed", a->path.max_speed, "scanning speed on straight parts (mm/s)")
      ->capture_default_str();
  c->add_option("--max-acceleration", a->path.max_normal_acceleration,
                "largest v²/R on curves, which sets their speed (mm/s²)")
      ->capture_default_str();
  c->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  return {{c,
           [a] {
             if (a->step.empty() == a->design.empty())
               throw CLI::ValidationError("give --step FILE with --section, or --design FILE");
             if (!a->step.empty() && a->sections.empty())
               throw CLI::ValidationError("--step needs at least one --section");
             a->path.min_speed = std::min(a->path.min_speed, a->path.max_speed);
             try {
               a->path.validate();
             } catch (const Error& e) {
               throw CLI::ValidationError(e.what());
             }
             return run_design(*a);
           }},
          simulate_part(simulate)};
}

}  // namespace trueaxis::cli
