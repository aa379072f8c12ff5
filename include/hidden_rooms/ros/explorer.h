#pragma once

#include <deque>
#include <optional>
#include <string>
#include <vector>

#include <hidden_rooms/LockstepAck.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/Bool.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "hidden_rooms/exploration/exploration_policy.h"

namespace hidden_rooms {

// Parameters of the explorer node (all private, ~name; see docs/ros_api.md and config/explorer.yaml): the
// policy's (planner, frontiers, follower, passages, replanning, hysteresis, blacklist, done, search turn, obstacle
// memory) and the node's own.
struct ExplorerOptions : exploration::ExplorationPolicyOptions {
  ExplorerOptions() { background_planning = true; }  // plans never hold up cmd_vel (~background_planning)
  std::string map_frame = "map";
  std::string base_frame = "base_link";
  double control_rate = 10.0;       // Hz of ROS time: commands (and replanning when due)
  double scan_timeout = 1.0;        // seconds (ROS time): an older scan stops the robot
  double pose_timeout = 1.0;        // seconds (ROS time): an older map -> base transform stops the robot
  double map_timeout = 10.0;        // seconds (ROS time) without a new map (mapper down) stop the robot; 0 = never
  bool start_paused = false;        // wait for true on ~resume before exploring
  // Lockstep with the simulator (its ~lockstep_nodes) behind this mapper node: one control step per scan, at the
  // scan's stamp, with the map and map -> odom the mapper reported for the scan before, planning in place; each
  // step is reported on `lockstep`. "" = free-running on the control timer.
  std::string lockstep_mapper;
  std::string odom_frame = "odom";  // lockstep: the frame the robot's pose is chained through (map -> odom -> base)
  double lockstep_wait = 5.0;       // wall seconds a lockstep step waits for the mapper's results before holding
};

// The node's own parameters (frames, rates, timeouts); the policy's are in the core's tables.
const common::OptionTable<ExplorerOptions>& explorerNodeOptionTable();
// Every parameter of the node, as docs/ros_api.md lists them.
std::vector<common::OptionDescription> explorerParameters();
// Reads the options from the private node handle. Throws InputError naming the first bad parameter.
ExplorerOptions readExplorerOptions(const ros::NodeHandle& private_nh);

// Nearest-frontier exploration (replaces explore + move_base) with the core's ExplorationPolicy on the latest
// `map`, the robot's pose from tf and the laser on `base_scan`: publishes its commands on `cmd_vel`, its state on
// `exploration_markers`, the latched `exploration_done` and `exploration_status`, and logs its events. Stops (and
// holds the policy) while the map, the pose or the scan is stale, and while paused: false on `~resume`
// (std_msgs/Bool, as explore_lite's resume topic) pauses, true resumes with the same goal and blacklist. In
// lockstep (~lockstep_mapper) the steps follow the scans instead of the timer (see ExplorerOptions).
class Explorer {
 public:
  // Subscribes and advertises; does not wait for anything (the control timer does the work).
  Explorer(ros::NodeHandle nh, const ExplorerOptions& options);

  bool done() const { return policy_.done(); }

 private:
  void onMap(const nav_msgs::OccupancyGrid::ConstPtr& map);
  void onScan(const sensor_msgs::LaserScan::ConstPtr& scan);
  void onResume(const std_msgs::Bool::ConstPtr& resume);
  void onTimer(const ros::TimerEvent& event);
  void onLockstepAck(const hidden_rooms::LockstepAck::ConstPtr& ack);
  // Gives the policy a map (stamped `received` for the map timeout).
  void applyMap(const nav_msgs::OccupancyGrid::ConstPtr& map, const ros::Time& received);
  // The control step at ROS time `now`: checks the map, pose and scan, updates the policy, publishes.
  void controlStep(const ros::Time& now);
  // Lockstep: takes the control step of the pending scan once the mapper's results for the scan before it (its
  // report, the map it names) are here, or after ~lockstep_wait without them; then reports. The first step waits
  // until the mapper's reports and maps and the simulator's cmd_vel are connected, so that none is missed.
  void tryLockstepStep();
  void reportLockstep(const ros::Time& stamp);
  bool robotPose(const ros::Time& now, common::Pose2* pose);
  // Stops the robot from outside the policy (stale map, pose or scan): the follower's timers do not count it.
  void holdRobot(const ros::Time& now);
  // Logs the policy's events as ROS_INFO / ROS_WARN lines and publishes exploration_done when it changes.
  void report(const exploration::ExplorationStep& step, const ros::Time& now);
  void publishCommand(const common::VelocityCommand& command);
  void publishMarkers(const ros::Time& now);
  void publishStatus(const ros::Time& now);

  ExplorerOptions options_;
  exploration::ExplorationPolicy policy_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  nav_msgs::OccupancyGrid::ConstPtr latest_map_;
  ros::Time map_received_;  // ROS time the latest map arrived
  bool map_stale_ = false;  // stopped because no map came for map_timeout
  sensor_msgs::LaserScan::ConstPtr latest_scan_;
  std::vector<common::Point2> scan_points_;  // latest scan's returns in base_frame
  bool scan_remembered_ = true;      // the latest scan was given to the policy
  bool stopped_ = true;  // the last command sent was a stop
  bool paused_ = false;  // by ~resume (or ~start_paused)
  // Statistics for the log.
  std::optional<common::Pose2> last_pose_;
  double distance_driven_ = 0.0;
  int goals_chosen_ = 0;
  int goals_reached_ = 0;
  int goals_failed_ = 0;
  ros::Subscriber map_subscriber_;
  ros::Subscriber scan_subscriber_;
  ros::Subscriber resume_subscriber_;
  ros::Publisher command_publisher_;
  ros::Publisher done_publisher_;
  ros::Publisher markers_publisher_;
  ros::Publisher status_publisher_;
  ros::Timer timer_;
  // Lockstep state.
  std::string lockstep_mapper_;  // resolved name; "" = free-running
  ros::Subscriber lockstep_subscriber_;
  ros::Publisher lockstep_publisher_;
  std::deque<hidden_rooms::LockstepAck> mapper_acks_;  // the mapper's reports not yet used, oldest first
  std::deque<nav_msgs::OccupancyGrid::ConstPtr> pending_maps_;  // maps not yet given to the policy, oldest first
  sensor_msgs::LaserScan::ConstPtr pending_scan_;  // the scan whose step is due
  ros::WallTime pending_since_;
  ros::Time last_step_stamp_;       // stamp of the last scan stepped
  bool mapper_heard_ = false;       // a report of the mapper's has come (its `lockstep` reaches this node)
  std::optional<common::Pose2> map_to_odom_;  // map -> odom of the step's pose (the mapper's report)
  uint32_t commands_published_ = 0;
};

}  // namespace hidden_rooms
