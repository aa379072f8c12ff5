#pragma once

// Helpers of the rostest nodes (they need roscpp; the core's tests use test_util.h).
#include <ros/ros.h>

namespace hidden_rooms::testing {

// Spins the global callback queue until `condition()` holds or `wall_seconds` of wall time pass; `each_turn()`
// runs before every spin (e.g. to keep publishing a command). Returns whether the condition held.
template <typename Condition, typename Turn>
bool spinUntil(Condition condition, double wall_seconds, Turn each_turn, double period = 0.005) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wall_seconds);
  while (ros::WallTime::now() < deadline) {
    each_turn();
    ros::spinOnce();
    if (condition()) return true;
    ros::WallDuration(period).sleep();
  }
  return false;
}

template <typename Condition>
bool spinUntil(Condition condition, double wall_seconds) {
  return spinUntil(condition, wall_seconds, [] {});
}

}  // namespace hidden_rooms::testing
