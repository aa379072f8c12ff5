#include "hidden_rooms/ros/mapper.h"

#include <geometry_msgs/PoseArray.h>
#include <nav_msgs/MapMetaData.h>
#include <nav_msgs/OccupancyGrid.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/ros/lockstep.h"
#include "ros/mrpt_scan.h"
#include "hidden_rooms/ros/parameters.h"

namespace hidden_rooms {

const common::OptionTable<MapperOptions>& mapperNodeOptionTable() {
  using O = MapperOptions;
  static const common::OptionTable<O> table{
      {"map_frame", &O::map_frame, "frame of the map", common::anyFinite(), true},
      {"odom_frame", &O::odom_frame, "frame of the odometry", common::anyFinite(), true},
      {"base_frame", &O::base_frame, "frame of the robot", common::anyFinite(), true},
      {"map_update_interval", &O::map_update_interval, "seconds (ROS time) between map publications",
       common::atLeast(0)},
      {"tf_publish_rate", &O::tf_publish_rate, "Hz of map -> odom; 0 = after each scan", common::atLeast(0)},
      {"transform_tolerance", &O::transform_tolerance, "seconds map -> odom is stamped ahead", common::atLeast(0)},
      {"tf_wait", &O::tf_wait, "seconds (scan time) a scan waits for its odometry before it is dropped",
       common::atLeast(0)},
      {"future_stamp_tolerance", &O::future_stamp_tolerance,
       "seconds a scan may be stamped ahead of ROS time; 0 = no check", common::atLeast(0)},
      {"publish_particles", &O::publish_particles, "publish particles"},
      {"lockstep", &O::lockstep, "report each scan on `lockstep` (the simulator's ~lockstep_nodes)"},
      {"tf_wait_wall", &O::tf_wait_wall, "wall seconds a scan waits for its odometry in lockstep", common::above(0)},
  };
  return table;
}

std::vector<common::OptionDescription> mapperParameters() {
  std::vector<common::OptionDescription> rows = common::describeOptions(mapping::rbpfMapperOptionTable());
  const std::vector<common::OptionDescription> node = common::describeOptions(mapperNodeOptionTable());
  rows.insert(rows.end(), node.begin(), node.end());
  rows.push_back({"seed", "int", "0", "seed of MRPT's random generator"});  // read apart: an unsigned seed
  return rows;
}

MapperOptions readMapperOptions(const ros::NodeHandle& nh) {
  MapperOptions options;
  readParameters(nh, mapping::rbpfMapperOptionTable(), &options.rbpf);
  // The seed is unsigned: read as an int (all XML-RPC has), then checked.
  int seed = 0;
  readParameter(nh, "seed", &seed);
  if (seed < 0) throw common::InputError("~seed", "must be zero or positive");
  options.rbpf.seed = static_cast<uint32_t>(seed);
  if (options.rbpf.config_file.empty())
    throw common::InputError("~config_file", "must name the MRPT ini (config/rbpf.ini)");
  readParameters(nh, mapperNodeOptionTable(), &options);
  if (options.lockstep) {
    options.tf_publish_rate = 0.0;  // a timer's stamps would depend on the machine's speed
    // The scans' stamps are the clock: /clock comes on a connection of its own and may lag them.
    options.future_stamp_tolerance = 0.0;
  }
  return options;
}

Mapper::Mapper(ros::NodeHandle nh, const MapperOptions& options)
    : options_(options),
      mapper_(std::make_unique<mapping::RbpfMapper>(options.rbpf)),
      tf_buffer_(ros::Duration(30.0)),
      tf_listener_(tf_buffer_) {
  scan_subscriber_ = nh.subscribe("scan", 50, &Mapper::onScan, this);
  map_publisher_ = nh.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
  metadata_publisher_ = nh.advertise<nav_msgs::MapMetaData>("map_metadata", 1, true);
  if (options.publish_particles) particles_publisher_ = nh.advertise<geometry_msgs::PoseArray>("particles", 1);
  save_service_ = nh.advertiseService("save_map", &Mapper::onSaveMap, this);
  dynamic_map_service_ = nh.advertiseService("dynamic_map", &Mapper::onDynamicMap, this);
  if (options.lockstep) {
    lockstep_publisher_ = nh.advertise<hidden_rooms::LockstepAck>("lockstep", 10, true);
    reportLockstep(ros::Time());  // ready
  }
  if (options.tf_publish_rate > 0.0) {
    ros::NodeHandle tf_nh(nh);
    tf_nh.setCallbackQueue(&tf_queue_);
    tf_timer_ = tf_nh.createTimer(ros::Duration(1.0 / options.tf_publish_rate), &Mapper::onTimer, this);
    tf_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &tf_queue_);
    tf_spinner_->start();
  }
}

// Scans that would harm the filter are ignored on arrival, each kind with its own throttled warning: stamps
// before the last scan's (the filter cannot go back), stamps too far ahead of ROS time (they would make every
// later scan look old), and scans without a valid range (NaN, infinite, out of range: nothing to match or insert,
// and the filter would spend an update and an insertion on them).
void Mapper::onScan(const sensor_msgs::LaserScan::ConstPtr& scan) {
  if (options_.lockstep && !last_scan_stamp_.isZero() && scan->header.stamp == last_scan_stamp_) {
    reportLockstep(last_scan_stamp_);  // the simulator re-sent a scan: handled already
    return;
  }
  handleScan(scan);
  if (options_.lockstep) reportLockstep(scan->header.stamp);
}

void Mapper::handleScan(const sensor_msgs::LaserScan::ConstPtr& scan) {
  const ros::Time stamp = scan->header.stamp;
  if (!last_scan_stamp_.isZero() && stamp < last_scan_stamp_) {
    // Time went back (a bag restarted, the simulator was reset with a new clock, a stale message).
    ++ignored_;
    ROS_WARN_THROTTLE(5.0, "mapper: scan stamped %.3f before the last one (%.3f); ignored (%d scans ignored so far)",
                      stamp.toSec(), last_scan_stamp_.toSec(), ignored_);
    return;
  }
  const ros::Time now = ros::Time::now();
  if (options_.future_stamp_tolerance > 0.0 && !now.isZero() &&
      (stamp - now).toSec() > options_.future_stamp_tolerance) {
    ++ignored_;
    ROS_WARN_THROTTLE(5.0, "mapper: scan stamped %.3f, %.1f s ahead of ROS time %.3f; ignored (%d scans ignored so far)",
                      stamp.toSec(), (stamp - now).toSec(), now.toSec(), ignored_);
    return;
  }
  if (countValidRanges(*scan) == 0) {
    ++ignored_;
    ROS_WARN_THROTTLE(5.0, "mapper: scan stamped %.3f has no valid range (all NaN, infinite or outside (range_min, "
                      "range_max)); ignored (%d scans ignored so far)", stamp.toSec(), ignored_);
    return;
  }
  last_scan_stamp_ = stamp;
  pending_.push_back(scan);
  processPending();
}

// Scans wait (in order) until the odometry at their stamp is in the tf buffer; those that waited longer than
// ~tf_wait (in scan time) are dropped.
void Mapper::processPending() {
  while (!pending_.empty()) {
    const sensor_msgs::LaserScan& scan = *pending_.front();
    if (odometryArrived(scan.header.stamp)) {
      if (process(scan)) ++processed_;
      pending_.pop_front();
    } else if (options_.lockstep || (last_scan_stamp_ - scan.header.stamp).toSec() > options_.tf_wait) {
      ++dropped_;
      ROS_WARN_THROTTLE(5.0, "mapper: no %s -> %s at scan stamp %.3f; scan dropped (%d so far)",
                        options_.odom_frame.c_str(), options_.base_frame.c_str(), scan.header.stamp.toSec(), dropped_);
      pending_.pop_front();
    } else {
      break;
    }
  }
}

bool Mapper::odometryArrived(const ros::Time& stamp) {
  return waitOnWallClock([&] { return tf_buffer_.canTransform(options_.odom_frame, options_.base_frame, stamp); },
                         options_.lockstep ? options_.tf_wait_wall : 0.0);
}

void Mapper::reportLockstep(const ros::Time& stamp) {
  hidden_rooms::LockstepAck ack = lockstepReport(stamp);
  ack.map_stamp = last_map_stamp_;
  {
    std::lock_guard<std::mutex> lock(transform_mutex_);
    if (map_to_odom_ && !last_tf_stamp_.isZero())
      ack.map_to_odom = toTransform(*map_to_odom_, options_.map_frame, options_.odom_frame,
                                    last_tf_stamp_ + ros::Duration(options_.transform_tolerance));
  }
  lockstep_publisher_.publish(ack);
}

bool Mapper::process(const sensor_msgs::LaserScan& scan) {
  common::Pose2 odometry;
  LaserMount mount;
  try {
    odometry = fromRos(tf_buffer_.lookupTransform(options_.odom_frame, options_.base_frame, scan.header.stamp).transform);
    mount = laserMountFromRos(tf_buffer_.lookupTransform(options_.base_frame, scan.header.frame_id, ros::Time(0)).transform);
  } catch (const tf2::TransformException& error) {
    ROS_WARN_THROTTLE(5.0, "mapper: %s; scan dropped", error.what());
    ++dropped_;
    return false;
  }
  try {
    mapper_->addScan(odometry, toMrptScan(uprightScan(scan, mount), mount.pose));
  } catch (const common::InputError& error) {
    ROS_WARN_THROTTLE(5.0, "mapper: bad scan: %s", error.what());
    ++dropped_;
    return false;
  }
  {
    std::lock_guard<std::mutex> lock(transform_mutex_);
    map_to_odom_ = mapper_->mapToOdom();
  }
  // With a tf rate the timer publishes map -> odom (one stamp per ROS time, no repeated data), else each scan.
  if (options_.tf_publish_rate <= 0.0) publishTransform(scan.header.stamp);
  if (options_.publish_particles)
    particles_publisher_.publish(toRos(mapper_->particles(), options_.map_frame, scan.header.stamp));
  if (!map_published_ || (scan.header.stamp - last_map_stamp_).toSec() >= options_.map_update_interval)
    publishMap(scan.header.stamp);
  return true;
}

void Mapper::publishMap(const ros::Time& stamp) {
  const common::OccupancyGrid grid = mapper_->map();
  if (grid.empty()) return;
  const nav_msgs::OccupancyGrid message = toRos(grid, options_.map_frame, stamp);
  map_publisher_.publish(message);
  metadata_publisher_.publish(message.info);
  last_map_stamp_ = stamp;
  map_published_ = true;
}

void Mapper::publishTransform(const ros::Time& stamp) {
  std::lock_guard<std::mutex> lock(transform_mutex_);
  if (!map_to_odom_) return;             // no scan processed yet
  if (stamp <= last_tf_stamp_) return;  // time has not moved (simulated clock slower than the timer)
  last_tf_stamp_ = stamp;
  tf_broadcaster_.sendTransform(toTransform(*map_to_odom_, options_.map_frame, options_.odom_frame,
                                            stamp + ros::Duration(options_.transform_tolerance)));
}

void Mapper::onTimer(const ros::TimerEvent&) { publishTransform(ros::Time::now()); }

bool Mapper::onDynamicMap(nav_msgs::GetMap::Request&, nav_msgs::GetMap::Response& response) {
  const common::OccupancyGrid grid = mapper_->map();
  if (grid.empty()) return false;
  response.map = toRos(grid, options_.map_frame, last_scan_stamp_);
  return true;
}

bool Mapper::onSaveMap(hidden_rooms::SaveMap::Request& request, hidden_rooms::SaveMap::Response& response) {
  const common::OccupancyGrid grid = mapper_->map();
  if (grid.empty()) {
    response.success = false;
    response.message = "no map yet: no scan has been processed";
    return true;
  }
  if (request.prefix.empty()) {
    response.success = false;
    response.message = "empty prefix";
    return true;
  }
  try {
    response.message = common::saveMap(grid, request.prefix);
    response.success = true;
  } catch (const common::InputError& error) {
    response.success = false;
    response.message = error.what();
  }
  return true;
}

}  // namespace hidden_rooms
