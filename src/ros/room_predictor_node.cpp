#include <ros/ros.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/room_predictor.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "room_predictor");
  ros::NodeHandle nh, private_nh("~");
  try {
    hidden_rooms::RoomPredictorNode predictor(nh, hidden_rooms::readRoomPredictorOptions(private_nh));
    ROS_INFO("room_predictor: serving %s over the maps of %s", ros::names::resolve("predict_rooms").c_str(),
             ros::names::resolve("map").c_str());
    ros::spin();
  } catch (const hidden_rooms::common::InputError& error) {
    ROS_FATAL("room_predictor: %s", error.what());
    return 2;
  }
  return 0;
}
