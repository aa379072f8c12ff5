// map_from_bag BAG --out PREFIX: the mapper's SLAM straight from a bag's scans and tf, as fast as the CPU allows
// (rosbag C++ API, no roscore). Optionally scores the map against an environment's rendered ground truth or a
// reference map.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>
#include <nav_msgs/Odometry.h>
#include <ros/package.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/pose_log.h"
#include "hidden_rooms/evaluation/door_translation.h"
#include "hidden_rooms/evaluation/map_quality.h"
#include "hidden_rooms/mapping/rbpf_mapper.h"
#include "hidden_rooms/ros/conversions.h"
#include "ros/mrpt_scan.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

namespace po = boost::program_options;
using hidden_rooms::common::InputError;
using hidden_rooms::common::Pose2;
using hidden_rooms::common::TimedPose;
using hidden_rooms::common::poseAt;

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kMountWait = 1.0;  // seconds of bag time a scan waits for its laser mount
double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// A topic or frame name without its leading slashes: older bags and drivers write "/base_scan" and "/base_link"
// where newer ones write "base_scan" and "base_link"; tf2 takes frame ids without one.
std::string withoutLeadingSlash(const std::string& name) {
  const size_t first = name.find_first_not_of('/');
  return first == std::string::npos ? std::string() : name.substr(first);
}

// The bag's topics of `datatype`, comma-separated ("none" when there are none).
std::string topicsOfType(rosbag::Bag& bag, const std::string& datatype) {
  std::string listed;
  for (const rosbag::ConnectionInfo* connection : rosbag::View(bag).getConnections())
    if (connection->datatype == datatype && listed.find(connection->topic) == std::string::npos)
      listed += (listed.empty() ? "" : ", ") + connection->topic;
  return listed.empty() ? "none" : listed;
}

std::string defaultConfig() {
  const std::string package = ros::package::getPath("hidden_rooms");
  return package.empty() ? std::string() : package + "/config/rbpf.ini";
}

int run(int argc, char** argv) {
  std::string bag_path, prefix, config, scan_topic, odom_frame, base_frame, environment_path, reference_path, closed,
      metrics_path, truth_topic, comparison_path, odom_topic, trajectory_path;
  int seed = 0;
  bool quiet = false;
  po::options_description options("Options");
  options.add_options()
      ("bag", po::value(&bag_path)->required(), "input bag")
      ("out", po::value(&prefix)->required(), "output prefix: writes PREFIX.yaml and PREFIX.pgm")
      ("config", po::value(&config), "MRPT ini (default: the package's config/rbpf.ini)")
      ("seed", po::value(&seed)->default_value(0), "random seed of the filter")
      ("scan-topic", po::value(&scan_topic)->default_value("base_scan"), "sensor_msgs/LaserScan topic")
      ("odom-frame", po::value(&odom_frame)->default_value("odom"), "odometry frame in /tf")
      ("base-frame", po::value(&base_frame)->default_value("base_link"), "robot frame in /tf")
      ("odom-topic", po::value(&odom_topic),
       "nav_msgs/Odometry topic to take the odometry from, for bags without odom -> base_link in /tf")
      ("environment", po::value(&environment_path), "score the map against this environment XML's rendering")
      ("reference-map", po::value(&reference_path),
       "score the map against this map, in the frame of the true poses (carmen_to_bag --reference-map)")
      ("closed-doors", po::value(&closed)->default_value(""), "with --environment: doors closed in the run")
      ("truth-topic", po::value(&truth_topic)->default_value("base_pose_ground_truth"),
       "when scoring: nav_msgs/Odometry of the true pose in the world frame")
      ("metrics", po::value(&metrics_path), "when scoring: also write the figures to this YAML file")
      ("comparison", po::value(&comparison_path),
       "when scoring: PNG of the map on the truth (white: both free; orange / red / magenta: observed free the "
       "map has unknown / uncertain / occupied; blue: map free where the truth is not observed free)")
      ("trajectory", po::value(&trajectory_path),
       "also write the SLAM pose at every scan as a pose log (map frame), as estimated at the end (loop closures "
       "move earlier poses)")
      ("quiet", po::bool_switch(&quiet), "no progress line");
  po::positional_options_description positional;
  positional.add("bag", 1);
  po::variables_map values;
  if (!hidden_rooms::common::parseCommandLine(
          argc, argv,
          "Usage: map_from_bag BAG --out PREFIX [--config rbpf.ini] [--seed N]\n"
          "                    [--environment ENV.xml | --reference-map MAP.yaml] [--metrics F.yaml]\n"
          "Builds the mapper's map (MRPT RBPF) from the bag's scans and tf odom -> base_link (or --odom-topic), as\n"
          "fast as the CPU allows, and writes it as map_server files. With --environment or --reference-map also\n"
          "prints map quality and trajectory errors (absolute after a rigid fit, and relative between consecutive\n"
          "scans) against the rendered ground truth or the reference map (true poses from --truth-topic).",
          options, positional, &values))
    return hidden_rooms::common::kExitOk;
  if (seed < 0) throw InputError("--seed", "must be zero or positive");
  if (config.empty()) config = defaultConfig();
  if (config.empty()) throw InputError("--config", "not given and the package's config/rbpf.ini was not found");
  if (!environment_path.empty() && !reference_path.empty())
    throw InputError("--reference-map", "give --environment or --reference-map, not both");
  const bool scoring = !environment_path.empty() || !reference_path.empty();
  if (!metrics_path.empty() && !scoring) throw InputError("--metrics", "needs --environment or --reference-map");
  if (!comparison_path.empty() && !scoring) throw InputError("--comparison", "needs --environment or --reference-map");

  // Inputs first: nothing is written on bad input.
  hidden_rooms::common::OccupancyGrid truth_map;  // in the frame of the true poses
  if (!environment_path.empty()) {
    const hidden_rooms::world::Environment environment = hidden_rooms::world::loadEnvironment(environment_path);
    hidden_rooms::world::printRepairs(environment, environment_path, std::cerr);
    truth_map = hidden_rooms::world::renderEnvironment(
                    environment, hidden_rooms::world::parseDoorSelection(environment, closed, "--closed-doors"))
                    .map;
  } else if (!reference_path.empty()) {
    truth_map = hidden_rooms::common::loadMap(reference_path);
  }
  hidden_rooms::mapping::RbpfMapperOptions mapper_options;
  mapper_options.config_file = config;
  mapper_options.seed = static_cast<uint32_t>(seed);
  hidden_rooms::mapping::RbpfMapper mapper(mapper_options);

  rosbag::Bag bag;
  try {
    bag.open(bag_path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& error) {
    throw InputError(bag_path, std::string("cannot open the bag: ") + error.what());
  }
  // Topics and frames match with or without a leading slash.
  scan_topic = withoutLeadingSlash(scan_topic);
  truth_topic = withoutLeadingSlash(truth_topic);
  odom_topic = withoutLeadingSlash(odom_topic);
  odom_frame = withoutLeadingSlash(odom_frame);
  base_frame = withoutLeadingSlash(base_frame);
  std::vector<std::string> topics;
  for (const std::string& topic : {scan_topic, std::string("tf"), std::string("tf_static"), truth_topic, odom_topic})
    if (!topic.empty()) topics.insert(topics.end(), {topic, "/" + topic});
  rosbag::View view(bag, rosbag::TopicQuery(topics));
  bool scans_in_bag = false, odometry_in_bag = odom_topic.empty();
  for (const rosbag::ConnectionInfo* connection : view.getConnections()) {
    const std::string topic = withoutLeadingSlash(connection->topic);
    scans_in_bag |= connection->datatype == "sensor_msgs/LaserScan" && topic == scan_topic;
    odometry_in_bag |= connection->datatype == "nav_msgs/Odometry" && topic == odom_topic;
  }
  if (!scans_in_bag)
    throw InputError(bag_path, "no sensor_msgs/LaserScan on topic " + scan_topic + " (the bag's LaserScan topics: " +
                                   topicsOfType(bag, "sensor_msgs/LaserScan") + "; choose one with --scan-topic)");
  if (!odometry_in_bag)
    throw InputError(bag_path, "no nav_msgs/Odometry on topic " + odom_topic + " (the bag's Odometry topics: " +
                                   topicsOfType(bag, "nav_msgs/Odometry") + ")");
  const double bag_start = view.getBeginTime().toSec(), bag_end = view.getEndTime().toSec();
  const double bag_seconds = std::max(bag_end - bag_start, 1e-9);
  if (!(bag_seconds < 1e9))  // ros::Duration's range is 2^31 s
    throw InputError(bag_path, "its messages span " + hidden_rooms::common::formatNumber(bag_seconds) +
                                   " s: the bag's index is damaged");

  tf2::BufferCore tf_buffer(ros::Duration(std::max(60.0, bag_seconds + 10.0)));
  std::deque<sensor_msgs::LaserScan::ConstPtr> pending;
  std::vector<TimedPose> true_poses;
  std::vector<double> scan_stamps;  // of the scans the mapper took, in order (the poses: mapper.trajectory())
  std::vector<std::pair<double, hidden_rooms::common::RangeScan>> inserted_scans;  // for the observed cells
  int processed = 0, dropped = 0, received = 0, without_returns = 0, without_mount = 0;
  std::string last_tf_error, last_mount_error;
  const Clock::time_point start = Clock::now();
  Clock::time_point last_progress = start;

  auto process = [&](const sensor_msgs::LaserScan& scan) {
    if (hidden_rooms::countValidRanges(scan) == 0) {  // as the mapper node: nothing to match or insert
      ++dropped;
      ++without_returns;
      return;
    }
    const std::string laser_frame = withoutLeadingSlash(scan.header.frame_id);
    hidden_rooms::LaserMount mount;
    try {
      mount = hidden_rooms::laserMountFromRos(tf_buffer.lookupTransform(base_frame, laser_frame, ros::Time(0)).transform);
    } catch (const tf2::TransformException& error) {
      ++dropped;
      ++without_mount;
      last_mount_error = error.what();
      return;
    }
    Pose2 odometry;
    sensor_msgs::LaserScan upright;
    mrpt::obs::CObservation2DRangeScan observation;
    try {  // a scan without odometry at its stamp, or with bad geometry, is dropped; the mapper's errors are not
      odometry = hidden_rooms::fromRos(tf_buffer.lookupTransform(odom_frame, base_frame, scan.header.stamp).transform);
      upright = hidden_rooms::uprightScan(scan, mount);
      observation = hidden_rooms::toMrptScan(upright, mount.pose);
    } catch (const tf2::TransformException& error) {
      ++dropped;
      last_tf_error = error.what();
      return;
    } catch (const InputError& error) {
      ++dropped;
      last_tf_error = error.what();
      return;
    }
    const bool inserted = mapper.addScan(odometry, observation);
    ++processed;
    if (scoring || !trajectory_path.empty()) {
      scan_stamps.push_back(scan.header.stamp.toSec());
      if (inserted) inserted_scans.emplace_back(scan.header.stamp.toSec(), hidden_rooms::fromRos(upright, mount.pose));
    }
  };

  for (const rosbag::MessageInstance& message : view) {
    const std::string topic = withoutLeadingSlash(message.getTopic());
    if (const auto tf = message.instantiate<tf2_msgs::TFMessage>()) {
      for (geometry_msgs::TransformStamped transform : tf->transforms) {
        transform.header.frame_id = withoutLeadingSlash(transform.header.frame_id);
        transform.child_frame_id = withoutLeadingSlash(transform.child_frame_id);
        tf_buffer.setTransform(transform, "bag", topic == "tf_static");
      }
    } else if (const auto scan = message.instantiate<sensor_msgs::LaserScan>()) {
      if (topic != scan_topic) continue;
      pending.push_back(scan);
      ++received;
    } else if (const auto odometry = message.instantiate<nav_msgs::Odometry>()) {
      if (topic == odom_topic) {  // the odometry as the transform odom_frame -> base_frame at its stamp
        geometry_msgs::TransformStamped transform;
        transform.header.stamp = odometry->header.stamp;
        transform.header.frame_id = odom_frame;
        transform.child_frame_id = base_frame;
        transform.transform.translation.x = odometry->pose.pose.position.x;
        transform.transform.translation.y = odometry->pose.pose.position.y;
        transform.transform.translation.z = odometry->pose.pose.position.z;
        transform.transform.rotation = odometry->pose.pose.orientation;
        tf_buffer.setTransform(transform, "bag", false);
      }
      if (topic == truth_topic)
        true_poses.push_back({odometry->header.stamp.toSec(), hidden_rooms::fromRos(odometry->pose.pose)});
    }
    // A scan is processed once the odometry after its stamp is in the buffer (tf at the scan's time) and the laser
    // mount is known; the mount (/tf_static, often stamped like the first scan) is awaited up to kMountWait seconds.
    const auto ready = [&](const sensor_msgs::LaserScan& scan) {
      if (!tf_buffer.canTransform(odom_frame, base_frame, scan.header.stamp)) return false;
      return tf_buffer.canTransform(base_frame, withoutLeadingSlash(scan.header.frame_id), ros::Time(0)) ||
             message.getTime().toSec() - scan.header.stamp.toSec() > kMountWait;
    };
    while (!pending.empty() && ready(*pending.front())) {
      process(*pending.front());
      pending.pop_front();
    }
    if (!quiet && seconds(Clock::now() - last_progress) > 0.5) {
      last_progress = Clock::now();
      const double done = message.getTime().toSec() - bag_start;
      std::fprintf(stderr, "\rmap_from_bag: %5.1f%%  %.1f / %.1f s of bag, %d scans, %.1fx real time   ",
                   100.0 * done / bag_seconds, done, bag_seconds, processed,
                   done / std::max(seconds(last_progress - start), 1e-9));
    }
  }
  for (; !pending.empty(); pending.pop_front()) process(*pending.front());  // the last ones, if tf allows
  bag.close();
  const double wall_seconds = seconds(Clock::now() - start);
  if (!quiet) std::fprintf(stderr, "\n");
  if (processed == 0) {
    const std::string odometry_source = odom_topic.empty() ? "in /tf; a bag with odometry only as nav_msgs/Odometry "
                                                             "needs --odom-topic"
                                                           : "from " + odom_topic;
    throw InputError(bag_path,
                     received == 0                    ? "no scans on topic " + scan_topic
                     : without_returns == received    ? "no scan has a valid range"
                     : without_mount + without_returns == received
                         ? "no laser mount: no transform from " + base_frame + " to the scans' frame (usually on " +
                               "/tf_static): " + last_mount_error
                         : "no scan has odometry (" + odom_frame + " -> " + base_frame + " " + odometry_source +
                               ") at its stamp: " + last_tf_error);
  }

  const hidden_rooms::common::OccupancyGrid map = mapper.map();
  // The SLAM pose at every scan's stamp, as the mapper estimates it at the end (a loop closure moves the poses
  // before it).
  std::vector<TimedPose> estimated;
  const std::vector<Pose2> final_poses = mapper.trajectory();
  for (size_t i = 0; i < scan_stamps.size() && i < final_poses.size(); ++i)
    estimated.push_back({scan_stamps[i], final_poses[i]});
  const std::string yaml = hidden_rooms::common::saveMap(map, prefix);
  std::printf("bag: %s\nmap: %s\nscans: %d\nscans_inserted: %d\nscans_dropped: %d\nbag_seconds: %.2f\n"
              "wall_seconds: %.2f\nspeed_factor: %.1f\n",
              bag_path.c_str(), yaml.c_str(), processed, mapper.scansInserted(), dropped, bag_seconds, wall_seconds,
              bag_seconds / std::max(wall_seconds, 1e-9));
  if (!trajectory_path.empty()) {
    std::string log = hidden_rooms::common::poseLogHeader("map", base_frame);
    for (const TimedPose& pose : estimated) log += hidden_rooms::common::poseLogLine(pose);
    hidden_rooms::common::writeTextAtomically(trajectory_path, log, "trajectory");
  }
  if (!scoring) return hidden_rooms::common::kExitOk;

  if (true_poses.empty()) throw InputError(bag_path, "no nav_msgs/Odometry on " + truth_topic + " to score against");
  std::sort(true_poses.begin(), true_poses.end(),
            [](const TimedPose& a, const TimedPose& b) { return a.time < b.time; });
  std::vector<Pose2> estimate, truth_at_scans;
  for (const TimedPose& pose : estimated) {
    estimate.push_back(pose.pose);
    truth_at_scans.push_back(poseAt(true_poses, pose.time));
  }
  // The map placed in the truth's frame by the least-squares rigid fit of the whole trajectory.
  const Pose2 world_from_map = hidden_rooms::evaluation::fitWorldFromMap(true_poses, estimated);
  cv::Mat1b observed;
  for (const auto& [time, scan] : inserted_scans)
    hidden_rooms::evaluation::markObservedCells(
        truth_map, hidden_rooms::common::composePoses(poseAt(true_poses, time), scan.sensor_pose), scan, &observed);
  const hidden_rooms::evaluation::MapQuality quality =
      hidden_rooms::evaluation::evaluateMap(map, world_from_map, truth_map, observed);
  if (!comparison_path.empty())
    hidden_rooms::common::writeImage(
        comparison_path, hidden_rooms::evaluation::drawMapComparison(map, world_from_map, truth_map, observed));
  const hidden_rooms::evaluation::TrajectoryError trajectory =
      hidden_rooms::evaluation::trajectoryError(estimate, truth_at_scans, world_from_map);
  char text[1024];
  std::snprintf(text, sizeof(text),
                "free_iou: %.4f\ntrue_free_cells: %lld\nmap_free_cells: %lld\nwalls_within_2_cells: %.4f\n"
                "wall_distance_mean_cells: %.3f\nwall_distance_p95_cells: %.3f\ntrajectory_poses: %d\n"
                "trajectory_rmse_m: %.4f\ntrajectory_max_m: %.4f\nyaw_rmse_rad: %.4f\nrelations: %d\n"
                "relative_translation_mean_m: %.4f\nrelative_rotation_mean_rad: %.4f\n"
                "relative_translation_per_metre: %.4f\n",
                quality.free_iou, quality.true_free_cells, quality.map_free_cells, quality.walls_within_2_cells,
                quality.wall_distance_mean, quality.wall_distance_p95, trajectory.poses, trajectory.position_rmse,
                trajectory.position_max, trajectory.yaw_rmse, trajectory.relations,
                trajectory.relative_translation_mean, trajectory.relative_rotation_mean,
                trajectory.relative_translation_per_metre);
  std::printf("%s", text);
  if (!metrics_path.empty()) {
    std::ostringstream out;
    out << "bag: " << bag_path << "\nbag_seconds: " << bag_seconds << "\nwall_seconds: " << wall_seconds
        << "\nspeed_factor: " << bag_seconds / std::max(wall_seconds, 1e-9) << "\nscans: " << processed
        << "\nscans_inserted: " << mapper.scansInserted() << "\n" << text;
    hidden_rooms::common::writeTextAtomically(metrics_path, out.str(), "metrics file");
  }
  return hidden_rooms::common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return hidden_rooms::common::runTool("map_from_bag", [&] {
    try {
      return run(argc, argv);
    } catch (const ros::Exception& error) {  // rosbag's and the message deserializers' errors: a damaged bag
      throw InputError("bag", std::string("cannot be read, it is damaged: ") + error.what());
    }
  });
}
