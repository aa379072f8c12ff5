#pragma once

// The pieces of the lockstep protocol that the simulator, the mapper and the explorer share (docs/ros_api.md,
// "Lockstep"): node names from parameters, a node's report, and waits bounded by the wall clock.

#include <functional>
#include <string>

#include <hidden_rooms/LockstepAck.h>
#include <ros/subscriber.h>
#include <ros/time.h>

namespace hidden_rooms {

// A node name as a parameter gives it, resolved in this node's namespace ("mapper" -> "/mapper"). Throws
// InputError("~parameter", ...) for text that is no valid name.
std::string resolvedNodeName(const std::string& name, const std::string& parameter);

// This node's report of the scan stamped `stamp` (0: ready); the caller fills in the other fields.
LockstepAck lockstepReport(const ros::Time& stamp);

// Whether `subscriber` is connected to every publisher the master lists for its topic, and there is one (a message
// published once this holds reaches it). Asks the master: not for every message.
bool connectedToEveryPublisher(const ros::Subscriber& subscriber);

// Polls `ready` until it holds or `wall_seconds` of wall time have passed; whether it held. (tf2's own timeouts run
// on ROS time, which stands still while the simulator waits for the lockstep reports.)
bool waitOnWallClock(const std::function<bool()>& ready, double wall_seconds);

}  // namespace hidden_rooms
