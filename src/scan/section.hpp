// Internal to trueaxis::scan: the error-tolerant flow on one section (controller.cpp), called by
// the run over all sections (run.cpp).
#pragma once

#include <vector>

#include "trueaxis/scan/controller.hpp"
#include "trueaxis/scan/planner.hpp"

namespace trueaxis::scan::detail {

struct SectionContext {
  Machine& machine;
  const ControllerOptions& options;
  const Planner& planner;
  std::vector<Event>& events;
  bool& first_move;        // the run's first free move rises along the stylus first
  SectionResult& partial;  // receives what was measured when the section throws
  // Where the part stands, as the rigid corrections (translation, rotation) the last corrected
  // section accepted: carried to a section whose plane they keep before it is first scanned, and
  // replaced by that section's when it accepts corrections of its own that are all rigid.
  std::vector<Correction>& part_move;
};

// Scans `section` (its design data are corrected in place) and returns its result. Throws what
// the machine throws (a collision); `partial` then holds what was measured until then.
SectionResult run_section(const SectionContext& context, design::Section& section);

}  // namespace trueaxis::scan::detail
