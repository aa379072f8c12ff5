#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <geometry_msgs/PolygonStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Twist.h>
#include <hidden_rooms/LockstepAck.h>
#include <hidden_rooms/RunUntil.h>
#include <hidden_rooms/SetDoor.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/LaserScan.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include "hidden_rooms/common/options.h"
#include "hidden_rooms/simulation/simulation.h"
#include "hidden_rooms/world/render.h"

namespace hidden_rooms {

// Parameters of the simulator node (all private, ~name; see docs/ros_api.md and config/simulation.yaml).
struct SimulatorOptions {
  std::string environment;   // environment XML (set this, ~map_file or ~bitmap)
  std::string map_file;      // map_server yaml of a bitmap world
  std::string bitmap;        // Stage-style image (dark = wall), with ~bitmap_resolution
  double bitmap_resolution = 0.05;  // metres per pixel of ~bitmap; its lower-left corner is the world origin
  std::string closed_doors;  // environment doors closed at start: numbers or ids, comma-separated, or "all"
  world::RenderOptions render;  // door_width, wall_thickness (the world's walls as rendered)
  simulation::SimulationOptions simulation;
  double realtime_factor = 1.0;   // simulated seconds per wall-clock second; 0 = as fast as possible
  double laser_rate = 10.0;       // Hz of simulated time
  double odom_rate = 20.0;        // Hz of simulated time (odom, base_pose_ground_truth, tf odom -> base_link)
  double clock_rate = 100.0;      // Hz of simulated time (/clock); at most once per physics step
  double duration = 0.0;          // simulated seconds after which the node exits; 0 = run until shut down
  // Lockstep: nodes (names, comma-separated, resolved in the node's namespace) that must report each scan on
  // `lockstep` (and whose reported cmd_vel must have arrived) before the world steps on; "" = free-running.
  std::string lockstep_nodes;
  // Nodes that must report ready on `lockstep`, after the lockstep nodes have, before the world starts: nodes that
  // must see every message from the first (the pose logger's ~lockstep); "" = none.
  std::string lockstep_start_nodes;
  double run_until = 0.0;          // simulated seconds to hold the clock at until run_until asks for more; 0 = none
  double lockstep_timeout = 30.0;  // wall seconds to wait for the reports of one scan before stepping on anyway
  std::string world_frame = "world";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  std::string laser_frame = "base_laser_link";
  bool publish_world_to_odom = false;  // tf world -> odom at the start pose (for viewing without SLAM)
};

// The node's own parameters (world source, rates, frames, ...); the simulation's are in the core's tables.
const common::OptionTable<SimulatorOptions>& simulatorNodeOptionTable();
// Every parameter of the node, as docs/ros_api.md lists them: the tables' and, by hand, those read by explicit
// code (closed_doors, wall_thickness, seed, laser_field_of_view, laser_caster and the [x, y, yaw] poses).
std::vector<common::OptionDescription> simulatorParameters();

// Reads the options from the private node handle. Throws InputError for a bad value or a world source missing
// or given twice.
SimulatorOptions readSimulatorOptions(const ros::NodeHandle& private_nh);

// Stage/stage_ros's job on the core's Box2D simulation: steps the world with a fixed physics step at
// `realtime_factor`, publishes /clock, base_scan, odom, base_pose_ground_truth and tf, follows cmd_vel, and
// serves reset, set_door and run_until (hold the clock at a time). In lockstep (~lockstep_nodes) it starts once
// those nodes and the ~lockstep_start_nodes have reported ready, and waits after each scan until every lockstep
// node has reported it on `lockstep` and their commands have arrived, re-sending the scan with its clock and
// odometry every second meanwhile (to a node that subscribed late): the same seed then gives the same run however
// fast the machine is.
class Simulator {
 public:
  // Loads the world and builds the simulation (throws InputError when it cannot); does not wait for anything.
  Simulator(ros::NodeHandle nh, const SimulatorOptions& options);

  // Steps and publishes until ROS shuts down or ~duration is reached, pacing to realtime_factor, holding at the
  // run_until time and waiting for the lockstep nodes after each scan.
  void run();
  // One physics step and whatever is due after it (publications at their rates); true when a scan was published.
  // Callbacks are not handled.
  bool step();
  const simulation::Simulation& simulation() const { return *simulation_; }
  ros::Time now() const;

 private:
  void onCommand(const ros::MessageEvent<geometry_msgs::Twist const>& event);
  void onLockstepAck(const hidden_rooms::LockstepAck::ConstPtr& ack);
  bool onRunUntil(hidden_rooms::RunUntil::Request& request, hidden_rooms::RunUntil::Response& response);
  bool holding() const;
  // Lockstep nodes that have not yet reported the last scan (or whose reported commands have not arrived).
  std::vector<std::string> lockstepMissing() const;
  // Before the first step: handles callbacks until every lockstep node has reported, then until every start node
  // has reported again (at most ~lockstep_timeout in all; then it warns, naming them, and starts).
  void waitForStart();
  // Handles callbacks until lockstepMissing() is empty, re-sending the last scan every wall second; after
  // ~lockstep_timeout it warns, naming the nodes, and returns.
  void waitForLockstep();
  bool onReset(std_srvs::Trigger::Request& request, std_srvs::Trigger::Response& response);
  bool onSetDoor(hidden_rooms::SetDoor::Request& request, hidden_rooms::SetDoor::Response& response);
  void publishClock();
  void publishScan();
  void publishOdometry();

  SimulatorOptions options_;
  std::unique_ptr<simulation::Simulation> simulation_;
  uint64_t laser_period_steps_ = 1;
  uint64_t odom_period_steps_ = 1;
  uint64_t clock_period_steps_ = 1;
  std::vector<float> ranges_;
  // The last publications, kept for lockstep's re-sending: the same messages, not a new noisy scan.
  rosgraph_msgs::Clock last_clock_;
  sensor_msgs::LaserScan last_scan_;
  geometry_msgs::TransformStamped last_odometry_transform_;
  std::vector<std::string> lockstep_nodes_;  // resolved names
  std::vector<std::string> lockstep_start_nodes_;
  std::map<std::string, hidden_rooms::LockstepAck> lockstep_acks_;  // each node's last report
  std::map<std::string, uint32_t> commands_received_;  // cmd_vel messages by publisher
  bool lockstep_waiting_ = false;
  double run_until_ = 0.0;  // simulated seconds to hold at; 0 = none
  ros::Publisher clock_publisher_;
  ros::Publisher scan_publisher_;
  ros::Publisher odom_publisher_;
  ros::Publisher ground_truth_publisher_;
  ros::Publisher footprint_publisher_;
  geometry_msgs::PolygonStamped footprint_;  // the robot's outline in base_frame, re-stamped with each odometry
  ros::Subscriber command_subscriber_;
  ros::ServiceServer reset_service_;
  ros::ServiceServer set_door_service_;
  ros::ServiceServer run_until_service_;
  ros::Subscriber lockstep_subscriber_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  tf2_ros::StaticTransformBroadcaster static_tf_broadcaster_;
};

}  // namespace hidden_rooms
