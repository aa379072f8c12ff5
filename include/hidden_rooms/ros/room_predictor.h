#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <boost/thread/recursive_mutex.hpp>
#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/PointStamped.h>
#include <hidden_rooms/PredictRooms.h>
#include <hidden_rooms/RoomPredictorConfig.h>
#include <hidden_rooms/SaveDoors.h>
#include <hidden_rooms/SegmentRooms.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/input_limits.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/options.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "hidden_rooms/segmentation/floor.h"

namespace hidden_rooms {

// Parameters of the room_predictor node (all private, ~name).
struct RoomPredictorOptions {
  std::string method = "default";  // method used when a request names none (and by ~predict_on_map)
  std::string closed_doors_file;   // doors.yaml: the doors of a request that gives none; "" = none
  std::string params_file;         // flat `name: number` overrides applied to every request; "" = none
  bool predict_on_map = false;     // predict the file's doors again whenever a new map arrives on `map`
  bool publish_debug = false;      // add the layout analysis to predicted_rooms (extended lines, IN/OUT cells)
  std::string frame_id = "map";    // frame of outputs when the map message has an empty header.frame_id
  std::string octomap_file;        // 3D map source (.bt/.ot): its band [octomap_z_min, octomap_z_max] sliced
                                   // into the map predicted on until one arrives on `map`; "" = none
  double octomap_z_min = 0.1;      // metres
  double octomap_z_max = 2.0;      // metres
  std::string octomap_out;         // after each prediction, the completed map extruded to this .ot/.bt; "" = off
  double octomap_height = 2.5;     // metres, height of the extruded walls
  // Doors marked in rviz: a point published on `clicked_point` ("Publish Point" tool) adds the door there, or
  // removes the door clicked on, and predicts again.
  bool doors_from_clicks = true;
  double click_door_width = 0.9;     // metres: a clicked door's width when the map shows no jambs and no door is known
  double click_search_radius = 1.0;  // metres around the click where the door's wall is looked for
  // A tf frame at the centre of the latest map's known cells (static, child of the map's frame): the shipped rviz
  // views look at it, so they centre on any map; "" = none.
  std::string view_frame = "map_view";
  // Room segmentation (segment_rooms service, room_segmentation markers).
  std::string segmentation_method = "default";  // method of segment_rooms requests that name none
  std::string segmentation_params_file;  // flat `name: number` overrides of the segmentation; "" = none
  bool segment_on_prediction = true;     // after each prediction, segment its map with the predicted rooms
  // Requests beyond these are refused (bounded answer times and memory).
  int max_doors = common::kMaxDoors;
  int max_map_cells = static_cast<int>(common::kMaxMapCells);  // 5000 x 5000 cells: 250 m x 250 m at 0.05 m
};

// The node's parameters, as docs/ros_api.md lists them.
const common::OptionTable<RoomPredictorOptions>& roomPredictorNodeOptionTable();
std::vector<common::OptionDescription> roomPredictorParameters();
// Reads the options from the private node handle. Throws InputError naming the first bad parameter, or for
// ~predict_on_map without a way to get doors (a doors file or clicks).
RoomPredictorOptions readRoomPredictorOptions(const ros::NodeHandle& private_nh);

// Serves `predict_rooms` (PredictRooms) over the latest map of `map` or the request's own map, and publishes
// each prediction, latched, as `predicted_map` (the completed map) and `predicted_rooms` (rviz markers). Serves
// `segment_rooms` (SegmentRooms) and publishes each segmentation, latched, as `room_segmentation` (rviz markers);
// with ~segment_on_prediction every prediction is followed by a segmentation with its predicted rooms. The
// method and the parameters of requests that name none can be changed live (dynamic_reconfigure,
// cfg/RoomPredictor.cfg): the node then predicts its own doors again.
class RoomPredictorNode {
 public:
  // Checks the method, loads the doors and parameters files and slices ~octomap_file (throws InputError naming
  // a bad one); does not wait for anything.
  RoomPredictorNode(ros::NodeHandle nh, const RoomPredictorOptions& options);

  // The service: never throws; every failure is success = false with a message.
  bool predictRooms(PredictRooms::Request& request, PredictRooms::Response& response);
  // The segmentation service: never throws; every failure is success = false with a message.
  bool segmentRooms(SegmentRooms::Request& request, SegmentRooms::Response& response);
  // save_doors: writes the node's doors; never throws.
  bool saveDoors(SaveDoors::Request& request, SaveDoors::Response& response);

 private:
  void receiveMap(const nav_msgs::OccupancyGrid::ConstPtr& map);
  // A click on clicked_point: adds or removes a door (see RoomPredictorOptions::doors_from_clicks).
  void receiveClick(const geometry_msgs::PointStamped::ConstPtr& click);
  // Moves ~view_frame to the centre of the map's known cells when it moved by more than a few metres.
  void publishViewFrame(const nav_msgs::OccupancyGrid& map);
  // Predicts the node's doors with its method on the latest map and logs the outcome (`why`: what triggered it).
  void predictAndLog(const std::string& why);
  // Predicts and publishes; throws InputError for an unusable request.
  void predict(const PredictRooms::Request& request, PredictRooms::Response* response);
  // The request's map, or the latest one; throws InputError when there is none or it has more cells than
  // ~max_map_cells.
  const nav_msgs::OccupancyGrid& requestMap(const nav_msgs::OccupancyGrid& request_map) const;
  // The frame of the outputs on `map`: its header's, else ~frame_id.
  std::string outputFrame(const nav_msgs::OccupancyGrid& map) const;
  // The request's doors, else the node's; throws InputError when neither has any and `required`.
  common::DoorsFile requestDoors(const std::vector<ClosedDoor>& request_doors, const std::string& frame,
                                 bool required) const;
  // Segments and publishes room_segmentation; throws InputError for an unusable request.
  segmentation::SegmentedFloor segment(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                                       const cv::Mat1w& predicted_rooms, const std::string& method,
                                       const std::string& frame);
  // dynamic_reconfigure: takes the method and the parameters (those ~params_file sets, and those that differ from
  // the .cfg's defaults, i.e. config/*.yaml's) and predicts the node's doors again. A method or value that the
  // prediction refuses puts `config` back to the settings before, with a warning naming it.
  void reconfigure(RoomPredictorConfig& config, uint32_t level);

  RoomPredictorOptions options_;
  std::optional<common::DoorsFile> default_doors_;  // the doors of requests without doors: file, then clicks
  std::map<std::string, double> file_parameters_;  // ~params_file's
  // The method and parameter overrides of requests that name none: ~method and ~params_file, then reconfigured.
  std::string method_;
  std::map<std::string, double> parameters_;
  RoomPredictorConfig applied_config_;  // the configuration method_ and parameters_ come from
  // The server's mutex is the node's, so that its configuration can be set at start (updateConfig) under it.
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<RoomPredictorConfig>> reconfigure_server_;
  nav_msgs::OccupancyGrid::ConstPtr latest_map_;
  std::string map_topic_;
  ros::Subscriber map_subscriber_;
  ros::Publisher predicted_map_publisher_;
  ros::Publisher markers_publisher_;
  ros::Publisher segmentation_publisher_;
  ros::ServiceServer segmentation_service_;
  std::map<std::string, double> segmentation_parameters_;  // ~segmentation_params_file's
  // The latest prediction's rooms (labels in its map's grid) and that map's geometry, for with_predicted_rooms.
  cv::Mat1w latest_prediction_labels_;
  common::Point2 latest_prediction_origin_ = common::Point2::Zero();
  double latest_prediction_resolution_ = 0.0;
  ros::ServiceServer service_;
  ros::ServiceServer save_doors_service_;
  ros::Subscriber click_subscriber_;
  tf2_ros::StaticTransformBroadcaster view_broadcaster_;
  std::optional<common::Point2> view_centre_;  // where ~view_frame was last published
  ros::WallTimer octomap_timer_;
};

}  // namespace hidden_rooms
