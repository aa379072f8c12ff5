#include "hidden_rooms/ros/conversions.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/prediction/prediction_support.h"

namespace hidden_rooms {
namespace {

// The double a float was written from: its shortest decimal form (0.05f -> 0.05, not 0.0500000007), so that a
// map's resolution is the same in a node as in the file it came from.
double floatToDouble(float value) {
  char text[64];
  const auto end = std::to_chars(text, text + sizeof(text) - 1, value).ptr;
  *end = '\0';
  return std::strtod(text, nullptr);
}

}  // namespace

geometry_msgs::Point toRos(const common::Point2& point, double z) {
  geometry_msgs::Point message;
  message.x = point.x();
  message.y = point.y();
  message.z = z;
  return message;
}

nav_msgs::OccupancyGrid toRos(const common::OccupancyGrid& grid, const std::string& frame_id, const ros::Time& stamp) {
  nav_msgs::OccupancyGrid message;
  message.header.frame_id = frame_id;
  message.header.stamp = stamp;
  message.info.map_load_time = stamp;
  message.info.resolution = static_cast<float>(grid.resolution);
  message.info.width = static_cast<uint32_t>(grid.width());
  message.info.height = static_cast<uint32_t>(grid.height());
  message.info.origin.position.x = grid.origin.x();
  message.info.origin.position.y = grid.origin.y();
  message.info.origin.orientation.w = 1.0;
  message.data.resize(static_cast<size_t>(grid.width()) * grid.height());
  for (int row = 0; row < grid.height(); ++row) {
    const int8_t* source = grid.cells.ptr<int8_t>(row);
    std::copy(source, source + grid.width(), message.data.begin() + static_cast<size_t>(grid.height() - 1 - row) * grid.width());
  }
  return message;
}

common::OccupancyGrid fromRos(const nav_msgs::OccupancyGrid& message) {
  const auto& info = message.info;
  if (static_cast<size_t>(info.width) * info.height != message.data.size())
    throw common::InputError("map message", "data has " + std::to_string(message.data.size()) +
                                                " cells, width x height is " +
                                                std::to_string(static_cast<size_t>(info.width) * info.height));
  if (!(info.resolution > 0.0f) || !std::isfinite(info.resolution))
    throw common::InputError("map message", "resolution must be positive");
  const auto& q = info.origin.orientation;
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!(std::abs(norm - 1.0) < 1e-3))
    throw common::InputError("map message", "the origin's orientation is not a unit quaternion (norm " +
                                                common::formatNumber(norm) + "; an unrotated map has w = 1)");
  const double yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  if (std::abs(yaw) > 1e-6) throw common::InputError("map message", "rotated map origins are not supported");
  if (!std::isfinite(info.origin.position.x) || !std::isfinite(info.origin.position.y))
    throw common::InputError("map message", "the origin is not finite");
  const auto bad_value = std::find_if(message.data.begin(), message.data.end(),
                                      [](int8_t value) { return value < -1 || value > 100; });
  if (bad_value != message.data.end())
    throw common::InputError("map message", "cell " + std::to_string(bad_value - message.data.begin()) + " is " +
                                                std::to_string(*bad_value) + " (values are -1 unknown or 0..100)");
  common::OccupancyGrid grid;
  grid.resolution = floatToDouble(info.resolution);
  grid.origin = common::Point2(info.origin.position.x, info.origin.position.y);
  grid.cells.create(static_cast<int>(info.height), static_cast<int>(info.width));
  for (int row = 0; row < grid.height(); ++row) {
    const auto begin = message.data.begin() + static_cast<size_t>(grid.height() - 1 - row) * grid.width();
    std::copy(begin, begin + grid.width(), grid.cells.ptr<int8_t>(row));
  }
  return grid;
}

hidden_rooms::ClosedDoor toRos(const common::MapDoor& door) {
  hidden_rooms::ClosedDoor message;
  message.id = door.id;
  message.position.x = door.position.x();
  message.position.y = door.position.y();
  message.width = door.width;
  message.orientation = door.orientation == common::DoorOrientation::kAlongX ? hidden_rooms::ClosedDoor::ALONG_X
                                                                             : hidden_rooms::ClosedDoor::ALONG_Y;
  return message;
}

common::MapDoor fromRos(const hidden_rooms::ClosedDoor& message) {
  if (!std::isfinite(message.position.x) || !std::isfinite(message.position.y) || !std::isfinite(message.width) ||
      message.width <= 0.0)
    throw common::InputError("door " + std::to_string(message.id), "position and width must be finite, width positive");
  if (message.orientation != hidden_rooms::ClosedDoor::ALONG_X && message.orientation != hidden_rooms::ClosedDoor::ALONG_Y)
    throw common::InputError("door " + std::to_string(message.id), "orientation must be ALONG_X (0) or ALONG_Y (1)");
  common::MapDoor door;
  door.id = message.id;
  door.position = common::Point2(message.position.x, message.position.y);
  door.width = message.width;
  door.orientation = message.orientation == hidden_rooms::ClosedDoor::ALONG_X ? common::DoorOrientation::kAlongX
                                                                              : common::DoorOrientation::kAlongY;
  return door;
}

common::DoorsFile fromRos(const std::vector<hidden_rooms::ClosedDoor>& messages, const std::string& frame) {
  common::DoorsFile doors;
  doors.frame = frame;
  for (const hidden_rooms::ClosedDoor& message : messages) doors.doors.push_back(fromRos(message));
  return doors;
}

std::vector<hidden_rooms::ClosedDoor> toRos(const common::DoorsFile& doors) {
  std::vector<hidden_rooms::ClosedDoor> messages;
  for (const common::MapDoor& door : doors.doors) messages.push_back(toRos(door));
  return messages;
}

std::map<std::string, double> fromRos(const std::vector<hidden_rooms::PredictionParameter>& messages) {
  std::map<std::string, double> parameters;
  for (const hidden_rooms::PredictionParameter& message : messages) {
    if (message.name.empty()) throw common::InputError("parameters", "a parameter has no name");
    if (!std::isfinite(message.value))
      throw common::InputError("parameters", "parameter '" + message.name + "' is not finite");
    if (!parameters.emplace(message.name, message.value).second)
      throw common::InputError("parameters", "parameter '" + message.name + "' is given twice");
  }
  return parameters;
}

std::vector<hidden_rooms::PredictionParameter> toRos(const std::map<std::string, double>& parameters) {
  std::vector<hidden_rooms::PredictionParameter> messages;
  for (const auto& [name, value] : parameters) {
    hidden_rooms::PredictionParameter message;
    message.name = name;
    message.value = value;
    messages.push_back(message);
  }
  return messages;
}

hidden_rooms::PredictedRoom toRos(const prediction::RoomPrediction& room, int label, const common::OccupancyGrid& map,
                                  const std::string& frame_id, const ros::Time& stamp) {
  hidden_rooms::PredictedRoom message;
  message.door_id = room.door_id;
  message.label = static_cast<uint32_t>(label);
  message.status = room.placed ? hidden_rooms::PredictedRoom::PREDICTED : hidden_rooms::PredictedRoom::NOT_PLACED;
  message.problem = room.placed ? "" : room.problem;
  for (const common::Point2& p : room.polygon) message.polygon.push_back(toRos(p, 0.0));
  message.area = room.area;
  const auto score = room.terms.find("score");
  message.score = score != room.terms.end() ? score->second : std::numeric_limits<double>::quiet_NaN();
  for (const auto& [name, value] : room.terms) {
    message.term_names.push_back(name);
    message.term_values.push_back(value);
  }
  message.mask.header.frame_id = frame_id;
  message.mask.header.stamp = stamp;
  message.mask.info.resolution = static_cast<float>(map.resolution);
  message.mask.info.origin.orientation.w = 1.0;
  std::vector<cv::Point> cells;
  if (room.placed && !room.mask.empty()) cv::findNonZero(room.mask, cells);
  if (!cells.empty()) {
    const cv::Rect box = cv::boundingRect(cells);
    common::OccupancyGrid crop;
    crop.resolution = map.resolution;
    crop.origin = map.origin + map.resolution * common::Point2(box.x, map.height() - box.y - box.height);
    crop.cells = cv::Mat_<int8_t>(box.size(), common::OccupancyGrid::kUnknown);
    crop.cells.setTo(common::OccupancyGrid::kFree, room.mask(box));
    message.mask = toRos(crop, frame_id, stamp);
  }
  return message;
}

prediction::RoomPrediction fromRos(const hidden_rooms::PredictedRoom& message, const common::OccupancyGrid& map) {
  const std::string source = "room of door " + std::to_string(message.door_id);
  prediction::RoomPrediction room;
  room.door_id = message.door_id;
  room.placed = message.status == hidden_rooms::PredictedRoom::PREDICTED;
  room.problem = message.problem;
  room.mask = cv::Mat1b::zeros(map.cells.size());
  room.area = message.area;
  for (const geometry_msgs::Point& p : message.polygon) room.polygon.emplace_back(p.x, p.y);
  if (message.term_names.size() != message.term_values.size())
    throw common::InputError(source, "term_names and term_values differ in length");
  for (size_t k = 0; k < message.term_names.size(); ++k) room.terms[message.term_names[k]] = message.term_values[k];
  if (!room.placed || message.mask.info.width == 0 || message.mask.info.height == 0) return room;
  const common::OccupancyGrid crop = fromRos(message.mask);
  const common::Point2 offset = (crop.origin - map.origin) / map.resolution;
  const int col = static_cast<int>(std::lround(offset.x()));
  const int row = map.height() - static_cast<int>(std::lround(offset.y())) - crop.height();
  if (std::abs(crop.resolution - map.resolution) > 1e-9 * map.resolution ||
      (offset - common::Point2(std::round(offset.x()), std::round(offset.y()))).cwiseAbs().maxCoeff() > 1e-3)
    throw common::InputError(source, "mask is not on the map's cell grid");
  if (col < 0 || row < 0 || col + crop.width() > map.width() || row + crop.height() > map.height())
    throw common::InputError(source, "mask reaches outside the map");
  room.mask(cv::Rect(col, row, crop.width(), crop.height())).setTo(255, crop.cells == common::OccupancyGrid::kFree);
  return room;
}

hidden_rooms::SegmentedRoom toRos(const segmentation::Room& room) {
  hidden_rooms::SegmentedRoom message;
  message.label = static_cast<uint32_t>(room.label);
  message.kind = room.kind == segmentation::RoomKind::kCorridor ? hidden_rooms::SegmentedRoom::CORRIDOR
                                                                : hidden_rooms::SegmentedRoom::ROOM;
  message.type = room.type;
  message.predicted = room.predicted;
  message.area = room.area;
  message.width = room.width;
  message.mean_width = room.mean_width;
  message.centroid = toRos(room.centroid, 0.0);
  for (const common::Point2& vertex : room.outline) message.outline.push_back(toRos(vertex, 0.0));
  return message;
}

hidden_rooms::RoomPassage toRos(const segmentation::Passage& passage) {
  hidden_rooms::RoomPassage message;
  message.room_a = static_cast<uint32_t>(passage.room_a);
  message.room_b = static_cast<uint32_t>(passage.room_b);
  switch (passage.kind) {
    case segmentation::PassageKind::kOpen: message.kind = hidden_rooms::RoomPassage::OPEN; break;
    case segmentation::PassageKind::kClosed: message.kind = hidden_rooms::RoomPassage::CLOSED; break;
    case segmentation::PassageKind::kPredicted: message.kind = hidden_rooms::RoomPassage::PREDICTED; break;
  }
  message.door_id = passage.door_id;
  message.centre = toRos(passage.centre, 0.0);
  message.width = passage.width;
  return message;
}

sensor_msgs::Image labelsToRos(const cv::Mat1w& labels, const std::string& frame_id, const ros::Time& stamp) {
  sensor_msgs::Image message;
  message.header.frame_id = frame_id;
  message.header.stamp = stamp;
  message.width = static_cast<uint32_t>(labels.cols);
  message.height = static_cast<uint32_t>(labels.rows);
  message.encoding = "mono16";
  message.is_bigendian = false;
  message.step = message.width * 2;
  message.data.resize(static_cast<size_t>(message.step) * message.height);
  for (int row = 0; row < labels.rows; ++row)
    for (int col = 0; col < labels.cols; ++col) {
      const uint16_t label = labels(labels.rows - 1 - row, col);
      const size_t at = static_cast<size_t>(row) * message.step + 2 * static_cast<size_t>(col);
      message.data[at] = static_cast<uint8_t>(label & 0xff);
      message.data[at + 1] = static_cast<uint8_t>(label >> 8);
    }
  return message;
}

common::VelocityCommand fromRos(const geometry_msgs::Twist& message) { return {message.linear.x, message.angular.z}; }

geometry_msgs::Twist toRos(const common::VelocityCommand& command) {
  geometry_msgs::Twist message;
  message.linear.x = command.linear;
  message.angular.z = command.angular;
  return message;
}

common::LaserGeometry laserGeometryOf(const sensor_msgs::LaserScan& message) {
  common::LaserGeometry laser;
  laser.beams = static_cast<int>(message.ranges.size());
  laser.angle_min = message.angle_min;
  laser.angle_increment = message.angle_increment;
  laser.max_range = message.range_max;
  return laser;
}

sensor_msgs::LaserScan toRos(const std::vector<float>& ranges, const common::LaserGeometry& laser, double min_range,
                             double scan_time, const std::string& frame_id, const ros::Time& stamp) {
  sensor_msgs::LaserScan message;
  message.header.frame_id = frame_id;
  message.header.stamp = stamp;
  message.angle_min = static_cast<float>(laser.angle_min);
  message.angle_max = static_cast<float>(laser.angle_min + (laser.beams - 1) * laser.angle_increment);
  message.angle_increment = static_cast<float>(laser.angle_increment);
  message.time_increment = 0.0f;
  message.scan_time = static_cast<float>(scan_time);
  message.range_min = static_cast<float>(min_range);
  message.range_max = static_cast<float>(laser.max_range);
  message.ranges = ranges;
  return message;
}

nav_msgs::Odometry toRos(const common::Pose2& pose, const common::VelocityCommand& velocity,
                         const std::string& frame_id, const std::string& child_frame_id, const ros::Time& stamp) {
  nav_msgs::Odometry message;
  message.header.frame_id = frame_id;
  message.header.stamp = stamp;
  message.child_frame_id = child_frame_id;
  message.pose.pose.position.x = pose.x;
  message.pose.pose.position.y = pose.y;
  message.pose.pose.orientation.z = std::sin(0.5 * pose.yaw);
  message.pose.pose.orientation.w = std::cos(0.5 * pose.yaw);
  message.twist.twist.linear.x = velocity.linear;
  message.twist.twist.angular.z = velocity.angular;
  return message;
}

geometry_msgs::TransformStamped toTransform(const common::Pose2& pose, const std::string& frame_id,
                                            const std::string& child_frame_id, const ros::Time& stamp) {
  geometry_msgs::TransformStamped message;
  message.header.frame_id = frame_id;
  message.header.stamp = stamp;
  message.child_frame_id = child_frame_id;
  message.transform.translation.x = pose.x;
  message.transform.translation.y = pose.y;
  message.transform.rotation.z = std::sin(0.5 * pose.yaw);
  message.transform.rotation.w = std::cos(0.5 * pose.yaw);
  return message;
}

common::Pose2 fromRos(const geometry_msgs::Pose& pose) {
  const auto& q = pose.orientation;
  return {pose.position.x, pose.position.y,
          std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))};
}

common::RangeScan fromRos(const sensor_msgs::LaserScan& message, const common::Pose2& sensor_pose) {
  if (message.ranges.empty()) throw common::InputError("scan", "has no beams");
  if (!std::isfinite(message.angle_min) || !std::isfinite(message.angle_increment) || message.angle_increment == 0.0f)
    throw common::InputError("scan", "non-finite or zero angle increment");
  common::RangeScan scan;
  scan.angle_min = message.angle_min;
  scan.angle_increment = message.angle_increment;
  scan.range_min = message.range_min;
  scan.range_max = message.range_max;
  scan.ranges = message.ranges;
  scan.sensor_pose = sensor_pose;
  return scan;
}

common::Pose2 fromRos(const geometry_msgs::Transform& transform) {
  geometry_msgs::Pose pose;
  pose.position.x = transform.translation.x;
  pose.position.y = transform.translation.y;
  pose.orientation = transform.rotation;
  return fromRos(pose);
}

LaserMount laserMountFromRos(const geometry_msgs::Transform& transform) {
  const auto& q = transform.rotation;
  LaserMount mount;
  mount.pose = fromRos(transform);
  mount.upside_down = 1.0 - 2.0 * (q.x * q.x + q.y * q.y) < 0.0;  // z component of the laser's z axis
  return mount;
}

sensor_msgs::LaserScan uprightScan(const sensor_msgs::LaserScan& message, const LaserMount& mount) {
  if (!mount.upside_down) return message;
  sensor_msgs::LaserScan upright = message;
  upright.angle_min = -message.angle_max;
  upright.angle_max = -message.angle_min;
  std::reverse(upright.ranges.begin(), upright.ranges.end());
  std::reverse(upright.intensities.begin(), upright.intensities.end());
  return upright;
}

geometry_msgs::PoseArray toRos(const std::vector<mapping::RbpfParticle>& particles, const std::string& frame_id,
                               const ros::Time& stamp) {
  geometry_msgs::PoseArray message;
  message.header.frame_id = frame_id;
  message.header.stamp = stamp;
  for (const mapping::RbpfParticle& particle : particles) {
    geometry_msgs::Pose pose;
    pose.position.x = particle.pose.x;
    pose.position.y = particle.pose.y;
    pose.orientation.z = std::sin(0.5 * particle.pose.yaw);
    pose.orientation.w = std::cos(0.5 * particle.pose.yaw);
    message.poses.push_back(pose);
  }
  return message;
}

}  // namespace hidden_rooms
