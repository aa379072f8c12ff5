#pragma once

#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>

#include "hidden_rooms/common/options.h"

namespace hidden_rooms {

// Parameters of the pose_logger node (all private, ~name; see docs/ros_api.md).
struct PoseLoggerOptions {
  std::string estimate_log = "poses_map.log";   // tf map_frame -> base_frame, one line per period
  std::string ground_truth_log;                 // base_pose_ground_truth at the same period; "" = not logged
  std::string map_frame = "map";
  std::string base_frame = "base_link";
  std::string ground_truth_topic = "base_pose_ground_truth";
  double period = 0.1;                          // seconds of ROS time between logged poses
  // Continue existing logs (a respawned logger) instead of starting them afresh: a line cut by a kill is
  // removed, poses at or before a log's last time are not logged again.
  bool append = false;
  // Lockstep (explore.launch at realtime_factor 0): until the clock runs, report ready on `lockstep` while subscribed
  // to every publisher of tf and of the ground-truth topic, so that the simulator's ~lockstep_start_nodes can wait
  // until no pose of the run can be missed.
  bool lockstep = false;
};

// The node's parameters, as docs/ros_api.md lists them.
const common::OptionTable<PoseLoggerOptions>& poseLoggerNodeOptionTable();
std::vector<common::OptionDescription> poseLoggerParameters();
// Reads the options from the private node handle; throws InputError naming the first bad parameter.
PoseLoggerOptions readPoseLoggerOptions(const ros::NodeHandle& private_nh);

// The thesis's tf listener: logs the robot's pose in the map (tf map -> base_link) at every multiple of `period`
// of ROS time and, optionally, its true pose (nav_msgs/Odometry on base_pose_ground_truth) every `period`, into
// pose logs (pose_log.h) flushed line by line so a killed run keeps what it logged; with `append` a restarted
// logger continues them.
class PoseLogger {
 public:
  // Opens the logs (throws InputError when one cannot be written); does not wait for tf or messages.
  PoseLogger(ros::NodeHandle nh, const PoseLoggerOptions& options);

  long long estimatesLogged() const { return estimates_logged_; }
  long long groundTruthLogged() const { return ground_truth_logged_; }

 private:
  // Logs the estimates of the grid times up to ROS time now that tf can give (or that it gave up on).
  void logEstimates();
  // Lockstep: whether the transforms of the grid time `time` may still come: tf has none after it yet, and it has
  // waited less than kLockstepGiveUpWall of wall time since its first try.
  bool transformsLate(const ros::Time& time);
  void onGroundTruth(const nav_msgs::Odometry::ConstPtr& message);
  void onReadyTimer(const ros::WallTimerEvent& event);
  void addTransforms(const tf2_msgs::TFMessage& message, bool is_static);

  PoseLoggerOptions options_;
  std::ofstream estimate_log_;
  std::ofstream ground_truth_log_;
  tf2_ros::Buffer tf_buffer_;
  // tf2_ros's listener, on this node's queue with room for a burst (see kTransformQueue).
  ros::Subscriber tf_subscriber_;
  ros::Subscriber tf_static_subscriber_;
  ros::Subscriber ground_truth_subscriber_;
  ros::Timer timer_;          // logEstimates every ~period of ROS time
  ros::WallTimer wall_timer_;  // lockstep: logEstimates every 0.02 s of wall time instead
  ros::WallTime first_try_;    // lockstep: when the grid time due was first tried after kGiveUpDelay
  ros::Publisher lockstep_publisher_;  // lockstep: the ready reports
  ros::WallTimer ready_timer_;
  double next_estimate_time_ = 0.0;  // next grid time to log (seconds); 0 = not started
  ros::Time last_ground_truth_stamp_;
  // The last pose already in a continued log (seconds); -infinity for a new log.
  double last_estimate_time_ = -std::numeric_limits<double>::infinity();
  double last_ground_truth_time_ = -std::numeric_limits<double>::infinity();
  bool ground_truth_header_written_ = false;
  long long estimates_logged_ = 0;
  long long ground_truth_logged_ = 0;
};

}  // namespace hidden_rooms
