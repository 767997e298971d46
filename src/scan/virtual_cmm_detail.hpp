// Internal to the virtual CMM (virtual_cmm.cpp, virtual_cmm_moves.cpp): what its motions share.
#pragma once

namespace trueaxis::scan::vcmm {

constexpr long kMaxTicks = 50'000'000;  // 14 hours of machine time at 1 kHz: a runaway guard
// A ball entering a face it may not touch by more than this is a collision (mm): the probe's
// trigger threshold of a touch-trigger probe, well under a scanning probe's deflection.
constexpr double kCollision = 0.05;
// Distances to the solid are looked for this far beyond an element's surface (mm); farther
// counts as this far.
constexpr double kSolidLookout = 10;

// Within a motion the probe's trigger stops (a free move, a touch's approach, a scan): the ball
// off its surface or the stem meeting the part sets the trigger instead of being a collision.
struct Guard {
  bool& on;
  bool saved;
  Guard(bool& flag, int& triggered) : on(flag), saved(flag) {
    on = true;
    triggered = -1;
  }
  ~Guard() { on = saved; }
};

}  // namespace trueaxis::scan::vcmm
