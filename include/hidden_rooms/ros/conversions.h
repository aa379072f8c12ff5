#pragma once

// The one place where core types and ROS messages meet.

#include <map>
#include <string>
#include <vector>

#include <hidden_rooms/ClosedDoor.h>
#include <hidden_rooms/PredictedRoom.h>
#include <hidden_rooms/PredictionParameter.h>
#include <hidden_rooms/RoomPassage.h>
#include <hidden_rooms/SegmentedRoom.h>
#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/time.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/range_scan.h"
#include "hidden_rooms/mapping/rbpf_mapper.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "hidden_rooms/segmentation/floor.h"
#include "hidden_rooms/simulation/simulation.h"

namespace hidden_rooms {

// A map-frame point at height `z`.
geometry_msgs::Point toRos(const common::Point2& point, double z);

// Core grids keep row 0 at the top (image order); nav_msgs keeps row 0 at the origin (bottom).
nav_msgs::OccupancyGrid toRos(const common::OccupancyGrid& grid, const std::string& frame_id, const ros::Time& stamp);
// Throws InputError for a message whose data size does not match width x height, a non-positive resolution
// or a rotated origin.
common::OccupancyGrid fromRos(const nav_msgs::OccupancyGrid& message);

hidden_rooms::ClosedDoor toRos(const common::MapDoor& door);
common::MapDoor fromRos(const hidden_rooms::ClosedDoor& message);

// Doors of a request, in `frame`. Throws InputError naming a bad door (non-finite, bad width or orientation).
common::DoorsFile fromRos(const std::vector<hidden_rooms::ClosedDoor>& messages, const std::string& frame);
std::vector<hidden_rooms::ClosedDoor> toRos(const common::DoorsFile& doors);

// Parameter overrides. Throws InputError("parameters", ...) for an empty or repeated name or a non-finite value.
std::map<std::string, double> fromRos(const std::vector<hidden_rooms::PredictionParameter>& messages);
std::vector<hidden_rooms::PredictionParameter> toRos(const std::map<std::string, double>& parameters);

// The message of the room predicted for the door with 1-based position `label` in the request: status, polygon,
// area, score ("score" term, NaN without one), terms, and the mask cropped to the room's bounding box (0 on its
// cells, -1 elsewhere) in `map`'s cell grid.
hidden_rooms::PredictedRoom toRos(const prediction::RoomPrediction& room, int label, const common::OccupancyGrid& map,
                                  const std::string& frame_id, const ros::Time& stamp);
// The room back with its mask at the map's size (255 on its cells). Throws InputError when the mask does not lie
// on the map's cell grid or term names and values differ in length.
prediction::RoomPrediction fromRos(const hidden_rooms::PredictedRoom& message, const common::OccupancyGrid& map);

// A segmented floor's rooms and passages, and its labels as a mono16 image with the rows in the order of the map
// message (row 0 at the map's origin, unlike the label image files, whose row 0 is the map's top row).
hidden_rooms::SegmentedRoom toRos(const segmentation::Room& room);
hidden_rooms::RoomPassage toRos(const segmentation::Passage& passage);
sensor_msgs::Image labelsToRos(const cv::Mat1w& labels, const std::string& frame_id, const ros::Time& stamp);

// Simulator. A velocity command as it came (non-finite values pass: Simulation::setCommand rejects them).
common::VelocityCommand fromRos(const geometry_msgs::Twist& message);
geometry_msgs::Twist toRos(const common::VelocityCommand& command);
// The beams of a scan message (count, first angle, increment, range_max).
common::LaserGeometry laserGeometryOf(const sensor_msgs::LaserScan& message);
// A scan of `laser` (ranges per beam, metres) in `frame_id`; scan_time = the laser's period.
sensor_msgs::LaserScan toRos(const std::vector<float>& ranges, const common::LaserGeometry& laser, double min_range,
                             double scan_time, const std::string& frame_id, const ros::Time& stamp);
// Pose of `child_frame_id` in `frame_id` with its velocity (base_link frame: linear x, angular z).
nav_msgs::Odometry toRos(const common::Pose2& pose, const common::VelocityCommand& velocity,
                         const std::string& frame_id, const std::string& child_frame_id, const ros::Time& stamp);
// The transform frame_id -> child_frame_id that places the child at `pose`.
geometry_msgs::TransformStamped toTransform(const common::Pose2& pose, const std::string& frame_id,
                                            const std::string& child_frame_id, const ros::Time& stamp);
common::Pose2 fromRos(const geometry_msgs::Pose& pose);

// Mapper. A scan as the core's mapper takes it, with the pose of its frame in base_link (`sensor_pose`). Throws
// InputError for a scan without beams or with a non-finite or zero angle increment.
common::RangeScan fromRos(const sensor_msgs::LaserScan& message, const common::Pose2& sensor_pose);
// The planar part of a transform (translation x, y and the yaw of its rotation).
common::Pose2 fromRos(const geometry_msgs::Transform& transform);
// A laser's mount, from the transform base frame -> scan frame: the planar pose of the scan's frame, and whether the
// laser hangs upside down (its z axis points down, e.g. rolled by pi), so that its beams sweep clockwise seen from
// above.
struct LaserMount {
  common::Pose2 pose;
  bool upside_down = false;
};
LaserMount laserMountFromRos(const geometry_msgs::Transform& transform);
// The scan as the same laser mounted the right way up at `mount.pose` gives it: for an upside-down mount the beams
// in reverse order, their angles negated (angle_min = -angle_max); otherwise the message unchanged.
sensor_msgs::LaserScan uprightScan(const sensor_msgs::LaserScan& message, const LaserMount& mount);
// The particles' poses in `frame_id` (weights are not part of the message).
geometry_msgs::PoseArray toRos(const std::vector<mapping::RbpfParticle>& particles, const std::string& frame_id,
                               const ros::Time& stamp);

}  // namespace hidden_rooms
