#include "trueaxis/io/ballgauge/ballgauge.hpp"

#include <fmt/format.h>

#include <cmath>

#include "../grid_json.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/sim/machine.hpp"

namespace trueaxis::io {
namespace {

using ptr = JsonFile::pointer;
using ojson = nlohmann::ordered_json;
using detail::xyz;

Eigen::Vector3d triple(const JsonFile& f, const ptr& p) {
  const Eigen::VectorXd v = f.numbers(p);
  if (v.size() != 3) f.fail(p, fmt::format("'{}' needs [x, y, z] (mm)", dotted(p)));
  return v;
}

const char* alignment_name(ballgauge::Alignment a) {
  return a == ballgauge::Alignment::ThreeTwoOne    ? "321"
         : a == ballgauge::Alignment::LeastSquares ? "ls"
                                                   : "stitch";
}

}  // namespace

ballgauge::Gauge read_gauge(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  ballgauge::Gauge g;
  for (const auto& [key, value] : f.object(ptr()).items())
    if (key != "ball_diameter" && key != "balls" && key != "plate" && key != "frame")
      f.fail(ptr() / key,
             fmt::format("unknown key '{}' (ball_diameter, balls or plate, frame)", key));
  if (!f.has(ptr() / "ball_diameter")) f.fail(ptr(), "'ball_diameter' is missing");
  g.ball_diameter = f.number(ptr() / "ball_diameter");
  if (!(g.ball_diameter > 0)) f.fail(ptr() / "ball_diameter", "ball_diameter must be > 0 (mm)");
  const bool has_balls = f.has(ptr() / "balls"), has_plate = f.has(ptr() / "plate");
  if (has_balls && has_plate)
    f.fail(ptr() / "plate", "give the balls or a plate's layout, not both");
  if (!has_balls && !has_plate) f.fail(ptr(), "'balls' (or a 'plate' layout) is missing");
  ptr where = ptr() / "balls";
  if (has_balls) {
    const auto& balls = f.array(where);
    for (std::size_t i = 0; i < balls.size(); ++i) g.balls.push_back(triple(f, where / i));
  } else {
    // A ball plate: rows × columns balls at a pitch, numbered row by row from ball 0.
    where = ptr() / "plate";
    int count[2] = {0, 0};
    double pitch[2] = {0, 0};
    for (const auto& [key, value] : f.object(where).items()) {
      const ptr k = where / key;
      if (key == "rows" || key == "columns") {
        const double v = f.number(k);
        if (!(v >= 2 && v <= 100 && v == std::floor(v)))
          f.fail(k, fmt::format("{} must be a whole number from 2 to 100", key));
        count[key == "rows" ? 1 : 0] = static_cast<int>(v);
      } else if (key == "pitch") {
        const Eigen::VectorXd v =
            f.root().at(k).is_number() ? Eigen::VectorXd::Constant(1, f.number(k)) : f.numbers(k);
        if (v.size() != 1 && v.size() != 2)
          f.fail(k, "pitch is one number (mm) or [along a row, between rows] (mm)");
        pitch[0] = v[0];
        pitch[1] = v[v.size() - 1];
        if (!(pitch[0] > 0 && pitch[1] > 0)) f.fail(k, "pitch must be > 0 (mm)");
      } else {
        f.fail(k, fmt::format("unknown key '{}' (rows, columns, pitch)", key));
      }
    }
    if (count[0] == 0 || count[1] == 0 || pitch[0] == 0)
      f.fail(where, "a plate needs rows, columns and pitch");
    for (int j = 0; j < count[1]; ++j)
      for (int i = 0; i < count[0]; ++i) g.balls.emplace_back(pitch[0] * i, pitch[1] * j, 0.0);
  }
  if (f.has(ptr() / "frame")) {
    const Eigen::VectorXd v = f.numbers(ptr() / "frame");
    if (v.size() != 3) f.fail(ptr() / "frame", "frame names three balls: [origin, axis, plane]");
    for (Eigen::Index i = 0; i < 3; ++i) {
      if (!(v[i] >= 0 && v[i] < static_cast<double>(g.balls.size()) && v[i] == std::floor(v[i])))
        f.fail(ptr() / "frame" / static_cast<std::size_t>(i),
               fmt::format("frame ball {:g} is not a ball of the gauge (0..{})", v[i],
                           g.balls.size() - 1));
      g.frame.push_back(static_cast<int>(v[i]));
    }
  }
  try {
    g.validate();
  } catch (const Error& e) {
    f.fail(f.has(ptr() / "frame") ? ptr() / "frame" : where, e.what());
  }
  return g;
}

void write_gauge(const std::string& path, const ballgauge::Gauge& g) {
  ojson balls = ojson::array();
  for (const auto& b : g.balls) balls.push_back(xyz(b));
  ojson j{{"ball_diameter", g.ball_diameter}, {"balls", balls}};
  if (!g.frame.empty()) j["frame"] = g.frame;
  write_json(path, j);
}

std::vector<ballgauge::Placement> read_measurements(const std::string& path,
                                                    const ballgauge::Gauge* gauge) {
  const JsonFile f = JsonFile::read(path);
  for (const auto& [key, value] : f.object(ptr()).items())
    if (key != "placements") f.fail(ptr() / key, fmt::format("unknown key '{}' (placements)", key));
  if (!f.has(ptr() / "placements")) f.fail(ptr(), "'placements' is missing");
  const ptr pl = ptr() / "placements";
  std::vector<ballgauge::Placement> out;
  const auto& arr = f.array(pl);
  if (arr.empty()) f.fail(pl, "no placements");
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const ptr p = pl / i;
    ballgauge::Placement P;
    for (const auto& [key, value] : f.object(p).items()) {
      const ptr k = p / key;
      if (key == "name") {
        P.name = f.string(k);
      } else if (key == "alignment") {
        const std::string a = f.string(k);
        if (a == "321")
          P.alignment = ballgauge::Alignment::ThreeTwoOne;
        else if (a == "ls")
          P.alignment = ballgauge::Alignment::LeastSquares;
        else if (a == "stitch")
          P.alignment = ballgauge::Alignment::Stitch;
        else
          f.fail(k, fmt::format("alignment must be \"321\", \"ls\" or \"stitch\", not \"{}\"", a));
      } else if (key == "tip_radius") {
        P.tip_radius = f.number(k);
        if (P.tip_radius < 0) f.fail(k, "tip_radius must be >= 0 (mm)");
      } else if (key == "stylus_offset") {
        P.stylus_offset = triple(f, k);
      } else if (key == "balls") {
        const auto& balls = f.array(k);
        for (std::size_t b = 0; b < balls.size(); ++b) {
          const ptr bp = k / b;
          ballgauge::BallPoints B;
          bool has_index = false;
          for (const auto& [bk, bv] : f.object(bp).items()) {
            if (bk == "index") {
              const double v = f.number(bp / bk);
              if (v < 0 || v != std::floor(v))
                f.fail(bp / bk, "index must be a whole number >= 0 (a ball of gauge.json)");
              // The range is checked on the number, before it is converted (1e10 read as
              // "ball index -2147483648").
              if (v > 1e6 || (gauge && v >= static_cast<double>(gauge->balls.size())))
                f.fail(bp / bk, gauge ? fmt::format("ball index {:g} is not in the gauge (0..{})",
                                                    v, gauge->balls.size() - 1)
                                      : fmt::format("ball index {:g} is out of range", v));
              B.index = static_cast<int>(v);
              has_index = true;
              if (gauge && B.index >= static_cast<int>(gauge->balls.size()))
                f.fail(bp / bk, fmt::format("ball index {} is not in the gauge (0..{})", B.index,
                                            gauge->balls.size() - 1));
              for (const auto& other : P.balls)
                if (gauge && other.index == B.index)
                  f.fail(bp / bk,
                         fmt::format("ball {} is measured twice in this placement", B.index));
            } else if (bk == "points") {
              const auto& pts = f.array(bp / bk);
              B.points.resize(3, static_cast<Eigen::Index>(pts.size()));
              for (std::size_t q = 0; q < pts.size(); ++q)
                B.points.col(static_cast<Eigen::Index>(q)) = triple(f, bp / bk / q);
            } else if (bk == "centre" || bk == "center") {
              if (B.centre) f.fail(bp / bk, "the centre is given twice");
              B.centre = triple(f, bp / bk);
            } else if (bk == "u_um") {
              const Eigen::Vector3d u = triple(f, bp / bk);
              if (!(u.minCoeff() > 0))
                f.fail(bp / bk, "u_um (the centre's standard uncertainty, µm) must be > 0");
              B.centre_u = u * 1e-3;
            } else {
              f.fail(bp / bk, fmt::format("unknown key '{}' (index, points or centre, u_um)", bk));
            }
          }
          if (!has_index) f.fail(bp, "ball without an 'index'");
          if (B.centre && B.points.cols() > 0)
            f.fail(bp, "give the probed points or the fitted centre, not both");
          if (!B.centre && B.points.cols() == 0)
            f.fail(bp, "ball without 'points' (probed tip centres) or a 'centre'");
          if (!B.centre && f.has(bp / "u_um"))
            f.fail(bp / "u_um", "u_um belongs to a given centre; probed points give their own");
          P.balls.push_back(std::move(B));
        }
      } else {
        f.fail(k, fmt::format(
                      "unknown key '{}' (name, alignment, tip_radius, stylus_offset, balls)", key));
      }
    }
    if (P.name.empty()) P.name = fmt::format("placement {}", i);
    out.push_back(std::move(P));
  }
  return out;
}

void write_measurements(const std::string& path, const std::vector<ballgauge::Placement>& ps) {
  ojson arr = ojson::array();
  for (const auto& p : ps) {
    ojson balls = ojson::array();
    for (const auto& b : p.balls) {
      ojson pts = ojson::array();
      if (b.centre) {
        ojson ball{{"index", b.index}, {"centre", xyz(*b.centre)}};
        if (b.centre_u.allFinite()) ball["u_um"] = xyz(b.centre_u, 1e3);
        balls.push_back(ball);
        continue;
      }
      for (Eigen::Index q = 0; q < b.points.cols(); ++q) pts.push_back(xyz(b.points.col(q)));
      balls.push_back({{"index", b.index}, {"points", pts}});
    }
    ojson pl{
        {"name", p.name}, {"alignment", alignment_name(p.alignment)}, {"tip_radius", p.tip_radius}};
    if (p.stylus_offset) pl["stylus_offset"] = xyz(*p.stylus_offset);
    pl["balls"] = balls;
    arr.push_back(pl);
  }
  write_json(path, ojson{{"placements", arr}});
}

void write_ballgauge_map(const std::string& path, const ballgauge::Result& r) {
  ojson pts = ojson::array();
  bool stated = true;
  for (const auto& p : r.points) {
    const bool u = p.uncertainty.allFinite();
    stated = stated && u;
    pts.push_back({{"placement", p.placement},
                   {"frame", p.frame},
                   {"ball", p.ball},
                   {"nominal", xyz(p.nominal)},
                   {"measured", xyz(p.measured)},
                   {"error", xyz(p.error, 1e3)},
                   {"uncertainty", u ? xyz(p.uncertainty, 1e3) : ojson(nullptr)}});
  }
  ojson pl = ojson::array();
  for (const auto& p : r.placements)
    pl.push_back(
        {{"name", p.name},
         {"alignment", alignment_name(p.alignment)},
         {"frame", p.frame},
         {"balls", p.balls},
         {"shared", p.shared},
         {"given_centres", p.given_centres},
         {"registration_rms_um", p.registration_rms * 1e3},
         {"diameter_error_max_um",
          p.given_centres < p.balls ? ojson(p.diameter_error_max * 1e3) : ojson(nullptr)}});
  ojson j;
  j["kind"] = "ballgauge map";
  j["frame"] =
      "machine coordinates (mm); error = measured - true ball centre (µm); correct with X = x - "
      "error(x)";
  j["frames"] = r.frames;
  if (!stated)
    j["no_uncertainty"] =
        "some ball centres were given without their uncertainty: the errors that depend on them "
        "have none stated (null)";
  j["points"] = pts;
  j["placements"] = pl;
  if (r.grid) j["grid"] = detail::grid_json(*r.grid);
  write_json(path, j);
}

std::vector<ballgauge::LengthMeasurement> read_lengths(const std::string& path) {
  CsvTable t = CsvTable::read(path);
  const char* names[7] = {"x1", "y1", "z1", "x2", "y2", "z2", "nominal"};
  int c[7];
  for (int k = 0; k < 7; ++k) c[k] = t.require(names[k], Unit::Millimetre);
  if (t.rows() == 0) throw Error(fmt::format("{}: no lengths", path));
  std::vector<ballgauge::LengthMeasurement> out(t.rows());
  for (std::size_t i = 0; i < t.rows(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    auto& m = out[i];
    for (int k = 0; k < 3; ++k) {
      m.a[k] = t.column(c[k])[r];
      m.b[k] = t.column(c[k + 3])[r];
    }
    m.nominal = t.column(c[6])[r];
    if (!(m.nominal > 0))
      throw Error(fmt::format("{}nominal length {} mm: must be > 0", t.where(r, c[6]), m.nominal));
    if (!((m.b - m.a).norm() > 0))
      throw Error(fmt::format("{}the two end points coincide", t.where(r, c[3])));
  }
  return out;
}

void write_lengths(const std::string& path,
                   const std::vector<ballgauge::LengthMeasurement>& lengths) {
  const auto n = static_cast<Eigen::Index>(lengths.size());
  std::vector<Eigen::VectorXd> cols(7, Eigen::VectorXd(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& m = lengths[static_cast<std::size_t>(i)];
    for (int k = 0; k < 3; ++k) {
      cols[static_cast<std::size_t>(k)][i] = m.a[k];
      cols[static_cast<std::size_t>(k + 3)][i] = m.b[k];
    }
    cols[6][i] = m.nominal;
  }
  write_csv(path, {"x1", "y1", "z1", "x2", "y2", "z2", "nominal"},
            {&cols[0], &cols[1], &cols[2], &cols[3], &cols[4], &cols[5], &cols[6]});
}

std::vector<sim::Ball> read_balls(const std::string& path) {
  CsvTable t = CsvTable::read(path);
  const int c[4] = {t.require("x", Unit::Millimetre), t.require("y", Unit::Millimetre),
                    t.require("z", Unit::Millimetre), t.require("diameter", Unit::Millimetre)};
  if (t.rows() == 0) throw Error(fmt::format("{}: no balls", path));
  std::vector<sim::Ball> out(t.rows());
  for (std::size_t i = 0; i < t.rows(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    for (int k = 0; k < 3; ++k) out[i].centre[k] = t.column(c[k])[r];
    const double d = t.column(c[3])[r];
    if (!(d > 0))
      throw Error(fmt::format("{}ball diameter {} mm: must be > 0", t.where(r, c[3]), d));
    out[i].radius = d / 2;
  }
  return out;
}

void write_balls(const std::string& path, const std::vector<sim::Ball>& balls) {
  const auto n = static_cast<Eigen::Index>(balls.size());
  std::vector<Eigen::VectorXd> cols(4, Eigen::VectorXd(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& b = balls[static_cast<std::size_t>(i)];
    for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(k)][i] = b.centre[k];
    cols[3][i] = 2 * b.radius;
  }
  write_csv(path, {"x", "y", "z", "diameter"}, {&cols[0], &cols[1], &cols[2], &cols[3]});
}

void write_length_verification(const std::string& path,
                               const std::vector<ballgauge::LengthVerification>& results,
                               const ballgauge::Mpe* mpe) {
  auto stats = [](const ballgauge::LengthStats& s) {
    return ojson{{"min", s.min * 1e3},
                 {"max", s.max * 1e3},
                 {"range", s.range() * 1e3},
                 {"mean", s.mean * 1e3},
                 {"rms", s.rms * 1e3}};
  };
  auto num = [](double v) { return std::isfinite(v) ? ojson(v * 1e3) : ojson(nullptr); };
  ojson out = ojson::array();
  for (const auto& v : results) {
    ojson rows = ojson::array();
    for (const auto& r : v.rows) {
      rows.push_back({{"nominal", r.nominal},
                      {"position", r.position},
                      {"before", r.before * 1e3},
                      {"after", r.after * 1e3},
                      {"uncertainty", r.uncertainty * 1e3}});
      if (r.line >= 0) rows.back()["line"] = r.line;
    }
    out.push_back({{"correction", v.correction},
                   {"positions", v.positions},
                   {"lines",
                    [&] {
                      ojson l = ojson::array();
                      for (const auto& d : v.line_directions) l.push_back(xyz(d));
                      return l;
                    }()},
                   {"before", stats(v.before)},
                   {"after", stats(v.after)},
                   {"repeatability", num(v.repeatability)},
                   {"correction_uncertainty_rms", num(v.correction_u_rms)},
                   {"expected_after_rms", num(v.predicted_after)},
                   {"lengths", rows}});
  }
  ojson j{{"kind", "length verification"},
          {"units", "nominal in mm; length errors (measured - nominal) in µm"},
          {"results", out}};
  if (mpe && !results.empty()) {
    auto check = [&](const std::vector<ballgauge::LengthRow>& rows, bool after) {
      const auto c = ballgauge::check_mpe(rows, *mpe, after);
      return ojson{{"pass", c.pass()},
                   {"lengths", c.lengths},
                   {"beyond", c.failed},
                   {"worst_fraction_of_mpe", c.worst_ratio}};
    };
    ojson after = ojson::object();
    for (const auto& v : results) after[v.correction] = check(v.rows, true);
    j["e0"] = {{"mpe", mpe->text},
               {"before", check(results.front().rows, false)},
               {"after", after},
               {"rule", "every |E| <= MPE(L) (ISO 10360-2 simple acceptance)"}};
  }
  write_json(path, j);
}

void write_parametric(const std::string& path, const ballgauge::ParametricResult& r) {
  ojson j = machine_json(r.model);
  j["kind"] = "parametric model";
  ojson cov = ojson::array();
  for (Eigen::Index i = 0; i < r.covariance.rows(); ++i) {
    ojson row = ojson::array();
    for (Eigen::Index k = 0; k < r.covariance.cols(); ++k) row.push_back(r.covariance(i, k));
    cov.push_back(row);
  }
  ojson par = ojson::array();
  for (double v : r.parameters) par.push_back(v);
  ojson unobs = ojson::array();
  for (const auto& u : r.unobservable) unobs.push_back(u);
  j["identification"] = {
      {"method", "ball gauge, rigid-body model, linearised least squares"},
      {"degree", r.degree},
      {"centre", xyz(r.centre)},
      {"half_span", xyz(r.half_span)},
      {"parameters_units",
       "Chebyshev coefficients per error function (mm or rad), then EC0Y, EB0Z, EA0Z (rad)"},
      {"parameters", par},
      {"covariance", cov},
      {"residual_rms_um", r.residual_rms * 1e3},
      {"sigma_um", std::isfinite(r.sigma) ? ojson(r.sigma * 1e3) : ojson(nullptr)},
      {"balls", r.balls},
      {"placements", r.placements},
      {"unknowns", r.unknowns},
      {"rank", r.rank},
      {"iterations", r.iterations},
      {"unobservable", unobs}};
  ojson styli = ojson::array();
  for (const auto& st : r.styli)
    styli.push_back({{"offset", xyz(st.offset)}, {"placements", st.placements}});
  j["identification"]["styli"] = styli;
  // ISO 230-1 figures at the tool point, the other axes mid-span, with U (k = 2).
  ojson iso;
  const char* names[3][2] = {{"EYX", "EZX"}, {"EXY", "EZY"}, {"EXZ", "EYZ"}};
  ojson st, su;
  for (int k = 0; k < 3; ++k)
    for (int jj = 0; jj < 2; ++jj) {
      const auto K = static_cast<std::size_t>(k), J = static_cast<std::size_t>(jj);
      st[names[k][jj]] = r.iso.lines.straightness[K][J] * 1e3;
      su[names[k][jj]] = 2e3 * r.iso.u_straightness[K][J];
    }
  iso["meaning"] =
      "straightness about each axis' least-squares reference line and squareness as the angles "
      "between reference lines less 90 deg (ISO 230-1), of the tool point, the other axes "
      "mid-span; U expanded, k = 2, from the parameter covariance";
  iso["straightness_um"] = st;
  iso["straightness_U_um"] = su;
  iso["squareness_urad"] = {{"EC0Y", r.iso.lines.c0y * 1e6},
                            {"EB0Z", r.iso.lines.b0z * 1e6},
                            {"EA0Z", r.iso.lines.a0z * 1e6}};
  iso["squareness_U_urad"] = {
      {"EC0Y", 2e6 * r.iso.u_c0y}, {"EB0Z", 2e6 * r.iso.u_b0z}, {"EA0Z", 2e6 * r.iso.u_a0z}};
  j["identification"]["iso_230_1"] = iso;
  write_json(path, j);
}

ballgauge::ParametricResult read_parametric(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  ballgauge::ParametricResult r;
  const ptr id("/identification");
  if (!f.has(id))
    f.fail(ptr(),
           "not a parametric model: no 'identification' (write one with 'trueaxis ballgauge "
           "--parametric')");
  r.model = read_machine(f);
  f.object(id);
  const double degree = f.number(id / "degree");
  if (!(degree >= 1 && degree <= 8) || degree != std::floor(degree))
    f.fail(id / "degree", "degree must be a whole number 1..8");
  r.degree = static_cast<int>(degree);
  r.centre = triple(f, id / "centre");
  r.half_span = triple(f, id / "half_span");
  if (!(r.half_span.minCoeff() > 0)) f.fail(id / "half_span", "half spans must be > 0 mm");
  r.parameters = f.numbers(id / "parameters");
  const Eigen::Index P = 18 * (r.degree + 1) + 3;
  if (r.parameters.size() != P)
    f.fail(id / "parameters",
           fmt::format("{} parameters; degree {} needs {}", r.parameters.size(), r.degree, P));
  const auto& cov = f.array(id / "covariance");
  if (static_cast<Eigen::Index>(cov.size()) != P)
    f.fail(id / "covariance", fmt::format("covariance needs {} rows", P));
  r.covariance.resize(P, P);
  for (Eigen::Index i = 0; i < P; ++i) {
    const Eigen::VectorXd row = f.numbers(id / "covariance" / static_cast<std::size_t>(i));
    if (row.size() != P)
      f.fail(id / "covariance" / static_cast<std::size_t>(i),
             fmt::format("covariance row needs {} numbers", P));
    r.covariance.row(i) = row.transpose();
  }
  if (f.has(id / "residual_rms_um")) r.residual_rms = f.number(id / "residual_rms_um") * 1e-3;
  if (f.has(id / "sigma_um"))  // null: no redundancy, the noise level is unknown
    r.sigma = f.root().at(id / "sigma_um").is_null() ? NAN : f.number(id / "sigma_um") * 1e-3;
  if (f.has(id / "styli"))
    for (std::size_t i = 0; i < f.array(id / "styli").size(); ++i) {
      const ptr q = id / "styli" / i;
      ballgauge::ParametricResult::Stylus st;
      st.offset = triple(f, q / "offset");
      for (std::size_t k = 0; k < f.array(q / "placements").size(); ++k)
        st.placements.push_back(f.string(q / "placements" / k));
      r.styli.push_back(std::move(st));
    }
  r.iso = ballgauge::iso_figures(r);
  return r;
}

}  // namespace trueaxis::io
