#pragma once

#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <hidden_rooms/LockstepAck.h>
#include <hidden_rooms/SaveMap.h>
#include <nav_msgs/GetMap.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <ros/spinner.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "hidden_rooms/mapping/rbpf_mapper.h"

namespace hidden_rooms {

// Parameters of the mapper node (all private, ~name; see docs/ros_api.md and config/mapper.yaml).
struct MapperOptions {
  mapping::RbpfMapperOptions rbpf;  // ~config_file (MRPT ini), ~seed
  std::string map_frame = "map";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  double map_update_interval = 2.0;   // seconds of ROS time between map publications (and on the first scan)
  double tf_publish_rate = 20.0;      // Hz (wall-clock timer on ROS time) of map -> odom; 0 = after each scan
  double transform_tolerance = 0.1;   // seconds map -> odom is stamped ahead (as gmapping / amcl do)
  double tf_wait = 0.5;               // seconds a scan may wait for odom -> base_link at its stamp before it is dropped
  // Seconds a scan may be stamped ahead of ROS time; later ones are ignored (one scan from a wrong clock would
  // otherwise make every following scan look out of order). 0 = no check.
  double future_stamp_tolerance = 1.0;
  bool publish_particles = true;      // publish `particles` (geometry_msgs/PoseArray)
  // Lockstep with the simulator (its ~lockstep_nodes): report each scan on `lockstep` once handled, wait for its
  // odometry as long as it takes (wall clock, up to ~tf_wait_wall) and publish map -> odom after each scan only.
  bool lockstep = false;
  double tf_wait_wall = 5.0;          // wall seconds a scan waits for its odometry in lockstep
};

// The node's own parameters (topic, frames, rates, waits, particles); the ini's are in the core's table.
const common::OptionTable<MapperOptions>& mapperNodeOptionTable();
// Every parameter of the node, as docs/ros_api.md lists them (~seed, read apart, listed by hand).
std::vector<common::OptionDescription> mapperParameters();
// Reads the options from the private node handle. Throws InputError naming the first bad parameter or a missing
// ~config_file.
MapperOptions readMapperOptions(const ros::NodeHandle& private_nh);

// SLAM node over the core's RbpfMapper: each scan on `scan` with the odometry (tf odom -> base_link at the
// scan's stamp) goes to MRPT's RBPF; publishes the map (latched), map_metadata, the particles and tf
// map -> odom, and serves save_map. With a tf rate, map -> odom is republished from its own thread, so a long
// filter update or map rendering (large maps) does not leave the tree without a recent map -> odom.
class Mapper {
 public:
  // Loads the MRPT options (throws InputError when it cannot); does not wait for anything.
  Mapper(ros::NodeHandle nh, const MapperOptions& options);

  const mapping::RbpfMapper& mapper() const { return *mapper_; }
  // Scans given to the filter / dropped because their odometry never arrived / ignored on arrival (stamped
  // before the last one or too far ahead, no valid range).
  int scansProcessed() const { return processed_; }
  int scansDropped() const { return dropped_; }
  int scansIgnored() const { return ignored_; }

 private:
  void onScan(const sensor_msgs::LaserScan::ConstPtr& scan);
  // Handles the scan (processes, drops or ignores it), then reports it in lockstep.
  void handleScan(const sensor_msgs::LaserScan::ConstPtr& scan);
  void processPending();
  // Whether odom -> base_frame at `stamp` is in the tf buffer; in lockstep, waits for it up to ~tf_wait_wall.
  bool odometryArrived(const ros::Time& stamp);
  void reportLockstep(const ros::Time& stamp);
  bool process(const sensor_msgs::LaserScan& scan);
  void publishMap(const ros::Time& stamp);
  // Publishes the last map -> odom (if any) at `stamp` + transform_tolerance, once per stamp.
  void publishTransform(const ros::Time& stamp);
  void onTimer(const ros::TimerEvent& event);
  bool onSaveMap(hidden_rooms::SaveMap::Request& request, hidden_rooms::SaveMap::Response& response);
  // dynamic_map (gmapping's convention): the map as it is now; false (a failed call) before the first scan.
  bool onDynamicMap(nav_msgs::GetMap::Request& request, nav_msgs::GetMap::Response& response);

  MapperOptions options_;
  std::unique_ptr<mapping::RbpfMapper> mapper_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  std::deque<sensor_msgs::LaserScan::ConstPtr> pending_;
  ros::Time last_map_stamp_;
  ros::Time last_scan_stamp_;
  bool map_published_ = false;
  int processed_ = 0;
  int dropped_ = 0;
  int ignored_ = 0;
  ros::Subscriber scan_subscriber_;
  ros::Publisher map_publisher_;
  ros::Publisher metadata_publisher_;
  ros::Publisher particles_publisher_;
  ros::ServiceServer save_service_;
  ros::ServiceServer dynamic_map_service_;
  // map -> odom after the last processed scan and the stamp it was last sent with: written by the scan callback,
  // read by the tf timer's thread.
  std::mutex transform_mutex_;
  std::optional<common::Pose2> map_to_odom_;
  ros::Time last_tf_stamp_;
  ros::Publisher lockstep_publisher_;
  // The tf timer's own queue and thread (declared last: the thread stops before the timer and queue go).
  ros::CallbackQueue tf_queue_;
  ros::Timer tf_timer_;
  std::unique_ptr<ros::AsyncSpinner> tf_spinner_;
};

}  // namespace hidden_rooms
