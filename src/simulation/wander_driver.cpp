#include "hidden_rooms/simulation/wander_driver.h"

#include <algorithm>
#include <cmath>

namespace hidden_rooms::simulation {

common::VelocityCommand WanderDriver::next(const std::vector<float>& ranges, const common::LaserGeometry& laser) {
  double ahead = laser.max_range, left = 0.0, right = 0.0;
  const int beams = std::min<int>(laser.beams, static_cast<int>(ranges.size()));
  for (int k = 0; k < beams; ++k) {
    const double angle = laser.angle_min + k * laser.angle_increment;
    if (std::abs(angle) < 0.45) ahead = std::min(ahead, static_cast<double>(ranges[k]));
    if (angle > 0.3 && angle < 1.6) left += std::min(ranges[k], 5.0f);
    if (angle < -0.3 && angle > -1.6) right += std::min(ranges[k], 5.0f);
  }
  if (turning_ != 0 && ahead > 1.5) turning_ = 0;
  if (turning_ == 0 && ahead < 0.9) turning_ = left >= right ? 1 : -1;
  if (turning_ != 0) return {0.0, 1.0 * turning_};
  const double balance = (left - right) / std::max(left + right, 1.0);
  return {std::min(0.6, 0.35 * ahead), std::clamp(2.0 * balance, -0.6, 0.6)};
}

}  // namespace hidden_rooms::simulation
