// trueaxis::ippdme — a ball gauge measured on a CMM over I++ DME: the probe for
// sim::measure_ballgauge that touches each ball with PtMeas, so the calibration loop (probe the
// gauge, map the errors, correct) runs against any I++ DME server, `trueaxis serve --balls` or a
// real controller.
//
// Each probing starts `clearance` mm off the ball along its direction (the tip centre at
// centre + (reach + clearance)·direction), searches along −direction up to `search` mm beyond
// the ball's nominal surface, and reads the ball centre as the server reports it: the surface
// point plus the tip radius along the measured normal. Afterwards the tip backs out to the start.
// Between probings the tip moves in straight lines that keep at least clearance/2 mm from every
// ball of `obstacles` (its surface to the tip's); where the straight line does not, it goes round
// by a detour (the two ends shifted alike, up and sideways, the shortest shift that is clear).
//
// Units: mm, mm/s; frame: the server's current coordinate system (the machine's, unless the
// client chose another).
#pragma once

#include <vector>

#include "trueaxis/ippdme/remote_cmm.hpp"
#include "trueaxis/sim/ballgauge.hpp"

namespace trueaxis::ippdme {

struct BallProbingOptions {
  double clearance = 3;     // mm between the tip and the ball where a probing starts
  double search = 3;        // mm searched beyond the nominal surface
  double speed = 5;         // probing speed (mm/s)
  double move_speed = 100;  // speed of the moves between probings (mm/s)
  void validate() const;    // throws Error naming the option
};

// The probe, with the CMM's tip radius (RemoteCmm::tip_radius(): construct it with tip_radius 0
// to take the server's). A probing that meets no surface, or a move the server refuses (a
// collision, the travel), throws Error naming the ball. Throws Error for no way round the
// obstacles between two probings.
sim::BallProbe ball_probe(RemoteCmm& cmm, std::vector<sim::Ball> obstacles,
                          const BallProbingOptions& options = {});

}  // namespace trueaxis::ippdme
