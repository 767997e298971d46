// The entry point of libtrueaxis_occt.so: the table of occt_api.hpp, each entry turning every
// failure (trueaxis::Error, an OCCT exception, anything else) into its one-line message so that
// nothing is thrown across the library boundary.
#include <exception>
#include <string>

#include "../occt_api.hpp"
#include "occt.hpp"

namespace trueaxis::design::occt {
namespace {

template <class Fn>
std::string guarded(Fn&& fn) noexcept {
  try {
    fn();
    return {};
  } catch (const Standard_Failure& e) {
    return "Open CASCADE Technology failed: " + message(e);
  } catch (const std::exception& e) {
    const std::string m = e.what();
    return m.empty() ? std::string("an unexplained failure in the CAD library") : m;
  } catch (...) {
    return "an unexplained failure in the CAD library";
  }
}

detail::OcctApi make_api() {
  static const std::string tag = detail::occt_api_tag();
  detail::OcctApi api;
  api.tag = tag.c_str();
  api.nurbs_ends = [](const Section& s, Eigen::Vector3d& first, Eigen::Vector3d& last) {
    return guarded([&] { occt::ends(s, first, last); });
  };
  api.nurbs_length = [](const Section& s, double& out) {
    return guarded([&] { out = occt::length(s); });
  };
  api.nurbs_piece = [](const Section& s, double from, double to, Section& out) {
    return guarded([&] { out = occt::piece(s, from, to); });
  };
  api.nurbs_sample_fine = [](const Section& s, double spacing, double tolerance, Samples& out) {
    return guarded([&] { out = occt::sample_fine(s, spacing, tolerance); });
  };
  api.moved_sections = [](const std::string& path, const double(&map)[12], const Plane& plane,
                          Design& out) {
    return guarded([&] { out = occt::moved_sections(path, map, plane); });
  };
  api.nurbs_sample = [](const Section& s, double spacing, Samples& out) {
    return guarded([&] { out = occt::sample(s, spacing); });
  };
  api.plane_path = [](const Section& s, const PathOptions& o, ScanPath& out) {
    return guarded([&] { out = occt::plane_path(s, o); });
  };
  api.cut_step = [](const std::string& path, const std::vector<StepSectionRequest>& planes,
                    const StepCutOptions& options, StepCut& out) {
    return guarded([&] { out = occt::cut_step(path, planes, options); });
  };
  api.step_mesh = [](const std::string& path, double deflection, detail::MeshData& out) {
    return guarded([&] { occt::step_mesh(path, deflection, out); });
  };
  return api;
}

}  // namespace
}  // namespace trueaxis::design::occt

extern "C" __attribute__((visibility("default"))) const trueaxis::design::detail::OcctApi*
trueaxis_design_occt_api() {
  static const trueaxis::design::detail::OcctApi api = trueaxis::design::occt::make_api();
  return &api;
}
