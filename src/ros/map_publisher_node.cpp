#include <ros/ros.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/map_publisher.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "map_publisher");
  ros::NodeHandle nh, private_nh("~");
  try {
    hidden_rooms::MapPublisher publisher(nh, hidden_rooms::readMapPublisherOptions(private_nh));
    ROS_INFO("map_publisher: publishing the map on %s", ros::names::resolve("map").c_str());
    ros::spin();
  } catch (const hidden_rooms::common::InputError& error) {
    ROS_FATAL("map_publisher: %s", error.what());
    return 2;
  }
  return 0;
}
