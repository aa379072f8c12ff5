#include "hidden_rooms/ros/conversions.h"

#include <cmath>

#include "hidden_rooms/input_error.h"

namespace hidden_rooms {

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
  grid.resolution = info.resolution;
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

}  // namespace hidden_rooms
