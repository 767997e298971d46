// Any result file, by its kind (result_file.hpp).
#include "trueaxis/io/result_file.hpp"

#include <fmt/format.h>

#include "trueaxis/error.hpp"
#include "trueaxis/io/separation/probes.hpp"

namespace trueaxis::io {

ResultFile read_result_file(const std::string& path) {
  ResultFile f;
  f.kind = read_kind(path);
  const std::string& k = f.kind;
  if (k == "separation") {
    f.result = read_result(path);
  } else if (k == "surface") {
    f.result = read_surface(path);
  } else if (k == "space") {
    SpaceFile s;
    s.space = read_space(path, &s.verification);
    f.result = std::move(s);
  } else if (k == "guideway") {
    f.result = read_guideway_result(path);
  } else if (k == "positioning") {
    f.result = read_positioning_result(path);
  } else if (k == "ballgauge map") {
    f.result = read_ballgauge_map(path);
  } else if (k == "parametric model") {
    f.result = read_parametric(path);
  } else if (k == "length verification") {
    f.result = read_length_verification(path);
  } else if (k == "fit") {
    f.result = read_fit(path);
  } else if (k == "scan") {
    f.result = read_scan(path);
  } else if (k == "circular") {
    f.result = read_circular_result(path);
  } else if (k == "acceptance-e0") {
    f.result = read_e0_result(path);
  } else if (k == "acceptance-probing") {
    f.result = read_probing_result(path);
  } else {
    throw Error(fmt::format(
        "{}: {} is not a result trueaxis writes (results: separation, surface, space, guideway, "
        "positioning, ballgauge map, parametric model, length verification, fit, scan, circular, "
        "acceptance-e0, acceptance-probing)",
        path, k.empty() ? "a file with no \"kind\"" : fmt::format("a '{}' file", k)));
  }
  return f;
}

}  // namespace trueaxis::io
