#pragma once

// The one place where core types and ROS messages meet.

#include <string>

#include <hidden_rooms/ClosedDoor.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/time.h>

#include "hidden_rooms/doors_file.h"
#include "hidden_rooms/occupancy_grid.h"

namespace hidden_rooms {

// Core grids keep row 0 at the top (image order); nav_msgs keeps row 0 at the origin (bottom).
nav_msgs::OccupancyGrid toRos(const OccupancyGrid& grid, const std::string& frame_id, const ros::Time& stamp);
// Throws InputError for a message whose data size does not match width x height, a non-positive resolution
// or a rotated origin.
OccupancyGrid fromRos(const nav_msgs::OccupancyGrid& message);

hidden_rooms::ClosedDoor toRos(const MapDoor& door);
MapDoor fromRos(const hidden_rooms::ClosedDoor& message);

}  // namespace hidden_rooms
