#include "hidden_rooms/ros/map_publisher.h"

#include <nav_msgs/MapMetaData.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/world/environment.h"

namespace hidden_rooms {

MapPublisherOptions readMapPublisherOptions(const ros::NodeHandle& private_nh) {
  MapPublisherOptions options;
  private_nh.param("map_file", options.map_file, options.map_file);
  private_nh.param("environment", options.environment, options.environment);
  private_nh.param("closed_doors", options.closed_doors, options.closed_doors);
  private_nh.param("frame_id", options.frame_id, options.frame_id);
  private_nh.param("resolution", options.render.resolution, options.render.resolution);
  private_nh.param("door_width", options.render.door_width, options.render.door_width);
  private_nh.param("margin", options.render.margin, options.render.margin);
  double wall_thickness = 0.0;
  if (private_nh.getParam("wall_thickness", wall_thickness) && wall_thickness > 0.0)
    options.render.wall_thickness = wall_thickness;
  if (options.map_file.empty() == options.environment.empty())
    throw common::InputError(private_nh.getNamespace(), "set exactly one of ~map_file and ~environment");
  return options;
}

MapPublisher::MapPublisher(ros::NodeHandle nh, const MapPublisherOptions& options) {
  common::OccupancyGrid grid;
  if (!options.map_file.empty()) {
    grid = common::loadMap(options.map_file);
  } else {
    const world::Environment environment = world::loadEnvironment(options.environment);
    grid =
        world::renderEnvironment(
            environment, world::parseDoorSelection(environment, options.closed_doors, "~closed_doors"), options.render)
            .map;
  }
  map_ = toRos(grid, options.frame_id, ros::Time::now());
  map_publisher_ = nh.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
  metadata_publisher_ = nh.advertise<nav_msgs::MapMetaData>("map_metadata", 1, true);
  map_service_ = nh.advertiseService("static_map", &MapPublisher::serveMap, this);
  map_publisher_.publish(map_);
  metadata_publisher_.publish(map_.info);
}

bool MapPublisher::serveMap(nav_msgs::GetMap::Request&, nav_msgs::GetMap::Response& response) {
  response.map = map_;
  return true;
}

}  // namespace hidden_rooms
