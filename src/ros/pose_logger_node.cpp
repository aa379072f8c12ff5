#include <ros/ros.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/pose_logger.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "pose_logger");
  ros::NodeHandle nh, private_nh("~");
  try {
    const hidden_rooms::PoseLoggerOptions options = hidden_rooms::readPoseLoggerOptions(private_nh);
    hidden_rooms::PoseLogger logger(nh, options);
    ROS_INFO("pose_logger: %s -> %s every %.2f s into %s%s%s", options.map_frame.c_str(), options.base_frame.c_str(),
             options.period, options.estimate_log.c_str(), options.ground_truth_log.empty() ? "" : ", ground truth into ",
             options.ground_truth_log.c_str());
    ros::spin();
    ROS_INFO("pose_logger: %lld estimated and %lld true poses logged", logger.estimatesLogged(),
             logger.groundTruthLogged());
  } catch (const hidden_rooms::common::InputError& error) {
    ROS_FATAL("pose_logger: %s", error.what());
    return 2;
  }
  return 0;
}
