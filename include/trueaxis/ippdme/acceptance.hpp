// trueaxis::ippdme — the CMM acceptance tests (acceptance/acceptance.hpp) run on a CMM over I++
// DME: the Touch that measures a point of an artefact with PtMeas, every move planned against
// the artefacts as the set-up places them.
//
// A face is probed from its start point, `approach` mm plus the tip radius out from it along
// its normal, searching `search` mm beyond it. The moves between probings keep the ball at
// least `clearance` mm from every block of the position being measured and from the reference
// sphere (the approach leg, straight in along the face's normal, excepted): out along the face's
// normal, up to a safe height above every block, across, and down to the next start, stepping
// sideways where a straight way up or down would meet a block (the lower face of an upright
// block). Positions are set up one after another: before another position the probe goes up
// above every block, where the set-up is changed.
//
// Units: mm, mm/s; frame: the server's machine coordinates.
#pragma once

#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/ippdme/remote_cmm.hpp"

namespace trueaxis::ippdme {

struct AcceptanceProbingOptions {
  double clearance = 5;     // mm between the ball and any artefact on a free move
  double escape = 30;       // mm out from a face before going up or across
  double search = 3;        // mm searched beyond a face's nominal place
  double speed = 5;         // probing speed (mm/s)
  double move_speed = 300;  // moves (mm/s), a bridge CMM's usual positioning speed
  void validate() const;    // throws Error naming the option
};

// The Touch for acceptance::run_e0 and run_probing on `cmm`. The travel (tip-centre positions)
// bounds the safe height. Throws Error: no contact (naming the point), no safe way to a face
// (naming it), a move or probing the server refuses. `cmm` must outlive the Touch.
acceptance::Touch acceptance_touch(RemoteCmm& cmm, const acceptance::Setup& setup,
                                   const acceptance::Volume& travel,
                                   const AcceptanceProbingOptions& options = {});

}  // namespace trueaxis::ippdme
