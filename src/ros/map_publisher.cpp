#include "hidden_rooms/ros/map_publisher.h"

#include <nav_msgs/MapMetaData.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/ros/parameters.h"
#include "hidden_rooms/world/environment.h"

namespace hidden_rooms {

const common::OptionTable<MapPublisherOptions>& mapPublisherNodeOptionTable() {
  using O = MapPublisherOptions;
  static const common::OptionTable<O> table{
      {"map_file", &O::map_file, "map_server yaml to publish (set this or ~environment)"},
      {"environment", &O::environment, "environment XML to render and publish"},
      {"frame_id", &O::frame_id, "frame of the published map"},
  };
  return table;
}

std::vector<common::OptionDescription> mapPublisherParameters() {
  std::vector<common::OptionDescription> rows = common::describeOptions(mapPublisherNodeOptionTable());
  const std::vector<common::OptionDescription> render = common::describeOptions(world::renderOptionTable());
  rows.insert(rows.end(), render.begin(), render.end());
  // Read apart: a door number roslaunch types as an int; a thickness that applies only when > 0.
  rows.push_back({"closed_doors", "string", "\"\"", "doors drawn closed"});
  rows.push_back({"wall_thickness", "double", "0", "rendering: metres"});
  return rows;
}

MapPublisherOptions readMapPublisherOptions(const ros::NodeHandle& private_nh) {
  MapPublisherOptions options;
  readParameters(private_nh, mapPublisherNodeOptionTable(), &options);
  readTextParameter(private_nh, "closed_doors", &options.closed_doors);
  readParameters(private_nh, world::renderOptionTable(), &options.render);
  readPositiveParameter(private_nh, "wall_thickness", &options.render.wall_thickness);  // else the file's own
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
    for (const std::string& repair : environment.repairs)
      ROS_WARN("%s: %s", options.environment.c_str(), repair.c_str());
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
