#pragma once

namespace hidden_rooms::common {

// A velocity command for a differential-drive base (geometry_msgs/Twist's linear.x and angular.z).
struct VelocityCommand {
  double linear = 0.0;   // m/s along base_link's x
  double angular = 0.0;  // rad/s
};

}  // namespace hidden_rooms::common
