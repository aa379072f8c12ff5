// record_simulation_bag WORLD.xml --out BAG: drives the core simulation (reactive wander) and writes the bag the
// simulator node and launch_files/record.launch would give (base_scan, odom, base_pose_ground_truth, /tf,
// /tf_static), without roscore and as fast as the CPU allows. Deterministic per world, doors and seed.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <boost/make_shared.hpp>
#include <boost/program_options.hpp>
#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/simulation/simulation.h"
#include "hidden_rooms/simulation/wander_driver.h"
#include "hidden_rooms/world/environment.h"

namespace po = boost::program_options;
using hidden_rooms::common::InputError;

namespace {

int run(int argc, char** argv) {
  std::string world_path, bag_path, closed;
  double duration = 120.0;
  int seed = 0;
  po::options_description options("Options");
  options.add_options()
      ("world", po::value(&world_path)->required(), "environment XML")
      ("out", po::value(&bag_path)->required(), "bag to write")
      ("seconds", po::value(&duration)->default_value(120.0), "simulated seconds")
      ("closed-doors", po::value(&closed)->default_value(""), "doors closed: numbers or ids, 'closable' or 'all'")
      ("seed", po::value(&seed)->default_value(0), "simulation seed (laser noise, odometry error)");
  po::positional_options_description positional;
  positional.add("world", 1);
  po::variables_map values;
  if (!hidden_rooms::common::parseCommandLine(
          argc, argv,
          "Usage: record_simulation_bag WORLD.xml --out BAG [--seconds S] [--closed-doors SPEC] [--seed N]\n"
          "Simulates the robot wandering reactively through the world (the simulator node's defaults: 10 Hz\n"
          "scans, 20 Hz odometry) and writes base_scan, odom, base_pose_ground_truth, /tf and /tf_static.",
          options, positional, &values))
    return hidden_rooms::common::kExitOk;
  if (!(duration > 0.0) || !std::isfinite(duration)) throw InputError("--seconds", "must be positive");
  if (seed < 0) throw InputError("--seed", "must be zero or positive");

  const hidden_rooms::world::Environment environment = hidden_rooms::world::loadEnvironment(world_path);
  hidden_rooms::world::printRepairs(environment, world_path, std::cerr);
  hidden_rooms::simulation::SimulationOptions simulation_options;
  simulation_options.seed = static_cast<uint64_t>(seed);
  hidden_rooms::simulation::Simulation simulation(
      hidden_rooms::simulation::worldFromEnvironment(
          environment, hidden_rooms::world::parseDoorSelection(environment, closed, "--closed-doors")),
      simulation_options);

  rosbag::Bag bag;
  try {
    bag.open(bag_path, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& error) {
    throw InputError(bag_path, std::string("cannot write the bag: ") + error.what());
  }
  const double dt = simulation_options.physics_step;
  const int laser_period = static_cast<int>(std::lround(0.1 / dt)), odom_period = static_cast<int>(std::lround(0.05 / dt));
  const int steps = static_cast<int>(std::lround(duration / dt));
  hidden_rooms::simulation::WanderDriver driver;
  std::vector<float> ranges;
  tf2_msgs::TFMessage fixed;
  fixed.transforms.push_back(hidden_rooms::toTransform(simulation_options.laser.mount, "base_link", "base_laser_link",
                                                        ros::Time(dt)));
  // Latched, as tf2's static broadcaster publishes it: rosbag play then latches it too, so that nodes started
  // with the replay (replay.launch) still get the laser mount.
  // (A given connection header replaces rosbag's own, so it carries the message's type fields too.)
  auto latched = boost::make_shared<ros::M_string>();
  (*latched)["topic"] = "/tf_static";
  (*latched)["type"] = ros::message_traits::datatype(fixed);
  (*latched)["md5sum"] = ros::message_traits::md5sum(fixed);
  (*latched)["message_definition"] = ros::message_traits::definition(fixed);
  (*latched)["latching"] = "1";
  (*latched)["callerid"] = "/record_simulation_bag";
  bag.write("/tf_static", ros::Time(dt), fixed, latched);
  for (int k = 1; k <= steps; ++k) {
    simulation.step();
    const ros::Time stamp(simulation.time());
    if (k % odom_period == 0) {
      const hidden_rooms::common::Pose2 odometry = simulation.odometryPose();
      bag.write("odom", stamp, hidden_rooms::toRos(odometry, simulation.odometryVelocity(), "odom", "base_link", stamp));
      bag.write("base_pose_ground_truth", stamp,
                hidden_rooms::toRos(simulation.truePose(), simulation.velocity(), "world", "base_link", stamp));
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(hidden_rooms::toTransform(odometry, "odom", "base_link", stamp));
      bag.write("/tf", stamp, tf);
    }
    if (k % laser_period == 0) {
      simulation.scan(&ranges);
      simulation.setCommand(driver.next(ranges, simulation.laserGeometry()));
      bag.write("base_scan", stamp,
                hidden_rooms::toRos(ranges, simulation.laserGeometry(), simulation_options.laser.min_range,
                                    laser_period * dt, "base_laser_link", stamp));
    }
  }
  bag.close();
  std::printf("bag: %s\nseconds: %.1f\nscans: %d\n", bag_path.c_str(), duration, steps / laser_period);
  return hidden_rooms::common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return hidden_rooms::common::runTool("record_simulation_bag", [&] { return run(argc, argv); });
}
