#pragma once

#include <vector>

#include "hidden_rooms/common/range_scan.h"
#include "hidden_rooms/common/velocity_command.h"

namespace hidden_rooms::simulation {

// A reactive wander for recording data without a planner: forward, steering towards the more open side, turning
// in place (one way until the way ahead is clear) when something is close ahead. Deterministic.
class WanderDriver {
 public:
  // The command for the latest scan (ranges per beam of `laser`).
  common::VelocityCommand next(const std::vector<float>& ranges, const common::LaserGeometry& laser);

 private:
  int turning_ = 0;
};

}  // namespace hidden_rooms::simulation
