#include <ros/ros.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/explorer.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "explorer");
  ros::NodeHandle nh, private_nh("~");
  try {
    const hidden_rooms::ExplorerOptions options = hidden_rooms::readExplorerOptions(private_nh);
    hidden_rooms::Explorer explorer(nh, options);
    ROS_INFO("explorer: exploring with the map on %s and the laser on %s (robot radius %.2f m)",
             ros::names::resolve("map").c_str(), ros::names::resolve("scan").c_str(),
             options.planner.robot_radius);
    ros::spin();
  } catch (const hidden_rooms::common::InputError& error) {
    ROS_FATAL("explorer: %s", error.what());
    return 2;
  }
  return 0;
}
