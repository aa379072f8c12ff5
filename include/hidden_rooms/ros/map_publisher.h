#pragma once

#include <string>
#include <vector>

#include <nav_msgs/GetMap.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>

#include "hidden_rooms/world/render.h"

namespace hidden_rooms {

// Parameters of the map_publisher node (all private, ~name).
struct MapPublisherOptions {
  std::string map_file;      // map_server yaml; used when set
  std::string environment;   // environment XML, rendered when map_file is empty
  std::string closed_doors;  // doors drawn closed when rendering: numbers/ids, comma-separated, or "all"
  world::RenderOptions render;  // resolution, door_width, wall_thickness, margin
  std::string frame_id = "map";
};

// The node's own parameters (sources, frame); the rendering's are in the core's table.
const common::OptionTable<MapPublisherOptions>& mapPublisherNodeOptionTable();
// Every parameter of the node, as docs/ros_api.md lists them (~closed_doors and ~wall_thickness, read apart,
// listed by hand).
std::vector<common::OptionDescription> mapPublisherParameters();
// Reads the options from the private node handle. Throws InputError naming the first bad parameter, or when
// neither or both sources are set.
MapPublisherOptions readMapPublisherOptions(const ros::NodeHandle& private_nh);

// map_server's job from the core loaders: publishes a map file or a rendered environment, latched, on `map`
// and `map_metadata`, and answers `static_map`.
class MapPublisher {
 public:
  // Loads the map (throws InputError when it cannot); does not wait for anything.
  MapPublisher(ros::NodeHandle nh, const MapPublisherOptions& options);

 private:
  bool serveMap(nav_msgs::GetMap::Request& request, nav_msgs::GetMap::Response& response);

  nav_msgs::OccupancyGrid map_;
  ros::Publisher map_publisher_;
  ros::Publisher metadata_publisher_;
  ros::ServiceServer map_service_;
};

}  // namespace hidden_rooms
