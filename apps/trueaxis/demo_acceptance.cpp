// trueaxis demo — the CMM acceptance scenario: E0 (ISO 10360-2) on the demo's virtual CMM, the
// CMM mapped with a ball gauge and corrected, E0 again, and the probing test (ISO 10360-5).
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/report/acceptance.hpp"
#include "trueaxis/sim/ballgauge.hpp"

namespace trueaxis::cli {

report::Section demo_acceptance(const sim::Machine& machine, const std::string& dir,
                                std::uint64_t seed,
                                const std::function<void(const std::string&)>& say) {
  const auto volume = acceptance::Volume::of(machine);
  const auto setup = acceptance::example_setup(volume);
  io::write_acceptance_setup(dir + "/acceptance.json", setup);
  acceptance::VirtualProbeOptions probe;
  probe.noise = 0.2e-3;
  probe.lobing = 0.4e-3;
  probe.seed = seed;
  acceptance::E0Options o;
  o.mpe = ballgauge::Mpe::parse("2.5+L/250");
  say("acceptance: E0 of the virtual CMM, 105 gauge-block lengths in ISO 10360-2's 7 positions...");
  const auto before =
      acceptance::run_e0(setup, volume, acceptance::virtual_touch(machine, probe), o);
  io::write_e0_result(dir + "/e0-before.json", before);
  // The correction: a frame of 5 × 4 × 2 balls at 175 mm, stacked twice over the volume.
  const auto gauge = sim::frame_gauge(5, 4, 2, 175, 25);
  const auto poses = sim::stacked_poses(gauge, 2, {50, 40, -40});
  sim::BallGaugeOptions bo;
  bo.tip_radius = 1.5;
  bo.points_per_ball = 6;
  bo.noise = 0.2e-3;
  bo.seed = seed;
  const auto mapped =
      ballgauge::calibrate(gauge, sim::simulate_ballgauge(machine, gauge, poses, bo).placements);
  map::EvalOptions clamp;
  clamp.outside = map::Outside::Clamp;
  const auto correction =
      std::make_shared<ballgauge::Correction>(ballgauge::grid_correction(*mapped.grid, clamp));
  const auto raw = acceptance::virtual_touch(machine, probe);
  const acceptance::Touch corrected = [raw, correction](const Eigen::Vector3d& at,
                                                        const Eigen::Vector3d& d) {
    return correction->corrected(raw(at, d));
  };
  const auto after = acceptance::run_e0(setup, volume, corrected, o);
  io::write_e0_result(dir + "/e0.json", after);
  acceptance::ProbingOptions po;
  po.mpe_form = 1.8e-3;
  po.mpe_size = 1.5e-3;
  const auto probing = acceptance::run_probing(setup, corrected, po);
  io::write_probing_result(dir + "/probing.json", probing);
  say(fmt::format(
      "acceptance: E0 {:.1f} µm ({}), mapped with a 60-ball frame and corrected: {:.2f} µm ({}); "
      "PForm {:.2f} µm, PSize {:+.2f} µm (the probe's lobing) -> acceptance.json, e0-before.json, "
      "e0.json, probing.json",
      before.e0_max * 1e3, acceptance::to_string(before.verdict), after.e0_max * 1e3,
      acceptance::to_string(after.verdict), probing.form * 1e3, probing.size * 1e3));
  auto s = report::e0_section(
      "CMM acceptance: length measuring error E0 (ISO 10360-2), after the error map", after);
  s.intro_html =
      fmt::format(
          "<p>The virtual CMM above, accepted as its owner would: 35 gauge blocks in the 7 "
          "positions of ISO 10360-2 (the 4 space diagonals and lines along X, Y and Z), each "
          "length probed on both faces 3 times by a touch-trigger probe ({:g} µm noise, {:g} µm "
          "of three-lobed pre-travel). As built its largest length error is {:.1f} µm against "
          "an E0,MPE of {} µm: it <strong>{}</strong>. Mapped with a ball gauge (a frame of 60 "
          "balls at 175 mm over the volume) and corrected with that map, E0 is {:.2f} µm: it "
          "<strong>{}</strong>, shown below. The probing test on a Ø25 mm sphere (ISO 10360-5): "
          "PForm {:.2f} µm, PSize {:+.2f} µm, the probe's own, which no map of the machine "
          "removes. Try <code>trueaxis acceptance e0 --machine machine.json --artefacts "
          "acceptance.json --mpe 2.5+L/250 --report e0.html</code>, or the same over I++ DME "
          "with <code>trueaxis serve --machine machine.json --artefacts acceptance.json</code> "
          "and <code>--cmm ipp://127.0.0.1:1294</code>.</p>",
          probe.noise * 1e3, probe.lobing * 1e3, before.e0_max * 1e3, o.mpe.text,
          acceptance::to_string(before.verdict), after.e0_max * 1e3,
          acceptance::to_string(after.verdict), probing.form * 1e3, probing.size * 1e3) +
      s.intro_html;
  s.summary = fmt::format("E0 {:.1f} µm ({}) → {:.2f} µm ({}) with the ball-gauge map",
                          before.e0_max * 1e3, acceptance::to_string(before.verdict),
                          after.e0_max * 1e3, acceptance::to_string(after.verdict));
  return s;
}

}  // namespace trueaxis::cli
