// libFuzzer target: the CSV readers (probes, points, spots, lengths, positioning runs, ballbar
// traces and time series), Renishaw .rtl files, the LinuxCNC, Sinumerik, HEIDENHAIN and FANUC
// compensation tables and backlash parameters, and Siemens cross-axis tables on arbitrary bytes.
#include <cstdint>

#include "fuzz_util.hpp"
#include "trueaxis/circular/circular.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/circular/circular.hpp"
#include "trueaxis/io/compensation/controller.hpp"
#include "trueaxis/io/compensation/parameters.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/guideway/guideway.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/positioning/renishaw.hpp"
#include "trueaxis/io/separation/probes.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/separation/separation.hpp"

using namespace trueaxis;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string p = fuzz::write_input("in.csv", data, size);
  fuzz::expect_only_trueaxis_errors([&] { io::CsvTable::read(p); });
  fuzz::expect_only_trueaxis_errors([&] {
    const auto probes = io::read_probes(p);
    if (probes.x.size() <= 2000) separation::separate(probes);
  });
  fuzz::expect_only_trueaxis_errors([&] {
    io::ProbeReadOptions o;
    o.angle_column = "angle";
    const auto probes = io::read_probes(p, o);
    separation::Options so;
    so.sigma = 1e-4;
    if (probes.x.size() <= 2000) separation::separate(probes, so);
  });
  fuzz::expect_only_trueaxis_errors([&] { io::read_points(p); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_lengths(p); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_linuxcnc(p, 0); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_sinumerik(p); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_heidenhain(p); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_fanuc(p); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_linuxcnc_backlash(p); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_heidenhain_backlash(p); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_fanuc_backlash(p); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_sinumerik_backlash(p); });
  fuzz::expect_only_trueaxis_errors([&] { io::read_sinumerik_cec(p).at(1.5); });
  fuzz::expect_only_trueaxis_errors([&] {
    io::TimeSeriesOptions ts;
    ts.feed = 1000;
    ts.radius = 10;
    const auto trace = io::read_trace(p, &ts);
    circular::Options o;
    o.radius = 10;
    o.min_samples = 8;
    o.max_gap = 3.2;
    if (trace.angle.size() <= 2000) circular::evaluate(trace, o);
  });
  fuzz::expect_only_trueaxis_errors([&] {
    positioning::Options o;
    o.allow_incomplete = true;
    positioning::evaluate(io::read_rtl(p).runs.readings, o);
  });
  fuzz::expect_only_trueaxis_errors([&] {
    io::RtlOptions ro;
    ro.directions = io::RunDirections::UpDown;
    io::read_rtl(p, ro);
  });
  fuzz::expect_only_trueaxis_errors([&] {
    const auto log = io::read_log(p);
    if (log.time.size() <= 20000) positioning::readings_from_log(log, {0, 10, 20, 50});
  });
  fuzz::expect_only_trueaxis_errors([&] {
    positioning::Options o;
    o.allow_incomplete = true;
    positioning::evaluate(io::read_runs(p).readings, o);
  });
  fuzz::expect_only_trueaxis_errors([&] {
    io::GuidewayLayout layout;
    for (const char* name : {"a", "b", "c"}) {
      guideway::Detector d;
      d.name = name;
      layout.layout.detectors.push_back(d);
    }
    layout.layout.detectors[1].position = {60, 0, 150};
    layout.layout.detectors[2].position = {0, 80, 300};
    io::read_spots(p, layout, true);
  });
  return 0;
}
