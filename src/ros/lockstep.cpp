#include "hidden_rooms/ros/lockstep.h"

#include <ros/init.h>
#include <ros/names.h>
#include <ros/this_node.h>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms {

std::string resolvedNodeName(const std::string& name, const std::string& parameter) {
  std::string problem;
  if (!ros::names::validate(name, problem))
    throw common::InputError("~" + parameter, "'" + name + "' is not a node name: " + problem);
  return ros::names::resolve(name);
}

LockstepAck lockstepReport(const ros::Time& stamp) {
  LockstepAck ack;
  ack.node = ros::this_node::getName();
  ack.stamp = stamp;
  return ack;
}

bool waitOnWallClock(const std::function<bool()>& ready, double wall_seconds) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wall_seconds);
  while (!ready()) {
    if (ros::WallTime::now() >= deadline || !ros::ok()) return false;
    ros::WallDuration(0.0005).sleep();
  }
  return true;
}

}  // namespace hidden_rooms
