// Private: the design module's Open CASCADE Technology (OCCT) code lives in its own shared
// library, loaded on first use.
//
// Debian builds the OCCT libraries with immediate binding, so a program linked to them resolves
// their ~77 000 relocations and runs their static constructors at every start, whether or not it
// reads a STEP file or evaluates a NURBS section. Most uses of trueaxis never do: a separation,
// a fit or `trueaxis --help` paid 30–45 ms for it. The library (libtrueaxis_occt.so, from
// src/design/occt/) is opened the first time a NURBS section, a plane section's scanning path or
// a STEP file needs it, and it hands back this table of entry points.
//
// Nothing is thrown across the boundary: each entry returns an empty string on success or a
// one-line message, which the caller throws as trueaxis::Error. Both sides are built from the same
// tree; the table carries a tag that the loader checks so that a library from another build is
// refused instead of called.
#pragma once

#include <string>
#include <vector>

#include "trueaxis/design/design.hpp"

namespace trueaxis::design::detail {

// A part's boundary as triangles (solid::Mesh's input): vertices (mm), vertex indices, and the CAD
// face of each triangle.
struct MeshData {
  Eigen::Matrix3Xd vertices;
  Eigen::Matrix3Xi triangles;
  std::vector<int> faces;
};

struct OcctApi {
  // occt_api_tag() of the library's build.
  const char* tag = nullptr;
  // The first and last point of a NURBS section's curve as OCCT builds it (the message says why
  // OCCT rejects it). Precondition: the section's other checks pass.
  std::string (*nurbs_ends)(const Section& s, Eigen::Vector3d& first,
                            Eigen::Vector3d& last) = nullptr;
  // Arc length of a NURBS section's curve (mm).
  std::string (*nurbs_length)(const Section& s, double& out) = nullptr;
  // design::piece of a NURBS section (arcs checked).
  std::string (*nurbs_piece)(const Section& s, double from, double to, Section& out) = nullptr;
  // A NURBS section sampled at about `spacing` mm (> 0), as design::sample.
  std::string (*nurbs_sample)(const Section& s, double spacing, Samples& out) = nullptr;
  // The same with every knot a sample and chords within `tolerance` (> 0) of the curve.
  std::string (*nurbs_sample_fine)(const Section& s, double spacing, double tolerance,
                                   Samples& out) = nullptr;
  // The sections of a STEP file's part moved by x -> linear·x + translation (a row-major 3 × 4
  // matrix), in one plane: as cut_step's, unnamed.
  std::string (*moved_sections)(const std::string& path, const double (&map)[12],
                                const Plane& plane, Design& out) = nullptr;
  // The scanning path of a plane section (checked, its plane normal of unit length, options
  // validated), as design::make_path.
  std::string (*plane_path)(const Section& s, const PathOptions& o, ScanPath& out) = nullptr;
  // design::cut_step (options validated).
  std::string (*cut_step)(const std::string& path, const std::vector<StepSectionRequest>& planes,
                          const StepCutOptions& options, StepCut& out) = nullptr;
  // The union of a STEP file's solids tessellated with chords within `deflection` mm of its faces
  // (each triangle counter-clockwise seen from outside the part).
  std::string (*step_mesh)(const std::string& path, double deflection, MeshData& out) = nullptr;
};

// Changes whenever the table or the types it passes change size or meaning.
inline std::string occt_api_tag() {
  return std::string("trueaxis-occt-3/") + std::to_string(sizeof(Section)) + "/" +
         std::to_string(sizeof(ScanPath)) + "/" + std::to_string(sizeof(PathOptions)) + "/" +
         std::to_string(sizeof(Samples)) + "/" + std::to_string(sizeof(Design)) + "/" +
         std::to_string(sizeof(StepCut)) + "/" + std::to_string(sizeof(MeshData)) + "/" +
         std::to_string(sizeof(PccSegment));
}

// The library's file name (found through the program's run path) and its one exported symbol, a
// function returning a pointer to a static OcctApi.
inline constexpr const char* kOcctLibrary = "libtrueaxis_occt.so";
inline constexpr const char* kOcctEntry = "trueaxis_design_occt_api";
using OcctEntry = const OcctApi*();

// The table, loading the library on the first call (thread-safe). Throws Error, naming the
// library and the loader's reason, if it cannot be loaded or comes from another build; a later
// call tries again.
const OcctApi& occt_api();
// Loads the table from `library` (a file name or path, as dlopen takes it), without caching.
const OcctApi& load_occt_api(const std::string& library);

}  // namespace trueaxis::design::detail
