#include "hidden_rooms/ros/conversions.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/label_image.h"
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

std_msgs::ColorRGBA colour(double r, double g, double b, double a) {
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(r);
  c.g = static_cast<float>(g);
  c.b = static_cast<float>(b);
  c.a = static_cast<float>(a);
  return c;
}

std_msgs::ColorRGBA roomColourRgba(int label, double alpha) {
  const cv::Vec3b bgr = roomColour(label);
  return colour(bgr[2] / 255.0, bgr[1] / 255.0, bgr[0] / 255.0, alpha);
}

geometry_msgs::Point point(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

// A map-frame point of continuous image coordinates (x = column, y = row from the top).
geometry_msgs::Point imagePoint(const OccupancyGrid& map, double x, double y, double z) {
  return point(map.origin.x() + x * map.resolution, map.origin.y() + (map.height() - y) * map.resolution, z);
}

visualization_msgs::Marker newMarker(const std::string& ns, int id, int type, const std::string& frame_id,
                                     const ros::Time& stamp) {
  visualization_msgs::Marker marker;
  marker.header.frame_id = frame_id;
  marker.header.stamp = stamp;
  marker.ns = ns;
  marker.id = id;
  marker.type = type;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose.orientation.w = 1.0;
  marker.scale.x = marker.scale.y = marker.scale.z = 1.0;
  marker.color = colour(1.0, 1.0, 1.0, 1.0);
  return marker;
}

// Two triangles per axis-aligned image rectangle [x0, x1) x [y0, y1).
void addRectangle(const OccupancyGrid& map, double x0, double y0, double x1, double y1, double z,
                  const std_msgs::ColorRGBA* vertex_colour, visualization_msgs::Marker* marker) {
  const geometry_msgs::Point a = imagePoint(map, x0, y1, z), b = imagePoint(map, x1, y1, z),
                             c = imagePoint(map, x1, y0, z), d = imagePoint(map, x0, y0, z);
  for (const geometry_msgs::Point& p : {a, b, c, a, c, d}) {
    marker->points.push_back(p);
    if (vertex_colour != nullptr) marker->colors.push_back(*vertex_colour);
  }
}

// The cells of a mask as few rectangles: runs of each row, stacked while the next row has the same run.
void addMaskTriangles(const OccupancyGrid& map, const cv::Mat1b& mask, double z, visualization_msgs::Marker* marker) {
  std::vector<cv::Point> cells;
  cv::findNonZero(mask, cells);
  if (cells.empty()) return;
  const cv::Rect box = cv::boundingRect(cells);
  std::map<std::pair<int, int>, int> open;  // run [begin, end) -> first row
  auto close_runs = [&](const std::set<std::pair<int, int>>& keep, int row) {
    for (auto it = open.begin(); it != open.end();) {
      if (keep.count(it->first) == 0) {
        addRectangle(map, it->first.first, it->second, it->first.second, row, z, nullptr, marker);
        it = open.erase(it);
      } else {
        ++it;
      }
    }
  };
  for (int row = box.y; row < box.y + box.height; ++row) {
    std::set<std::pair<int, int>> runs;
    const uchar* line = mask.ptr<uchar>(row);
    for (int col = box.x; col < box.x + box.width;) {
      if (line[col] == 0) {
        ++col;
        continue;
      }
      const int begin = col;
      while (col < box.x + box.width && line[col] != 0) ++col;
      runs.insert({begin, col});
    }
    close_runs(runs, row);
    for (const auto& run : runs) open.emplace(run, row);
  }
  close_runs({}, box.y + box.height);
}

}  // namespace

nav_msgs::OccupancyGrid toRos(const OccupancyGrid& grid, const std::string& frame_id, const ros::Time& stamp) {
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

OccupancyGrid fromRos(const nav_msgs::OccupancyGrid& message) {
  const auto& info = message.info;
  if (static_cast<size_t>(info.width) * info.height != message.data.size())
    throw InputError("map message", "data has " + std::to_string(message.data.size()) + " cells, width x height is " +
                                        std::to_string(static_cast<size_t>(info.width) * info.height));
  if (!(info.resolution > 0.0f) || !std::isfinite(info.resolution))
    throw InputError("map message", "resolution must be positive");
  const auto& q = info.origin.orientation;
  const double yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  if (std::abs(yaw) > 1e-6) throw InputError("map message", "rotated map origins are not supported");
  OccupancyGrid grid;
  grid.resolution = floatToDouble(info.resolution);
  grid.origin = Point2(info.origin.position.x, info.origin.position.y);
  grid.cells.create(static_cast<int>(info.height), static_cast<int>(info.width));
  for (int row = 0; row < grid.height(); ++row) {
    const auto begin = message.data.begin() + static_cast<size_t>(grid.height() - 1 - row) * grid.width();
    std::copy(begin, begin + grid.width(), grid.cells.ptr<int8_t>(row));
  }
  return grid;
}

hidden_rooms::ClosedDoor toRos(const MapDoor& door) {
  hidden_rooms::ClosedDoor message;
  message.id = door.id;
  message.position.x = door.position.x();
  message.position.y = door.position.y();
  message.width = door.width;
  message.orientation = door.orientation == DoorOrientation::kAlongX ? hidden_rooms::ClosedDoor::ALONG_X
                                                                      : hidden_rooms::ClosedDoor::ALONG_Y;
  return message;
}

MapDoor fromRos(const hidden_rooms::ClosedDoor& message) {
  if (!std::isfinite(message.position.x) || !std::isfinite(message.position.y) || !std::isfinite(message.width) ||
      message.width <= 0.0)
    throw InputError("door " + std::to_string(message.id), "position and width must be finite, width positive");
  if (message.orientation != hidden_rooms::ClosedDoor::ALONG_X && message.orientation != hidden_rooms::ClosedDoor::ALONG_Y)
    throw InputError("door " + std::to_string(message.id), "orientation must be ALONG_X (0) or ALONG_Y (1)");
  MapDoor door;
  door.id = message.id;
  door.position = Point2(message.position.x, message.position.y);
  door.width = message.width;
  door.orientation = message.orientation == hidden_rooms::ClosedDoor::ALONG_X ? DoorOrientation::kAlongX
                                                                               : DoorOrientation::kAlongY;
  return door;
}

DoorsFile fromRos(const std::vector<hidden_rooms::ClosedDoor>& messages, const std::string& frame) {
  DoorsFile doors;
  doors.frame = frame;
  for (const hidden_rooms::ClosedDoor& message : messages) doors.doors.push_back(fromRos(message));
  return doors;
}

std::vector<hidden_rooms::ClosedDoor> toRos(const DoorsFile& doors) {
  std::vector<hidden_rooms::ClosedDoor> messages;
  for (const MapDoor& door : doors.doors) messages.push_back(toRos(door));
  return messages;
}

std::map<std::string, double> fromRos(const std::vector<hidden_rooms::PredictionParameter>& messages) {
  std::map<std::string, double> parameters;
  for (const hidden_rooms::PredictionParameter& message : messages) {
    if (message.name.empty()) throw InputError("parameters", "a parameter has no name");
    if (!std::isfinite(message.value))
      throw InputError("parameters", "parameter '" + message.name + "' is not finite");
    if (!parameters.emplace(message.name, message.value).second)
      throw InputError("parameters", "parameter '" + message.name + "' is given twice");
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

hidden_rooms::PredictedRoom toRos(const RoomPrediction& room, int label, const OccupancyGrid& map,
                                  const std::string& frame_id, const ros::Time& stamp) {
  hidden_rooms::PredictedRoom message;
  message.door_id = room.door_id;
  message.label = static_cast<uint32_t>(label);
  message.status = room.placed ? hidden_rooms::PredictedRoom::PREDICTED : hidden_rooms::PredictedRoom::NOT_PLACED;
  message.problem = room.placed ? "" : room.problem;
  for (const Point2& p : room.polygon) message.polygon.push_back(point(p.x(), p.y(), 0.0));
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
    OccupancyGrid crop;
    crop.resolution = map.resolution;
    crop.origin = map.origin + map.resolution * Point2(box.x, map.height() - box.y - box.height);
    crop.cells = cv::Mat_<int8_t>(box.size(), OccupancyGrid::kUnknown);
    crop.cells.setTo(OccupancyGrid::kFree, room.mask(box));
    message.mask = toRos(crop, frame_id, stamp);
  }
  return message;
}

RoomPrediction fromRos(const hidden_rooms::PredictedRoom& message, const OccupancyGrid& map) {
  const std::string source = "room of door " + std::to_string(message.door_id);
  RoomPrediction room;
  room.door_id = message.door_id;
  room.placed = message.status == hidden_rooms::PredictedRoom::PREDICTED;
  room.problem = message.problem;
  room.mask = cv::Mat1b::zeros(map.cells.size());
  room.area = message.area;
  for (const geometry_msgs::Point& p : message.polygon) room.polygon.emplace_back(p.x, p.y);
  if (message.term_names.size() != message.term_values.size())
    throw InputError(source, "term_names and term_values differ in length");
  for (size_t k = 0; k < message.term_names.size(); ++k) room.terms[message.term_names[k]] = message.term_values[k];
  if (!room.placed || message.mask.info.width == 0 || message.mask.info.height == 0) return room;
  const OccupancyGrid crop = fromRos(message.mask);
  const Point2 offset = (crop.origin - map.origin) / map.resolution;
  const int col = static_cast<int>(std::lround(offset.x()));
  const int row = map.height() - static_cast<int>(std::lround(offset.y())) - crop.height();
  if (std::abs(crop.resolution - map.resolution) > 1e-9 * map.resolution ||
      (offset - Point2(std::round(offset.x()), std::round(offset.y()))).cwiseAbs().maxCoeff() > 1e-3)
    throw InputError(source, "mask is not on the map's cell grid");
  if (col < 0 || row < 0 || col + crop.width() > map.width() || row + crop.height() > map.height())
    throw InputError(source, "mask reaches outside the map");
  room.mask(cv::Rect(col, row, crop.width(), crop.height())).setTo(255, crop.cells == OccupancyGrid::kFree);
  return room;
}

visualization_msgs::MarkerArray toMarkers(const OccupancyGrid& map, const DoorsFile& doors,
                                          const std::vector<RoomPrediction>& rooms, const cv::Mat1w& labels,
                                          const std::string& frame_id, const ros::Time& stamp) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray array;
  Marker clear = newMarker("", 0, Marker::CUBE, frame_id, stamp);
  clear.action = Marker::DELETEALL;
  array.markers.push_back(clear);
  for (size_t k = 0; k < rooms.size(); ++k) {
    const RoomPrediction& room = rooms[k];
    const int label = static_cast<int>(k) + 1;
    if (!room.placed) continue;
    const cv::Mat1b cells = labels == label;
    Marker fill = newMarker("rooms", room.door_id, Marker::TRIANGLE_LIST, frame_id, stamp);
    fill.color = roomColourRgba(label, 0.55);
    addMaskTriangles(map, cells, 0.01, &fill);
    if (!fill.points.empty()) array.markers.push_back(fill);
    if (room.polygon.size() >= 2) {
      Marker outline = newMarker("outlines", room.door_id, Marker::LINE_STRIP, frame_id, stamp);
      outline.scale.x = 2.0 * map.resolution;
      outline.color = roomColourRgba(label, 1.0);
      for (const Point2& p : room.polygon) outline.points.push_back(point(p.x(), p.y(), 0.02));
      outline.points.push_back(outline.points.front());
      array.markers.push_back(outline);
    }
    const cv::Moments moments = cv::moments(cells, true);
    const cv::Mat1b own = room.mask;
    const cv::Moments fallback = moments.m00 > 0 ? moments : cv::moments(own, true);
    if (fallback.m00 > 0) {
      Marker text = newMarker("labels", room.door_id, Marker::TEXT_VIEW_FACING, frame_id, stamp);
      text.pose.position = imagePoint(map, fallback.m10 / fallback.m00 + 0.5, fallback.m01 / fallback.m00 + 0.5, 0.5);
      text.scale.z = 1.0;  // metres: text height
      char area[32];
      std::snprintf(area, sizeof(area), "%.1f", room.area);
      text.text = "door " + std::to_string(room.door_id) + "\n" + area + " m2";
      array.markers.push_back(text);
    }
  }
  Marker door_lines = newMarker("doors", 0, Marker::LINE_LIST, frame_id, stamp);
  door_lines.scale.x = 0.3;  // metres: line width
  for (size_t k = 0; k < doors.doors.size(); ++k) {
    const MapDoor& door = doors.doors[k];
    const bool placed = k < rooms.size() && rooms[k].placed;
    const std_msgs::ColorRGBA c = placed ? colour(0.9, 0.1, 0.1, 1.0) : colour(0.5, 0.5, 0.5, 1.0);
    const Point2 half = door.orientation == DoorOrientation::kAlongX ? Point2(door.width / 2, 0) : Point2(0, door.width / 2);
    for (const Point2& p : {Point2(door.position - half), Point2(door.position + half)}) {
      door_lines.points.push_back(point(p.x(), p.y(), 0.03));
      door_lines.colors.push_back(c);
    }
  }
  if (!door_lines.points.empty()) array.markers.push_back(door_lines);
  return array;
}

visualization_msgs::MarkerArray toDebugMarkers(const OccupancyGrid& map, const Layout& layout,
                                               const std::string& frame_id, const ros::Time& stamp) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray array;
  const CellGrid& grid = layout.grid;
  if (grid.xs.size() < 2 || grid.ys.size() < 2) return array;
  Marker lines = newMarker("debug_extended_lines", 0, Marker::LINE_LIST, frame_id, stamp);
  lines.scale.x = map.resolution;
  for (const ExtendedLine& line : layout.lines) {
    const std_msgs::ColorRGBA c = line.source == LineSource::kWall       ? colour(0.2, 0.4, 1.0, 1.0)
                                  : line.source == LineSource::kDoorPair ? colour(1.0, 0.6, 0.0, 1.0)
                                                                         : colour(0.6, 0.6, 0.6, 1.0);
    if (line.axis == LineAxis::kHorizontal) {
      lines.points.push_back(imagePoint(map, grid.xs.front(), line.position, 0.04));
      lines.points.push_back(imagePoint(map, grid.xs.back(), line.position, 0.04));
    } else {
      lines.points.push_back(imagePoint(map, line.position, grid.ys.front(), 0.04));
      lines.points.push_back(imagePoint(map, line.position, grid.ys.back(), 0.04));
    }
    lines.colors.push_back(c);
    lines.colors.push_back(c);
  }
  if (!lines.points.empty()) array.markers.push_back(lines);
  Marker cells = newMarker("debug_in_out_cells", 0, Marker::TRIANGLE_LIST, frame_id, stamp);
  for (const LayoutCell& cell : grid.cells) {
    const std_msgs::ColorRGBA c = cell.out ? colour(0.9, 0.2, 0.2, 0.25) : colour(0.2, 0.8, 0.2, 0.25);
    addRectangle(map, cell.rect.x, cell.rect.y, cell.rect.x + cell.rect.width, cell.rect.y + cell.rect.height, 0.005,
                 &c, &cells);
  }
  if (!cells.points.empty()) array.markers.push_back(cells);
  return array;
}

VelocityCommand fromRos(const geometry_msgs::Twist& message) { return {message.linear.x, message.angular.z}; }

geometry_msgs::Twist toRos(const VelocityCommand& command) {
  geometry_msgs::Twist message;
  message.linear.x = command.linear;
  message.angular.z = command.angular;
  return message;
}

LaserGeometry laserGeometryOf(const sensor_msgs::LaserScan& message) {
  LaserGeometry laser;
  laser.beams = static_cast<int>(message.ranges.size());
  laser.angle_min = message.angle_min;
  laser.angle_increment = message.angle_increment;
  laser.max_range = message.range_max;
  return laser;
}

sensor_msgs::LaserScan toRos(const std::vector<float>& ranges, const LaserGeometry& laser, double min_range,
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

nav_msgs::Odometry toRos(const Pose2& pose, const VelocityCommand& velocity, const std::string& frame_id,
                         const std::string& child_frame_id, const ros::Time& stamp) {
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

geometry_msgs::TransformStamped toTransform(const Pose2& pose, const std::string& frame_id,
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

Pose2 fromRos(const geometry_msgs::Pose& pose) {
  const auto& q = pose.orientation;
  return {pose.position.x, pose.position.y,
          std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))};
}

RangeScan fromRos(const sensor_msgs::LaserScan& message, const Pose2& sensor_pose) {
  if (message.ranges.empty()) throw InputError("scan", "has no beams");
  if (!std::isfinite(message.angle_min) || !std::isfinite(message.angle_increment) || message.angle_increment == 0.0f)
    throw InputError("scan", "non-finite or zero angle increment");
  RangeScan scan;
  scan.angle_min = message.angle_min;
  scan.angle_increment = message.angle_increment;
  scan.range_min = message.range_min;
  scan.range_max = message.range_max;
  scan.ranges = message.ranges;
  scan.sensor_pose = sensor_pose;
  return scan;
}

Pose2 fromRos(const geometry_msgs::Transform& transform) {
  geometry_msgs::Pose pose;
  pose.position.x = transform.translation.x;
  pose.position.y = transform.translation.y;
  pose.orientation = transform.rotation;
  return fromRos(pose);
}

geometry_msgs::PoseArray toRos(const std::vector<RbpfParticle>& particles, const std::string& frame_id,
                               const ros::Time& stamp) {
  geometry_msgs::PoseArray message;
  message.header.frame_id = frame_id;
  message.header.stamp = stamp;
  for (const RbpfParticle& particle : particles) {
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
