// The scanning controller's options: strategies by name, and the checks of every option.
#include <fmt/format.h>

#include <string>

#include "trueaxis/error.hpp"
#include "trueaxis/scan/controller.hpp"

namespace trueaxis::scan {

const char* to_string(Strategy s) {
  return s == Strategy::ErrorTolerant ? "error-tolerant"
         : s == Strategy::Design      ? "design"
                                      : "autonomous";
}

Strategy strategy_from_string(const std::string& s) {
  if (s == "error-tolerant") return Strategy::ErrorTolerant;
  if (s == "design") return Strategy::Design;
  if (s == "autonomous") return Strategy::Autonomous;
  throw Error("strategy '" + s + "': use error-tolerant, design or autonomous");
}

void ControllerOptions::validate() const {
  path.validate();
  auto bad = [](const char* name, double v, const char* why) {
    throw Error(fmt::format("{} = {:g}: {}", name, v, why));
  };
  if (!(tolerance > 0 && tolerance <= 10)) bad("tolerance", tolerance, "must be in (0, 10] mm");
  if (max_autonomous < 0 || max_autonomous > 100)
    bad("max autonomous", max_autonomous, "must be 0 to 100");
  if (touch_points < 4 || touch_points > 1000)
    bad("touch points", touch_points, "must be 4 to 1000");
  if (!(touch_trigger > 0 && touch_trigger < path.tip_radius))
    bad("touch trigger", touch_trigger, "must be positive and below the tip radius (mm)");
  if (!(touch_speed > 0 && touch_speed <= 50))
    bad("touch speed", touch_speed, "must be in (0, 50] mm/s");
  if (!(move_speed > 0 && move_speed <= 1000))
    bad("move speed", move_speed, "must be in (0, 1000] mm/s");
  if (!(clearance >= 1 && clearance <= 1000))
    bad("clearance", clearance, "must be in [1, 1000] mm");
  if (!(margin >= 0 && margin <= 100))
    bad("margin", margin, "must be in [0, 100] mm (0: automatic)");
  if (!(guarded_speed >= 0 && guarded_speed <= move_speed))
    bad("guarded speed", guarded_speed, "must be in [0, the move speed] mm/s (0: the machine's)");
  stylus.validate(path.tip_radius);
  if (!(autonomous_speed > 0 && autonomous_speed <= 100))
    bad("autonomous speed", autonomous_speed, "must be in (0, 100] mm/s");
  if (!(accept > 0 && accept < tolerance))
    bad("accept", accept, "must be positive and below the tolerance");
  if (!(record_spacing >= 0.01 && record_spacing <= 10))
    bad("record spacing", record_spacing, "must be in [0.01, 10] mm");
}

}  // namespace trueaxis::scan
