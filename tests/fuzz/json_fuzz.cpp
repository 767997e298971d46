// libFuzzer target: every JSON configuration and result reader on arbitrary bytes. The first
// byte chooses the reader, so that the corpus of each file kind evolves on its own.
#include <cstdint>

#include "fuzz_util.hpp"
#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/certificate/certificate.hpp"
#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/circular/circular.hpp"
#include "trueaxis/io/circular/compensation.hpp"
#include "trueaxis/io/design/design.hpp"
#include "trueaxis/io/guideway/guideway.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/separation/probes.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/io/surface/space.hpp"
#include "trueaxis/io/surface/surface.hpp"
#include "trueaxis/records/records.hpp"
#include "trueaxis/surface/surface.hpp"

using namespace trueaxis;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string p = fuzz::write_input("in.json", data + 1, size - 1);
  fuzz::expect_only_trueaxis_errors([&] {
    io::JsonFile::read(p);
    switch (data[0] % 20) {
      case 0:
        io::read_machine(p);
        break;
      case 1:
        io::read_plan(p);
        break;
      case 2: {
        const auto lines = io::read_lines(p);
        if (lines.size() <= 50) surface::build(lines);
        break;
      }
      case 3:
        io::read_layout(p);
        break;
      case 4:
        io::read_gauge(p);
        break;
      case 5:
        io::read_measurements(p);
        break;
      case 6:
        io::read_error_map(p);
        break;
      case 7:
        io::read_result(p);
        break;
      case 8:
        io::read_parametric(p);
        break;
      case 9:
        io::read_design(p);
        break;
      case 10:
        io::read_part(p);
        break;
      case 12:
        io::read_circular_result(p);
        break;
      case 13:
        io::read_servo(p);
        break;
      case 14:
        io::read_compensation_json(p);
        break;
      case 15: {  // a CMM acceptance set-up, checked against the standard and a volume
        const auto setup = io::read_acceptance_setup(p);
        acceptance::Volume v;
        v.high = Eigen::Vector3d(800, 600, 500);
        if (!setup.placements.empty()) {
          acceptance::artefact_boxes(setup);
          acceptance::positions(setup, v);
        }
        break;
      }
      case 16:  // CMM acceptance results, as 'trueaxis report' and trueaxis.load read them
        io::read_e0_result(p);
        break;
      case 17:
        io::read_probing_result(p);
        break;
      case 18: {  // the records' headline figures of any JSON text, whatever its kind says
        const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
        for (const char* kind : {"positioning", "circular", "acceptance-e0", "acceptance-probing",
                                 "separation", "guideway", "surface", "space",
                                 "length verification", "ballgauge map", "fit", "scan"}) {
          try {
            records::headline_figures(kind, text);
          } catch (const Error&) {  // not a result of that kind: the next
          }
        }
        break;
      }
      case 19:  // a laboratory's statements for a certificate
        certificate::read_lab(p);
        break;
      default:
        io::read_positioning_result(p);
        break;
    }
  });
  return 0;
}
