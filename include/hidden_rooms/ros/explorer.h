#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "hidden_rooms/exploration/frontier.h"
#include "hidden_rooms/exploration/grid_planner.h"
#include "hidden_rooms/exploration/path_follower.h"

namespace hidden_rooms {

// Parameters of the explorer node (all private, ~name; see docs/ros_api.md and config/explorer.yaml).
struct ExplorerOptions {
  GridPlannerOptions planner;    // inflation, proximity cost, smoothing
  FrontierOptions frontiers;     // frontier filtering, goal reach
  PathFollowerOptions follower;  // pure pursuit, laser speed limit, recovery
  BlockedPassagesOptions passages;  // gaps the robot failed to pass, blocked for the planner
  std::string map_frame = "map";
  std::string base_frame = "base_link";
  double control_rate = 10.0;       // Hz of ROS time: commands (and replanning when due)
  double replan_interval = 2.0;     // seconds of ROS time between replans without a new map (0 = only on new maps)
  double goal_hysteresis = 1.0;     // metres of path cost the current goal may exceed the best before switching
  double blacklist_radius = 0.8;    // metres around a failed or reached goal where no goal is chosen again
  int done_confirmations = 3;       // plans on new maps in a row without a reachable frontier before done
  double search_angular_velocity = 0.4;  // rad/s turned in place while there is no goal (and not done)
  double scan_timeout = 1.0;        // seconds (ROS time): an older scan stops the robot
  double pose_timeout = 1.0;        // seconds (ROS time): an older map -> base transform stops the robot
  double map_timeout = 10.0;        // seconds (ROS time) without a new map (mapper down) stop the robot; 0 = never
  double obstacle_memory = 1.5;     // seconds (ROS time) laser points are remembered (for the robot's blind rear)
};

// Reads the options from the private node handle. Throws InputError for a bad value.
ExplorerOptions readExplorerOptions(const ros::NodeHandle& private_nh);

// Nearest-frontier exploration (replaces explore + move_base): frontiers of the latest `map`, the one nearest by
// path cost as goal, a wavefront path to it, pure pursuit with a laser speed limit on `base_scan`, recovery, a
// blacklist and blocked passages. Publishes `cmd_vel`, `exploration_markers` and the latched `exploration_done`.
// Stops (and holds the follower) while the map, the pose or the scan is stale; does not report done while goals
// failed only because the robot could not move.
class Explorer {
 public:
  // Subscribes and advertises; does not wait for anything (the control timer does the work).
  Explorer(ros::NodeHandle nh, const ExplorerOptions& options);

  bool done() const { return done_; }

 private:
  void onMap(const nav_msgs::OccupancyGrid::ConstPtr& map);
  void onScan(const sensor_msgs::LaserScan::ConstPtr& scan);
  void onTimer(const ros::TimerEvent& event);
  bool robotPose(Pose2* pose);
  // Stops the robot from outside the follower (stale map, pose or scan): the follower's timers do not count it.
  void holdRobot(const ros::Time& now);
  // Chooses a goal and a path from `pose`; sets done_ after done_confirmations plans without a goal.
  void plan(const Pose2& pose, const ros::Time& now);
  void setDone(bool done, const ros::Time& now);
  void publishCommand(const VelocityCommand& command);
  void publishMarkers(const FrontierMap& frontiers, const ros::Time& now);

  ExplorerOptions options_;
  GridPlanner planner_;
  PathFollower follower_;
  Blacklist blacklist_;
  BlockedPassages passages_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  nav_msgs::OccupancyGrid::ConstPtr latest_map_;
  ros::Time map_received_;  // ROS time the latest map arrived
  bool map_stale_ = false;  // stopped because no map came for map_timeout
  bool map_changed_ = false;
  sensor_msgs::LaserScan::ConstPtr latest_scan_;
  std::vector<Point2> scan_points_;  // latest scan's returns in base_frame
  bool scan_remembered_ = true;      // the latest scan is in obstacle_memory_
  ObstacleMemory obstacle_memory_;
  std::optional<FrontierGoal> goal_;
  ros::Time last_plan_;
  int plans_without_goal_ = 0;
  bool done_ = false;
  bool stopped_ = true;  // the last command sent was a stop
  // Statistics for the log.
  std::optional<Pose2> last_pose_;
  double distance_driven_ = 0.0;
  int goals_chosen_ = 0;
  ros::Subscriber map_subscriber_;
  ros::Subscriber scan_subscriber_;
  ros::Publisher command_publisher_;
  ros::Publisher done_publisher_;
  ros::Publisher markers_publisher_;
  ros::Timer timer_;
};

}  // namespace hidden_rooms
