#include <ros/ros.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/mapper.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "mapper");
  ros::NodeHandle nh, private_nh("~");
  try {
    const hidden_rooms::MapperOptions options = hidden_rooms::readMapperOptions(private_nh);
    hidden_rooms::Mapper mapper(nh, options);
    ROS_INFO("mapper: RBPF from %s (seed %u), scans on %s, %s -> %s -> %s", options.rbpf.config_file.c_str(),
             options.rbpf.seed, ros::names::resolve("scan").c_str(), options.map_frame.c_str(),
             options.odom_frame.c_str(), options.base_frame.c_str());
    ros::spin();
  } catch (const hidden_rooms::common::InputError& error) {
    ROS_FATAL("mapper: %s", error.what());
    return 2;
  }
  return 0;
}
