#include "hidden_rooms/ros/simulator.h"

#include <cmath>
#include <thread>

#include <geometry_msgs/PolygonStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/LaserScan.h>

#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/world/environment.h"

namespace hidden_rooms {

namespace {

constexpr double kPi = 3.14159265358979323846;

// A [x, y, yaw] list parameter; false when it is not set or empty.
bool readPose(const ros::NodeHandle& nh, const std::string& name, common::Pose2* pose) {
  std::vector<double> values;
  if (!nh.getParam(name, values) || values.empty()) return false;
  if (values.size() != 3) throw common::InputError("~" + name, "must be a list [x, y, yaw]");
  *pose = {values[0], values[1], values[2]};
  return true;
}

// A text parameter that roslaunch may have typed as a number ("3" -> 3), e.g. a single door number.
std::string readText(const ros::NodeHandle& nh, const std::string& name, const std::string& fallback) {
  XmlRpc::XmlRpcValue value;
  if (!nh.getParam(name, value)) return fallback;
  switch (value.getType()) {
    case XmlRpc::XmlRpcValue::TypeString: return static_cast<std::string>(value);
    case XmlRpc::XmlRpcValue::TypeInt: return std::to_string(static_cast<int>(value));
    default:
      throw common::InputError("~" + name, "must be text (door numbers or ids, comma-separated, or 'all')");
  }
}

uint64_t periodInSteps(double rate, double physics_step, const std::string& name) {
  if (!std::isfinite(rate) || rate <= 0.0) throw common::InputError("~" + name, "must be positive");
  return std::max<uint64_t>(1, static_cast<uint64_t>(std::llround(1.0 / (rate * physics_step))));
}

}  // namespace

SimulatorOptions readSimulatorOptions(const ros::NodeHandle& nh) {
  SimulatorOptions options;
  nh.param("environment", options.environment, options.environment);
  nh.param("map_file", options.map_file, options.map_file);
  nh.param("bitmap", options.bitmap, options.bitmap);
  nh.param("bitmap_resolution", options.bitmap_resolution, options.bitmap_resolution);
  options.closed_doors = readText(nh, "closed_doors", options.closed_doors);
  nh.param("door_width", options.render.door_width, options.render.door_width);
  double wall_thickness = 0.0;
  if (nh.getParam("wall_thickness", wall_thickness) && wall_thickness > 0.0) options.render.wall_thickness = wall_thickness;

  simulation::SimulationOptions& simulation = options.simulation;
  nh.param("physics_step", simulation.physics_step, simulation.physics_step);
  int seed = 0;
  nh.param("seed", seed, seed);
  if (seed < 0) throw common::InputError("~seed", "must be zero or positive");
  simulation.seed = static_cast<uint64_t>(seed);
  simulation::RobotOptions& robot = simulation.robot;
  nh.param("footprint_length", robot.length, robot.length);
  nh.param("footprint_width", robot.width, robot.width);
  nh.param("max_linear_velocity", robot.max_linear_velocity, robot.max_linear_velocity);
  nh.param("max_angular_velocity", robot.max_angular_velocity, robot.max_angular_velocity);
  nh.param("linear_acceleration", robot.linear_acceleration, robot.linear_acceleration);
  nh.param("angular_acceleration", robot.angular_acceleration, robot.angular_acceleration);
  nh.param("watchdog_timeout", robot.watchdog_timeout, robot.watchdog_timeout);
  simulation::LaserOptions& laser = simulation.laser;
  nh.param("laser_beams", laser.beams, laser.beams);
  double field_of_view_degrees = laser.field_of_view * 180.0 / kPi;
  nh.param("laser_field_of_view", field_of_view_degrees, field_of_view_degrees);
  laser.field_of_view = field_of_view_degrees * kPi / 180.0;
  nh.param("laser_min_range", laser.min_range, laser.min_range);
  nh.param("laser_max_range", laser.max_range, laser.max_range);
  nh.param("laser_range_noise", laser.range_noise, laser.range_noise);
  nh.param("laser_max_range_probability", laser.max_range_probability, laser.max_range_probability);
  readPose(nh, "laser_pose", &laser.mount);
  std::string caster = toString(laser.caster);
  nh.param("laser_caster", caster, caster);
  laser.caster = simulation::laserCasterFromString(caster);
  nh.param("laser_grid_resolution", laser.grid_resolution, laser.grid_resolution);
  common::Pose2 odom_error{simulation.odometry_noise.x, simulation.odometry_noise.y, simulation.odometry_noise.yaw};
  readPose(nh, "odom_error", &odom_error);
  simulation.odometry_noise = {odom_error.x, odom_error.y, odom_error.yaw};
  common::Pose2 start;
  if (readPose(nh, "start_pose", &start)) simulation.start_pose = start;
  validate(simulation);

  nh.param("realtime_factor", options.realtime_factor, options.realtime_factor);
  nh.param("laser_rate", options.laser_rate, options.laser_rate);
  nh.param("odom_rate", options.odom_rate, options.odom_rate);
  nh.param("clock_rate", options.clock_rate, options.clock_rate);
  nh.param("duration", options.duration, options.duration);
  nh.param("world_frame", options.world_frame, options.world_frame);
  nh.param("odom_frame", options.odom_frame, options.odom_frame);
  nh.param("base_frame", options.base_frame, options.base_frame);
  nh.param("laser_frame", options.laser_frame, options.laser_frame);
  nh.param("publish_world_to_odom", options.publish_world_to_odom, options.publish_world_to_odom);
  if (!std::isfinite(options.realtime_factor) || options.realtime_factor < 0.0)
    throw common::InputError("~realtime_factor", "must be zero (as fast as possible) or positive");
  if (!std::isfinite(options.duration) || options.duration < 0.0)
    throw common::InputError("~duration", "must be zero (no limit) or positive");
  if (!std::isfinite(options.bitmap_resolution) || options.bitmap_resolution <= 0.0)
    throw common::InputError("~bitmap_resolution", "must be positive");
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
  footprint_publisher_ = nh.advertise<geometry_msgs::PolygonStamped>("footprint", 1, true);

  geometry_msgs::PolygonStamped footprint;  // stamp 0: valid at any time (rviz uses the latest transform)
  footprint.header.frame_id = options.base_frame;
  const double half_length = 0.5 * options.simulation.robot.length, half_width = 0.5 * options.simulation.robot.width;
  for (const auto& [x, y] : {std::pair<double, double>{half_length, half_width}, {-half_length, half_width},
                             {-half_length, -half_width}, {half_length, -half_width}}) {
    geometry_msgs::Point32 corner;
    corner.x = static_cast<float>(x);
    corner.y = static_cast<float>(y);
    footprint.polygon.points.push_back(corner);
  }
  footprint_publisher_.publish(footprint);

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
  const ros::WallTime wall_start = ros::WallTime::now();
  const double start = simulation_->time();
  while (ros::ok()) {
    ros::spinOnce();
    step();
    const double elapsed = simulation_->time() - start;
    if (options_.duration > 0.0 && simulation_->time() >= options_.duration - 1e-9) break;
    if (options_.realtime_factor > 0.0) {
      const ros::WallTime due = wall_start + ros::WallDuration(elapsed / options_.realtime_factor);
      const ros::WallTime wall_now = ros::WallTime::now();
      if (due > wall_now) (due - wall_now).sleep();
    }
  }
}

void Simulator::step() {
  simulation_->step();
  const uint64_t steps = simulation_->steps();
  if (steps % clock_period_steps_ == 0) publishClock();
  if (steps % odom_period_steps_ == 0) publishOdometry();
  if (steps % laser_period_steps_ == 0) publishScan();
}

void Simulator::publishClock() {
  rosgraph_msgs::Clock clock;
  clock.clock = now();
  clock_publisher_.publish(clock);
}

void Simulator::publishScan() {
  simulation_->scan(&ranges_);
  scan_publisher_.publish(toRos(ranges_, simulation_->laserGeometry(), options_.simulation.laser.min_range,
                                laser_period_steps_ * options_.simulation.physics_step, options_.laser_frame, now()));
}

void Simulator::publishOdometry() {
  const ros::Time stamp = now();
  const common::Pose2 odometry = simulation_->odometryPose();
  odom_publisher_.publish(toRos(odometry, simulation_->odometryVelocity(), options_.odom_frame, options_.base_frame, stamp));
  ground_truth_publisher_.publish(
      toRos(simulation_->truePose(), simulation_->velocity(), options_.world_frame, options_.base_frame, stamp));
  tf_broadcaster_.sendTransform(toTransform(odometry, options_.odom_frame, options_.base_frame, stamp));
}

void Simulator::onCommand(const geometry_msgs::Twist::ConstPtr& command) {
  try {
    simulation_->setCommand(fromRos(*command));
  } catch (const common::InputError& error) {
    ROS_WARN_THROTTLE(1.0, "simulator: ignoring %s", error.what());
  }
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
