#include "hidden_rooms/ros/simulator.h"

#include <cmath>

#include <XmlRpcValue.h>
#include <ros/callback_queue.h>
#include <geometry_msgs/PolygonStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/LaserScan.h>

#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/ros/lockstep.h"
#include "hidden_rooms/ros/parameters.h"
#include "hidden_rooms/world/environment.h"

namespace hidden_rooms {

namespace {

constexpr double kPi = 3.14159265358979323846;

// The walls as rendered: door_width (~wall_thickness is optional, read by hand).
const common::OptionTable<world::RenderOptions>& simulatorRenderOptionTable() {
  using O = world::RenderOptions;
  static const common::OptionTable<O> table{
      {"door_width", &O::door_width, "the walls as rendered: gap at open doors, metres", common::above(0)},
  };
  return table;
}

std::string poseText(const common::Pose2& pose) {
  return "[" + common::formatNumber(pose.x) + ", " + common::formatNumber(pose.y) + ", " +
         common::formatNumber(pose.yaw) + "]";
}

// The parameters readSimulatorOptions reads by explicit code, as docs/ros_api.md lists them.
std::vector<common::OptionDescription> explicitParameters() {
  const SimulatorOptions defaults;
  const simulation::SimulationOptions& simulation = defaults.simulation;
  const simulation::OdometryNoiseOptions& noise = simulation.odometry_noise;
  return {
      {"closed_doors", "string", "\"" + defaults.closed_doors + "\"", "environment doors closed at start"},
      {"wall_thickness", "double", "0", "the walls as rendered, metres; 0 = the file's own, else 0.15"},
      {"seed", "int", std::to_string(simulation.seed), "random seed (laser noise, odometry error)"},
      {"laser_field_of_view", "double", common::formatNumber(simulation.laser.field_of_view),
       "radians (REP-103), centred on the laser's x axis"},
      {"laser_caster", "string", "\"" + std::string(simulation::toString(simulation.laser.caster)) + "\"",
       "box2d or grid"},
      {"laser_pose", "[x, y, yaw]", poseText(simulation.laser.mount), "base_link -> base_laser_link"},
      {"odom_error", "[x, y, yaw]", poseText({noise.x, noise.y, noise.yaw}), "Stage's odom_error"},
      {"start_pose", "[x, y, yaw]", "[]", "start pose in the world frame; empty = chosen"},
  };
}

// A [x, y, yaw] list parameter of finite numbers; false when it is not set or empty. Throws InputError("~name")
// for anything else.
bool readPose(const ros::NodeHandle& nh, const std::string& name, common::Pose2* pose) {
  XmlRpc::XmlRpcValue value;
  if (!nh.getParam(name, value)) return false;
  const common::InputError bad("~" + name, "must be a list [x, y, yaw] of finite numbers");
  if (value.getType() != XmlRpc::XmlRpcValue::TypeArray) throw bad;
  if (value.size() == 0) return false;
  if (value.size() != 3) throw bad;
  double xyz[3];
  for (int k = 0; k < 3; ++k) {
    const bool is_int = value[k].getType() == XmlRpc::XmlRpcValue::TypeInt;
    if (!is_int && value[k].getType() != XmlRpc::XmlRpcValue::TypeDouble) throw bad;
    xyz[k] = is_int ? static_cast<int>(value[k]) : static_cast<double>(value[k]);
    if (!std::isfinite(xyz[k])) throw bad;
  }
  *pose = {xyz[0], xyz[1], xyz[2]};
  return true;
}

// "a, b" -> the names resolved in the node's namespace ({"/a", "/b"}). Throws InputError("~parameter", ...) for an
// invalid name.
std::vector<std::string> resolvedNodeNames(const std::string& list, const std::string& parameter) {
  std::vector<std::string> names;
  for (const std::string& name : common::splitList(list))
    if (!name.empty()) names.push_back(resolvedNodeName(name, parameter));
  return names;
}

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

uint64_t periodInSteps(double rate, double physics_step, const std::string& name) {
  if (!std::isfinite(rate) || rate <= 0.0) throw common::InputError("~" + name, "must be positive");
  return std::max<uint64_t>(1, static_cast<uint64_t>(std::llround(1.0 / (rate * physics_step))));
}

}  // namespace

const common::OptionTable<SimulatorOptions>& simulatorNodeOptionTable() {
  using O = SimulatorOptions;
  static const common::OptionTable<O> table{
      {"environment", &O::environment, "environment XML (set exactly one of this, ~map_file, ~bitmap)"},
      {"map_file", &O::map_file, "map_server yaml of a bitmap world"},
      {"bitmap", &O::bitmap, "Stage-style image (dark = wall), lower-left corner at the origin"},
      {"bitmap_resolution", &O::bitmap_resolution, "metres per pixel of ~bitmap", common::above(0)},
      {"realtime_factor", &O::realtime_factor, "simulated seconds per wall-clock second; 0 = as fast as possible",
       common::atLeast(0)},
      {"laser_rate", &O::laser_rate, "Hz of simulated time (base_scan)", common::above(0)},
      {"odom_rate", &O::odom_rate, "Hz of simulated time (odom, base_pose_ground_truth, tf)", common::above(0)},
      {"clock_rate", &O::clock_rate, "Hz of simulated time (/clock)", common::above(0)},
      {"duration", &O::duration, "simulated seconds after which the node exits; 0 = until shut down",
       common::atLeast(0)},
      {"world_frame", &O::world_frame, "frame of the world (environment / map)"},
      {"odom_frame", &O::odom_frame, "frame of the odometry"},
      {"base_frame", &O::base_frame, "frame of the robot"},
      {"laser_frame", &O::laser_frame, "frame of the laser"},
      {"publish_world_to_odom", &O::publish_world_to_odom, "static tf world -> odom at the start pose"},
      {"lockstep_nodes", &O::lockstep_nodes,
       "nodes (comma-separated) that must report each scan on `lockstep` before the world steps on; \"\" = none"},
      {"lockstep_start_nodes", &O::lockstep_start_nodes,
       "nodes (comma-separated) that must report ready on `lockstep`, after the ~lockstep_nodes have, before the "
       "world starts (nodes that must see every message, such as the pose logger); \"\" = none"},
      {"run_until", &O::run_until, "simulated seconds to hold the clock at from the start (as the run_until "
       "service); 0 = no hold", common::atLeast(0)},
      {"lockstep_timeout", &O::lockstep_timeout, "wall seconds to wait for one scan's reports before stepping on",
       common::above(0)},
  };
  return table;
}

std::vector<common::OptionDescription> simulatorParameters() {
  std::vector<common::OptionDescription> rows;
  for (const std::vector<common::OptionDescription>& more :
       {common::describeOptions(simulatorNodeOptionTable()), common::describeOptions(simulatorRenderOptionTable()),
        common::describeOptions(simulation::simulationOptionTable()),
        common::describeOptions(simulation::robotOptionTable()),
        common::describeOptions(simulation::laserOptionTable()), explicitParameters()})
    rows.insert(rows.end(), more.begin(), more.end());
  return rows;
}

SimulatorOptions readSimulatorOptions(const ros::NodeHandle& nh) {
  SimulatorOptions options;
  readParameters(nh, simulatorNodeOptionTable(), &options);
  readTextParameter(nh, "closed_doors", &options.closed_doors);
  readParameters(nh, simulatorRenderOptionTable(), &options.render);
  readPositiveParameter(nh, "wall_thickness", &options.render.wall_thickness);  // else the file's own

  simulation::SimulationOptions& simulation = options.simulation;
  readParameters(nh, simulation::simulationOptionTable(), &simulation);
  int seed = static_cast<int>(simulation.seed);
  readParameter(nh, "seed", &seed);
  if (seed < 0) throw common::InputError("~seed", "must be zero or positive");
  simulation.seed = static_cast<uint64_t>(seed);
  readParameters(nh, simulation::robotOptionTable(), &simulation.robot);
  simulation::LaserOptions& laser = simulation.laser;
  readParameters(nh, simulation::laserOptionTable(), &laser);
  readParameter(nh, "laser_field_of_view", &laser.field_of_view);
  if (!(laser.field_of_view > 0.0 && laser.field_of_view <= 2.0 * kPi))
    throw common::InputError("~laser_field_of_view", "must be in (0, 2 pi] radians (REP-103; 270 degrees is 4.712), got " +
                                                         common::formatNumber(laser.field_of_view));
  readPose(nh, "laser_pose", &laser.mount);
  std::string caster = simulation::toString(laser.caster);
  readParameter(nh, "laser_caster", &caster);
  try {
    laser.caster = simulation::laserCasterFromString(caster);
  } catch (const common::InputError& error) {
    throw common::InputError("~laser_caster", error.problem());
  }
  simulation::OdometryNoiseOptions& noise = simulation.odometry_noise;
  common::Pose2 odom_error{noise.x, noise.y, noise.yaw};
  readPose(nh, "odom_error", &odom_error);
  for (double error : {odom_error.x, odom_error.y, odom_error.yaw})
    if (error < 0.0 || error >= 2.0) throw common::InputError("~odom_error", "must be in [0, 2) per axis");
  noise = {odom_error.x, odom_error.y, odom_error.yaw};
  common::Pose2 start;
  if (readPose(nh, "start_pose", &start)) simulation.start_pose = start;
  validate(simulation);  // the rules between parameters

  const int sources = !options.environment.empty() + !options.map_file.empty() + !options.bitmap.empty();
  if (sources != 1)
    throw common::InputError(nh.getNamespace(), "set exactly one of ~environment, ~map_file and ~bitmap");
  if (options.environment.empty() && !options.closed_doors.empty())
    throw common::InputError("~closed_doors", "applies to ~environment worlds only");
  return options;
}

Simulator::Simulator(ros::NodeHandle nh, const SimulatorOptions& options) : options_(options) {
  simulation::SimulationWorld world;
  if (!options.environment.empty()) {
    const world::Environment environment = world::loadEnvironment(options.environment);
    for (const std::string& repair : environment.repairs)
      ROS_WARN("%s: %s", options.environment.c_str(), repair.c_str());
    world = simulation::worldFromEnvironment(
        environment, world::parseDoorSelection(environment, options.closed_doors, "~closed_doors"), options.render);
  } else if (!options.map_file.empty()) {
    world = simulation::worldFromGrid(common::loadMap(options.map_file));
  } else {
    const cv::Mat image = common::readImage(options.bitmap);
    common::MapMetadata metadata;
    metadata.image = options.bitmap;
    metadata.resolution = options.bitmap_resolution;
    world = simulation::worldFromGrid(common::gridFromImage(image, metadata));
  }
  simulation_ = std::make_unique<simulation::Simulation>(world, options.simulation);
  const double dt = options.simulation.physics_step;
  laser_period_steps_ = periodInSteps(options.laser_rate, dt, "laser_rate");
  odom_period_steps_ = periodInSteps(options.odom_rate, dt, "odom_rate");
  clock_period_steps_ = periodInSteps(options.clock_rate, dt, "clock_rate");

  clock_publisher_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  scan_publisher_ = nh.advertise<sensor_msgs::LaserScan>("base_scan", 10);
  odom_publisher_ = nh.advertise<nav_msgs::Odometry>("odom", 10);
  ground_truth_publisher_ = nh.advertise<nav_msgs::Odometry>("base_pose_ground_truth", 10);
  command_subscriber_ = nh.subscribe("cmd_vel", 10, &Simulator::onCommand, this);
  reset_service_ = nh.advertiseService("reset", &Simulator::onReset, this);
  set_door_service_ = nh.advertiseService("set_door", &Simulator::onSetDoor, this);
  run_until_service_ = nh.advertiseService("run_until", &Simulator::onRunUntil, this);
  run_until_ = options.run_until;
  lockstep_nodes_ = resolvedNodeNames(options.lockstep_nodes, "lockstep_nodes");
  lockstep_start_nodes_ = resolvedNodeNames(options.lockstep_start_nodes, "lockstep_start_nodes");
  if (!lockstep_nodes_.empty() || !lockstep_start_nodes_.empty())
    lockstep_subscriber_ = nh.subscribe("lockstep", 100, &Simulator::onLockstepAck, this);
  if (!lockstep_nodes_.empty())
    ROS_INFO("simulator: lockstep with %s: each scan waits for their reports on %s", joined(lockstep_nodes_).c_str(),
             lockstep_subscriber_.getTopic().c_str());
  footprint_publisher_ = nh.advertise<geometry_msgs::PolygonStamped>("footprint", 1, true);

  footprint_.header.frame_id = options.base_frame;
  const double half_length = 0.5 * options.simulation.robot.length, half_width = 0.5 * options.simulation.robot.width;
  for (const auto& [x, y] : {std::pair<double, double>{half_length, half_width}, {-half_length, half_width},
                             {-half_length, -half_width}, {half_length, -half_width}}) {
    geometry_msgs::Point32 corner;
    corner.x = static_cast<float>(x);
    corner.y = static_cast<float>(y);
    footprint_.polygon.points.push_back(corner);
  }

  std::vector<geometry_msgs::TransformStamped> fixed{
      toTransform(options.simulation.laser.mount, options.base_frame, options.laser_frame, now())};
  if (options.publish_world_to_odom)
    fixed.push_back(toTransform(simulation_->startPose(), options.world_frame, options.odom_frame, now()));
  static_tf_broadcaster_.sendTransform(fixed);
}

ros::Time Simulator::now() const {
  // Simulated time starts at 0; the first message is stamped one physics step later (ROS time 0 means unset).
  return ros::Time(simulation_->time());
}

void Simulator::run() {
  waitForStart();
  // Pacing restarts after each hold at the run_until time.
  ros::WallTime wall_start = ros::WallTime::now();
  double start = simulation_->time();
  while (ros::ok()) {
    ros::spinOnce();
    if (holding()) {
      ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.01));
      wall_start = ros::WallTime::now();
      start = simulation_->time();
      continue;
    }
    if (step() && !lockstep_nodes_.empty()) waitForLockstep();
    if (options_.duration > 0.0 && simulation_->time() >= options_.duration - 1e-9) break;
    if (options_.realtime_factor > 0.0) {
      const ros::WallTime due = wall_start + ros::WallDuration((simulation_->time() - start) / options_.realtime_factor);
      const ros::WallTime wall_now = ros::WallTime::now();
      if (due > wall_now) (due - wall_now).sleep();
    }
  }
}

bool Simulator::step() {
  simulation_->step();
  const uint64_t steps = simulation_->steps();
  if (steps % clock_period_steps_ == 0) publishClock();
  if (steps % odom_period_steps_ == 0) publishOdometry();
  if (steps % laser_period_steps_ != 0) return false;
  publishScan();
  return true;
}

bool Simulator::holding() const { return run_until_ > 0.0 && simulation_->time() >= run_until_ - 1e-9; }

std::vector<std::string> Simulator::lockstepMissing() const {
  const ros::Time stamp = last_scan_.header.stamp;
  std::vector<std::string> missing;
  for (const std::string& node : lockstep_nodes_) {
    const auto ack = lockstep_acks_.find(node);
    const auto commands = commands_received_.find(node);
    const uint32_t received = commands == commands_received_.end() ? 0 : commands->second;
    if (ack == lockstep_acks_.end() || ack->second.stamp < stamp || received < ack->second.commands)
      missing.push_back(node);
  }
  return missing;
}

void Simulator::waitForStart() {
  if (lockstep_nodes_.empty() && lockstep_start_nodes_.empty()) return;
  const ros::WallTime started = ros::WallTime::now();
  const auto wait = [&](const std::vector<std::string>& nodes, const char* what) {
    const auto missing = [&] {
      std::vector<std::string> names;
      for (const std::string& node : nodes)
        if (!lockstep_acks_.count(node)) names.push_back(node);
      return names;
    };
    while (!missing().empty() && ros::ok()) {
      if ((ros::WallTime::now() - started).toSec() > options_.lockstep_timeout) {
        ROS_WARN("simulator: lockstep: %s %s not ready in %.0f s (wall); starting without them", what,
                 joined(missing()).c_str(), options_.lockstep_timeout);
        return;
      }
      ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.01));
    }
  };
  wait(lockstep_nodes_, "nodes");
  // Only a report sent once the lockstep nodes are up counts: it says its sender hears their publications too.
  for (const std::string& node : lockstep_start_nodes_) lockstep_acks_.erase(node);
  wait(lockstep_start_nodes_, "start nodes");
}

void Simulator::waitForLockstep() {
  lockstep_waiting_ = true;
  const ros::WallTime started = ros::WallTime::now();
  ros::WallTime last_sent = started;
  std::vector<std::string> missing = lockstepMissing();
  while (!missing.empty() && ros::ok()) {
    const ros::WallTime wall_now = ros::WallTime::now();
    if ((wall_now - started).toSec() > options_.lockstep_timeout) {
      ROS_WARN("simulator: lockstep: no report of the scan at %.2f s from %s in %.0f s (wall); stepping on",
               last_scan_.header.stamp.toSec(), joined(missing).c_str(), options_.lockstep_timeout);
      break;
    }
    if ((wall_now - last_sent).toSec() >= 1.0) {  // a node that subscribed after the scan was sent gets it now
      clock_publisher_.publish(last_clock_);
      tf_broadcaster_.sendTransform(last_odometry_transform_);
      scan_publisher_.publish(last_scan_);
      last_sent = wall_now;
    }
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.001));
    missing = lockstepMissing();
  }
  lockstep_waiting_ = false;
}

void Simulator::publishClock() {
  last_clock_.clock = now();
  clock_publisher_.publish(last_clock_);
}

void Simulator::publishScan() {
  simulation_->scan(&ranges_);
  last_scan_ = toRos(ranges_, simulation_->laserGeometry(), options_.simulation.laser.min_range,
                     laser_period_steps_ * options_.simulation.physics_step, options_.laser_frame, now());
  scan_publisher_.publish(last_scan_);
}

void Simulator::publishOdometry() {
  const ros::Time stamp = now();
  const common::Pose2 odometry = simulation_->odometryPose();
  odom_publisher_.publish(toRos(odometry, simulation_->odometryVelocity(), options_.odom_frame, options_.base_frame, stamp));
  ground_truth_publisher_.publish(
      toRos(simulation_->truePose(), simulation_->velocity(), options_.world_frame, options_.base_frame, stamp));
  last_odometry_transform_ = toTransform(odometry, options_.odom_frame, options_.base_frame, stamp);
  tf_broadcaster_.sendTransform(last_odometry_transform_);
  // Stamped with the pose it goes with: rviz places a polygon once, at its stamp's transform.
  footprint_.header.stamp = stamp;
  footprint_publisher_.publish(footprint_);
}

void Simulator::onCommand(const ros::MessageEvent<geometry_msgs::Twist const>& event) {
  ++commands_received_[event.getPublisherName()];
  try {
    simulation_->setCommand(fromRos(*event.getMessage()));
  } catch (const common::InputError& error) {
    ROS_WARN_THROTTLE(1.0, "simulator: ignoring %s", error.what());
  }
}

void Simulator::onLockstepAck(const hidden_rooms::LockstepAck::ConstPtr& ack) {
  hidden_rooms::LockstepAck& last = lockstep_acks_[ack->node];
  if (ack->stamp >= last.stamp) last = *ack;  // a late re-sent report never goes back
}

bool Simulator::onRunUntil(hidden_rooms::RunUntil::Request& request, hidden_rooms::RunUntil::Response& response) {
  response.now = simulation_->time();
  if (!std::isfinite(request.time) || request.time < 0.0) {
    response.success = false;
    response.message = "time must be a finite number of seconds >= 0 (0 = no limit), got " +
                       common::formatNumber(request.time);
    return true;
  }
  run_until_ = request.time;
  response.success = true;
  response.reached = holding() && !lockstep_waiting_;
  for (const auto& [node, ack] : lockstep_acks_)
    if (ack.finished) response.finished.push_back(node);
  response.message = run_until_ == 0.0 ? "running without a limit"
                     : response.reached ? "holding at " + common::formatNumber(response.now) + " s"
                                        : "running to " + common::formatNumber(run_until_) + " s";
  return true;
}

bool Simulator::onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  simulation_->reset();
  const common::Pose2& start = simulation_->startPose();
  response.success = true;
  response.message = "robot back at its start pose (" + std::to_string(start.x) + ", " + std::to_string(start.y) +
                     ", " + std::to_string(start.yaw) + "), odometry at zero";
  return true;
}

bool Simulator::onSetDoor(hidden_rooms::SetDoor::Request& request, hidden_rooms::SetDoor::Response& response) {
  try {
    simulation_->setDoor(request.door, request.open);
    const int index = simulation_->world().findDoor(request.door);
    const simulation::SimulationWorld::DoorLeaf& door = simulation_->world().doors[index];
    response.success = true;
    response.message = "door " + std::to_string(door.number) + " (" + door.id + ") " + (request.open ? "open" : "closed");
  } catch (const common::InputError& error) {
    response.success = false;
    response.message = error.what();
  }
  return true;
}

}  // namespace hidden_rooms
