#include <ros/ros.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/simulator.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "simulator");
  ros::NodeHandle nh, private_nh("~");
  try {
    hidden_rooms::Simulator simulator(nh, hidden_rooms::readSimulatorOptions(private_nh));
    const hidden_rooms::common::Pose2& start = simulator.simulation().startPose();
    ROS_INFO("simulator: robot at (%.2f, %.2f, %.2f), %d static fixtures, laser caster %s", start.x, start.y, start.yaw,
             simulator.simulation().staticFixtureCount(),
             hidden_rooms::simulation::toString(simulator.simulation().options().laser.caster));
    simulator.run();
  } catch (const hidden_rooms::common::InputError& error) {
    ROS_FATAL("simulator: %s", error.what());
    return 2;
  }
  return 0;
}
