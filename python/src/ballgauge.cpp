// Python bindings for the ball-gauge error map (Oya, Hokari, Tamura 1988): calibrate from
// gauge.json and measurements.json (or their contents), and correct points with the resulting grid.
#include "trueaxis/ballgauge/ballgauge.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <optional>
#include <variant>

#include "bindings.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/ballgauge/parametric.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/surface/space.hpp"
#include "trueaxis/sim/ballgauge.hpp"

namespace py = pybind11;

namespace trueaxis::python {

namespace {

// trueaxis.simulate_ballgauge: `trueaxis simulate ballgauge` in process (files as it writes them).
py::dict simulate_ballgauge(const sim::Machine& machine, const std::string& gauge,
                            const std::string& measurements, const std::string& plate, double pitch,
                            int placements, const std::vector<double>& origin, double misalignment,
                            const std::string& alignment, double noise, int points_per_ball,
                            double tip_radius, std::uint64_t seed, const std::string& lengths,
                            int repeats, std::optional<double> length_noise) {
  if (origin.size() != 3) throw Error("origin needs [x, y, z] (mm)");
  if (alignment != "321" && alignment != "ls")
    throw Error(fmt::format("alignment '{}': use '321' or 'ls'", alignment));
  sim::BallGaugeSetup setup;
  if (!plate.empty() && !sim::parse_plate(plate, setup))
    throw Error(fmt::format("plate '{}': give ROWSxCOLUMNS, e.g. '5x5' (2 to 100 each)", plate));
  setup.pitch = pitch;
  setup.placements = placements;
  setup.origin = {origin[0], origin[1], origin[2]};
  setup.misalignment = misalignment * 1e-6;
  setup.least_squares = alignment == "ls";
  sim::BallGaugeOptions o;
  o.noise = noise * 1e-3;
  o.points_per_ball = points_per_ball;
  o.tip_radius = tip_radius;
  o.seed = seed;
  const sim::BallGaugeLayout layout = sim::ballgauge_setup(machine, setup);
  sim::BallGaugeCampaign c;
  {
    py::gil_scoped_release release;
    c = sim::simulate_ballgauge(machine, layout.gauge, layout.poses, o);
  }
  io::write_gauge(gauge, layout.gauge);
  io::write_measurements(measurements, c.placements);
  const sim::BallGaugeTruth t = sim::ballgauge_truth(machine, c);
  py::dict truth;
  truth["placement"] = t.placement;
  truth["ball"] = t.ball;
  truth["centre"] = Eigen::MatrixXd(t.centre.transpose());
  truth["error"] = Eigen::MatrixXd(t.error.transpose() * 1e3);
  py::dict d;
  d["gauge"] = gauge;
  d["measurements"] = measurements;
  d["truth"] = truth;
  d["description"] = layout.description;
  d["lengths"] = py::none();
  if (!lengths.empty()) {
    sim::GaugeBlockOptions go = sim::held_out_blocks(machine, c);
    go.repeats = repeats;
    go.tip_radius = tip_radius;
    go.noise = length_noise.value_or(noise) * 1e-3;
    go.seed = seed + 1000;
    const auto gb = sim::simulate_gauge_blocks(machine, go);
    io::write_lengths(lengths, gb.lengths);
    d["lengths"] = lengths;
  }
  d["summary"] = fmt::format("{} placements of {} ({} points per ball, noise {:g} µm)",
                             c.placements.size(), layout.description, points_per_ball, noise);
  return d;
}

}  // namespace

void bind_ballgauge(py::module_& m) {
  m.def("simulate_ballgauge", &simulate_ballgauge, py::arg("machine"), py::kw_only(),
        py::arg("gauge") = "gauge.json", py::arg("measurements") = "measurements.json",
        py::arg("plate") = "", py::arg("pitch") = 100.0, py::arg("placements") = 3,
        py::arg("origin") = std::vector<double>{150, 120, 60}, py::arg("misalignment") = 4000.0,
        py::arg("alignment") = "321", py::arg("noise") = 0.0, py::arg("points_per_ball") = 10,
        py::arg("tip_radius") = 1.5, py::arg("seed") = 1, py::arg("lengths") = "",
        py::arg("repeats") = 3, py::arg("length_noise") = py::none(),
        R"doc(A ball-gauge campaign on the virtual CMM, as 'trueaxis simulate ballgauge' makes it.

machine: a trueaxis.Machine. The frame gauge (5 x 4 x 2 balls at 80 mm) in `placements` placements
stacked in z from `origin` (ball 0, mm), or plate='5x5' for a ball plate at `pitch` (mm) in its
placements in the machine's reach; each set down misaligned by `misalignment` (µrad); aligned
'321' or by least squares ('ls'). noise: probing noise (µm, per coordinate); tip_radius in mm.
Writes `gauge` and `measurements` (what trueaxis.ballgauge and trueaxis.identify read) and, with
lengths='lengths.csv', held-out gauge blocks in ISO 10360-2's seven positions (for
verify_lengths; their noise length_noise µm, default `noise`). Returns {'gauge', 'measurements',
'lengths' (paths; None without lengths), 'truth': {'placement', 'ball', 'centre' (mm),
'error' (µm): the machine's error at each probed ball}, 'description', 'summary'}.)doc");

  m.def(
      "ballgauge",
      [](const std::string& gauge, const std::string& measurements, double match_tolerance,
         long min_points, double outlier_tolerance, bool drop_outliers) {
        const auto g = io::read_gauge(gauge);
        const auto p = io::read_measurements(measurements, &g);
        ballgauge::Options o;
        o.match_tolerance = match_tolerance;
        o.min_points = min_points;
        o.outlier_tolerance = outlier_tolerance;
        o.drop_outliers = drop_outliers;
        ballgauge::Result r;
        try {
          py::gil_scoped_release release;
          r = ballgauge::calibrate(g, p, o);
        } catch (const Error& e) {
          throw Error(fmt::format("{}: {}", measurements, e.what()));
        }
        const auto n = static_cast<Eigen::Index>(r.points.size());
        Eigen::MatrixXd nominal(n, 3), measured(n, 3), error(n, 3), u(n, 3);
        std::vector<std::string> placement;
        std::vector<int> ball;
        for (Eigen::Index i = 0; i < n; ++i) {
          const auto& q = r.points[static_cast<std::size_t>(i)];
          nominal.row(i) = q.nominal.transpose();
          measured.row(i) = q.measured.transpose();
          error.row(i) = q.error.transpose() * 1e3;
          u.row(i) = q.uncertainty.transpose() * 1e3;
          placement.push_back(q.placement);
          ball.push_back(q.ball);
        }
        py::dict d;
        d["nominal"] = nominal;
        d["measured"] = measured;
        d["error"] = error;
        d["uncertainty"] = u;
        d["placement"] = placement;
        d["ball"] = ball;
        d["map"] = r.grid ? py::cast(*r.grid) : py::object(py::none());
        std::vector<std::string> dropped;
        for (const auto& pl : r.placements)
          for (const auto& x : pl.dropped) dropped.push_back(pl.name + ": " + x);
        d["dropped"] = dropped;
        d["summary"] = r.summary();
        savable(d, [r](const std::string& path) { io::write_ballgauge_map(path, r); });
        return d;
      },
      py::arg("gauge"), py::arg("measurements"), py::kw_only(), py::arg("match_tolerance") = 1.0,
      py::arg("min_points") = 5, py::arg("outlier_tolerance") = 0.02,
      py::arg("drop_outliers") = false,
      R"doc(CMM error-vector map from ball-gauge placements (Oya et al. 1988).

gauge, measurements: paths of gauge.json and measurements.json. A probed point more than
outlier_tolerance (mm) off the sphere through its ball's other points is a wrong touch: an error
names it, or with drop_outliers=True it is left out and listed in 'dropped'. Returns {'nominal',
'measured' (mm), 'error' (measured − true), 'uncertainty' (µm): arrays (points, 3); 'placement',
'ball'; 'map': an ErrorMap when the points form a lattice (use map.correct(points) for
X = x − Δ(x)), else None; 'dropped'; 'summary'}.)doc");

  m.def(
      "identify",
      [](const std::string& gauge, const std::string& measurements,
         const std::vector<double>& stylus_offset, int degree, const std::string& chain,
         const std::string& output) {
        if (stylus_offset.size() != 3) throw Error("stylus_offset needs [x, y, z] (mm)");
        const auto g = io::read_gauge(gauge);
        const auto p = io::read_measurements(measurements, &g);
        ballgauge::ParametricOptions o;
        o.offset = Eigen::Vector3d(stylus_offset[0], stylus_offset[1], stylus_offset[2]);
        o.degree = degree;
        o.chain = chain;
        ballgauge::ParametricResult r;
        try {
          py::gil_scoped_release release;
          r = ballgauge::identify(g, p, o);
        } catch (const Error& e) {
          throw Error(fmt::format("{}: {}", measurements, e.what()));
        }
        if (!output.empty()) io::write_parametric(output, r);
        py::dict d;
        d["machine"] = r.model;
        d["residual_rms"] = r.residual_rms * 1e3;
        d["sigma"] = r.sigma * 1e3;
        d["rank"] = r.rank;
        d["unknowns"] = r.unknowns;
        d["unobservable"] = r.unobservable;
        py::list styli;
        for (const auto& st : r.styli) {
          py::dict one;
          one["offset"] = Eigen::Vector3d(st.offset);
          one["placements"] = st.placements;
          styli.append(one);
        }
        d["styli"] = styli;
        // ISO 230-1 figures with their expanded uncertainties (k = 2).
        py::dict st, st_u;
        const char* names[3][2] = {{"EYX", "EZX"}, {"EXY", "EZY"}, {"EXZ", "EYZ"}};
        for (std::size_t k = 0; k < 3; ++k)
          for (std::size_t j = 0; j < 2; ++j) {
            st[names[k][j]] = r.iso.lines.straightness[k][j] * 1e3;
            st_u[names[k][j]] = 2e3 * r.iso.u_straightness[k][j];
          }
        py::dict sq, sq_u;
        sq["EC0Y"] = r.iso.lines.c0y * 1e6;
        sq["EB0Z"] = r.iso.lines.b0z * 1e6;
        sq["EA0Z"] = r.iso.lines.a0z * 1e6;
        sq_u["EC0Y"] = 2e6 * r.iso.u_c0y;
        sq_u["EB0Z"] = 2e6 * r.iso.u_b0z;
        sq_u["EA0Z"] = 2e6 * r.iso.u_a0z;
        d["straightness_um"] = st;
        d["straightness_U_um"] = st_u;
        d["squareness_urad"] = sq;
        d["squareness_U_urad"] = sq_u;
        d["summary"] = r.summary();
        savable(d, [r](const std::string& path) { io::write_parametric(path, r); });
        return d;
      },
      py::arg("gauge"), py::arg("measurements"), py::kw_only(), py::arg("stylus_offset"),
      py::arg("degree") = 3, py::arg("chain") = "FYXZ", py::arg("output") = "",
      R"doc(The 21 rigid-body errors of the CMM from the ball-gauge data (parametric model).

stylus_offset: the stylus tip's offset [x, y, z] (mm) from the ram, as in machine.json: the
stylus of every placement that states none ("stylus_offset" in measurements.json, e.g. an upright
plate probed from the side), and the one the model corrects for. Every error function is a
polynomial of `degree` in its axis coordinate. Returns {'machine': the
identified trueaxis.Machine (its range is the measured span), 'residual_rms', 'sigma' (µm),
'rank', 'unknowns', 'unobservable' (error names the data cannot see), 'styli' (each stylus
offset with the placements probed with it), 'straightness_um',
'squareness_urad' (ISO 230-1: about and between the axes' reference lines at the tool point,
the other axes mid-span) with 'straightness_U_um', 'squareness_U_urad' (k = 2), 'summary'}. With
output='model.json' the model and its covariance are written for verify_lengths(model=...).)doc");

  m.def(
      "verify_lengths",
      [](const std::variant<std::string, Eigen::MatrixXd>& lengths,
         const std::optional<std::variant<std::string, map::ErrorMap>>& map,
         const std::optional<std::string>& model, double repeat_tolerance, bool clamp,
         const std::optional<std::string>& mpe_text) {
        std::optional<ballgauge::Mpe> mpe;
        if (mpe_text) mpe = ballgauge::Mpe::parse(*mpe_text);
        std::vector<ballgauge::LengthMeasurement> L;
        if (const auto* path = std::get_if<std::string>(&lengths)) {
          L = io::read_lengths(*path);
        } else {
          const auto& a = std::get<Eigen::MatrixXd>(lengths);
          if (a.cols() != 7)
            throw Error(
                fmt::format("lengths: shape ({}, {}); expected (n, 7): x1, y1, z1, x2, "
                            "y2, z2, nominal (mm)",
                            a.rows(), a.cols()));
          for (Eigen::Index i = 0; i < a.rows(); ++i)
            L.push_back(
                {a.row(i).segment<3>(0).transpose(), a.row(i).segment<3>(3).transpose(), a(i, 6)});
        }
        if (!map && !model) throw Error("verify_lengths needs map= or model= (or both)");
        std::optional<map::ErrorMap> grid;
        std::vector<ballgauge::Correction> corr;
        if (map) {
          if (const auto* path = std::get_if<std::string>(&*map))
            grid = io::read_error_map(*path);
          else
            grid = std::get<map::ErrorMap>(*map);
          map::EvalOptions eo;
          eo.outside = clamp ? map::Outside::Clamp : map::Outside::Refuse;
          corr.push_back(ballgauge::grid_correction(*grid, eo));
        }
        if (model) corr.push_back(ballgauge::parametric_correction(io::read_parametric(*model)));
        ballgauge::LengthOptions o;
        o.repeat_tolerance = repeat_tolerance;
        py::list out;
        for (const auto& c : corr) {
          const auto v = ballgauge::verify_lengths(L, c, o);
          const auto n = static_cast<Eigen::Index>(v.rows.size());
          Eigen::VectorXd nominal(n), before(n), after(n), u(n);
          Eigen::VectorXi position(n);
          for (Eigen::Index i = 0; i < n; ++i) {
            const auto& r = v.rows[static_cast<std::size_t>(i)];
            nominal[i] = r.nominal;
            before[i] = r.before * 1e3;
            after[i] = r.after * 1e3;
            u[i] = r.uncertainty * 1e3;
            position[i] = r.position;
          }
          auto stats = [](const ballgauge::LengthStats& st) {
            py::dict d;
            d["min"] = st.min * 1e3;
            d["max"] = st.max * 1e3;
            d["range"] = st.range() * 1e3;
            d["mean"] = st.mean * 1e3;
            d["rms"] = st.rms * 1e3;
            return d;
          };
          py::dict d;
          d["correction"] = v.correction;
          d["nominal"] = nominal;
          d["before"] = before;
          d["after"] = after;
          d["uncertainty"] = u;
          d["position"] = position;
          d["before_stats"] = stats(v.before);
          d["after_stats"] = stats(v.after);
          d["repeatability"] = v.repeatability * 1e3;
          d["expected_after"] = v.predicted_after * 1e3;
          d["summary"] = v.summary();
          savable(d, [v, mpe](const std::string& path) {
            io::write_length_verification(path, {v}, mpe ? &*mpe : nullptr);
          });
          if (mpe) {
            auto e0 = [&](bool after) {
              const auto c = ballgauge::check_mpe(v.rows, *mpe, after);
              py::dict x;
              x["pass"] = c.pass();
              x["beyond"] = c.failed;
              x["lengths"] = c.lengths;
              x["worst_fraction_of_mpe"] = c.worst_ratio;
              return x;
            };
            d["e0_before"] = e0(false);
            d["e0_after"] = e0(true);
          }
          out.append(d);
        }
        return out;
      },
      py::arg("lengths"), py::kw_only(), py::arg("map") = py::none(), py::arg("model") = py::none(),
      py::arg("repeat_tolerance") = 1.0, py::arg("clamp") = false, py::arg("mpe") = py::none(),
      R"doc(Gauge-block verification of a correction (ISO 10360-2 positions, as in Oya et al. 1988).

lengths: a lengths.csv path, or an array (n, 7) of x1, y1, z1, x2, y2, z2, nominal (mm).
map: an ErrorMap or a map.json path (grid correction); model: a model.json path (parametric);
either or both. Returns one dict per correction: 'correction', 'nominal' (mm), 'before',
'after', 'uncertainty' (µm per length), 'position' (repeat group), 'before_stats' and
'after_stats' (min, max, range, mean, rms in µm), 'repeatability' and 'expected_after' (µm;
NaN without repeats), 'summary'. With mpe="A+L/K" (µm, L in mm; ",B" caps it): 'e0_before' and
'e0_after' ({'pass', 'beyond', 'lengths', 'worst_fraction_of_mpe'}), every |E| <= MPE(L).)doc");
}

}  // namespace trueaxis::python
