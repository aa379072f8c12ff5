#include "hidden_rooms/ros/lockstep.h"

#include <ros/init.h>
#include <ros/master.h>
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

bool connectedToEveryPublisher(const ros::Subscriber& subscriber) {
  // getSystemState: [code, text, [publishers: [[topic, [node, ...]], ...], subscribers, services]].
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", request, response, payload, false)) return false;
  for (int i = 0; i < payload[0].size(); ++i)
    if (static_cast<std::string>(payload[0][i][0]) == subscriber.getTopic())
      return subscriber.getNumPublishers() >= static_cast<uint32_t>(payload[0][i][1].size());
  return false;
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
