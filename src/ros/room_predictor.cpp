#include "hidden_rooms/ros/room_predictor.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <boost/make_shared.hpp>
#include <visualization_msgs/MarkerArray.h>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/input_limits.h"
#include "hidden_rooms/map3d/octomap_io.h"
#include "hidden_rooms/prediction/door_at_point.h"
#include "hidden_rooms/prediction/layout.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/ros/markers.h"
#include "hidden_rooms/ros/parameters.h"
#include "hidden_rooms/segmentation/room_graph.h"

namespace hidden_rooms {

const common::OptionTable<RoomPredictorOptions>& roomPredictorNodeOptionTable() {
  using O = RoomPredictorOptions;
  static const common::OptionTable<O> table{
      {"method", &O::method, "method of requests that name none, and of ~predict_on_map"},
      {"closed_doors_file", &O::closed_doors_file, "doors.yaml: the doors of requests that give none"},
      {"params_file", &O::params_file, "flat `name: number` overrides applied to every request"},
      {"predict_on_map", &O::predict_on_map,
       "predict the node's doors on every new map (needs ~closed_doors_file or ~doors_from_clicks)"},
      {"publish_debug", &O::publish_debug, "add the layout analysis namespaces to predicted_rooms"},
      {"frame_id", &O::frame_id, "frame of the outputs when the map's header.frame_id is empty"},
      {"octomap_file", &O::octomap_file, "a 3D map as map source, sliced at start"},
      {"octomap_z_min", &O::octomap_z_min, "metres: bottom of the height band of ~octomap_file"},
      {"octomap_z_max", &O::octomap_z_max, "metres: top of the height band of ~octomap_file"},
      {"octomap_out", &O::octomap_out, "after each prediction, the completed map extruded into 3D and written here"},
      {"octomap_height", &O::octomap_height, "metres: height of the extruded walls and free space", common::above(0)},
      {"max_doors", &O::max_doors, "requests with more doors are refused", common::between(1, common::kMaxDoors)},
      {"max_map_cells", &O::max_map_cells, "maps with more cells (width x height) are refused",
       common::between(1, common::kMaxMapCells)},
      {"doors_from_clicks", &O::doors_from_clicks,
       "a point on clicked_point adds the door there, or removes the door clicked on, and predicts again"},
      {"click_door_width", &O::click_door_width,
       "metres: a clicked door's width when the map shows no jambs and the node has no doors", common::above(0)},
      {"click_search_radius", &O::click_search_radius, "metres around a click where the door's wall is looked for",
       common::above(0)},
      {"view_frame", &O::view_frame, "tf frame at the centre of the map's known cells, for rviz's view"},
      {"segmentation_method", &O::segmentation_method, "segmentation method of segment_rooms requests that name none"},
      {"segmentation_params_file", &O::segmentation_params_file,
       "flat `name: number` overrides of the segmentation (config/segmentation.yaml)"},
      {"segment_on_prediction", &O::segment_on_prediction,
       "after each prediction, segment its map with the predicted rooms and publish room_segmentation"},
  };
  return table;
}

std::vector<common::OptionDescription> roomPredictorParameters() {
  return common::describeOptions(roomPredictorNodeOptionTable());
}

RoomPredictorOptions readRoomPredictorOptions(const ros::NodeHandle& private_nh) {
  RoomPredictorOptions options;
  readParameters(private_nh, roomPredictorNodeOptionTable(), &options);
  if (options.predict_on_map && options.closed_doors_file.empty() && !options.doors_from_clicks)
    throw common::InputError(private_nh.getNamespace(), "~predict_on_map needs ~closed_doors_file or ~doors_from_clicks");
  return options;
}

RoomPredictorNode::RoomPredictorNode(ros::NodeHandle nh, const RoomPredictorOptions& options) : options_(options) {
  // A bad method, doors file or parameters file stops the node here, not at the first request.
  const std::unique_ptr<prediction::RoomPredictor> method = prediction::makeRoomPredictor(options_.method);
  if (!options_.closed_doors_file.empty()) default_doors_ = common::loadDoors(options_.closed_doors_file);
  if (!options_.params_file.empty()) {
    file_parameters_ = common::loadParameterFile(options_.params_file);
    prediction::resolveParameters(*method, file_parameters_);  // throws for a name no method reads
  }
  const std::unique_ptr<segmentation::RoomSegmenter> segmenter =
      segmentation::makeRoomSegmenter(options_.segmentation_method);
  if (!options_.segmentation_params_file.empty()) {
    segmentation_parameters_ = common::loadParameterFile(options_.segmentation_params_file);
    segmentation::resolveSegmenterParameters(*segmenter, segmentation_parameters_);  // throws for unknown names
  }
  method_ = options_.method;
  parameters_ = file_parameters_;
  // The live configuration starts from the node's settings (not from the .cfg's defaults).
  RoomPredictorConfig initial = RoomPredictorConfig::__getDefault__();
  initial.method = options_.method;
  dynamic_reconfigure::Config initial_message;
  initial.__toMessage__(initial_message);
  for (dynamic_reconfigure::DoubleParameter& parameter : initial_message.doubles)
    if (file_parameters_.count(parameter.name)) parameter.value = file_parameters_.at(parameter.name);
  initial.__fromMessage__(initial_message);
  applied_config_ = initial;
  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<RoomPredictorConfig>>(reconfigure_mutex_, ros::NodeHandle("~"));
  {
    boost::recursive_mutex::scoped_lock lock(reconfigure_mutex_);
    reconfigure_server_->updateConfig(initial);
  }
  reconfigure_server_->setCallback(
      [this](RoomPredictorConfig& config, uint32_t level) { reconfigure(config, level); });
  map_topic_ = nh.resolveName("map");
  predicted_map_publisher_ = nh.advertise<nav_msgs::OccupancyGrid>("predicted_map", 1, true);
  markers_publisher_ = nh.advertise<visualization_msgs::MarkerArray>("predicted_rooms", 1, true);
  service_ = nh.advertiseService("predict_rooms", &RoomPredictorNode::predictRooms, this);
  segmentation_publisher_ = nh.advertise<visualization_msgs::MarkerArray>("room_segmentation", 1, true);
  segmentation_service_ = nh.advertiseService("segment_rooms", &RoomPredictorNode::segmentRooms, this);
  map_subscriber_ = nh.subscribe("map", 1, &RoomPredictorNode::receiveMap, this);
  save_doors_service_ = nh.advertiseService("save_doors", &RoomPredictorNode::saveDoors, this);
  if (options_.doors_from_clicks)
    click_subscriber_ = nh.subscribe("clicked_point", 10, &RoomPredictorNode::receiveClick, this);
  if (!options_.octomap_out.empty()) {
    const std::filesystem::path folder = std::filesystem::path(options_.octomap_out).parent_path();
    std::error_code error;
    if (!folder.empty()) std::filesystem::create_directories(folder, error);
    if (error) throw common::InputError(options_.octomap_out, "its folder cannot be created: " + error.message());
  }
  if (!options_.octomap_file.empty()) {
    map3d::SliceOptions slice;
    slice.z_min = options_.octomap_z_min;
    slice.z_max = options_.octomap_z_max;
    const common::OccupancyGrid sliced = map3d::sliceOctomap(options_.octomap_file, slice);
    auto message = boost::make_shared<nav_msgs::OccupancyGrid>(toRos(sliced, options_.frame_id, ros::Time(0)));
    // Handled like a map from the topic once the node spins (predict_on_map predicts on it then).
    octomap_timer_ = nh.createWallTimer(
        ros::WallDuration(0.01), [this, message](const ros::WallTimerEvent&) { receiveMap(message); }, true);
  }
}

void RoomPredictorNode::receiveMap(const nav_msgs::OccupancyGrid::ConstPtr& map) {
  latest_map_ = map;
  if (!options_.view_frame.empty()) publishViewFrame(*map);
  if (options_.predict_on_map && default_doors_ && !default_doors_->doors.empty()) predictAndLog("new map");
}

void RoomPredictorNode::publishViewFrame(const nav_msgs::OccupancyGrid& map) {
  constexpr double kMoveDistance = 2.0;  // metres: a growing SLAM map moves the view only now and then
  const auto& info = map.info;
  int min_col = static_cast<int>(info.width), max_col = -1, min_row = static_cast<int>(info.height), max_row = -1;
  for (int row = 0; row < static_cast<int>(info.height); ++row)
    for (int col = 0; col < static_cast<int>(info.width); ++col)
      if (map.data[static_cast<size_t>(row) * info.width + col] >= 0) {
        min_col = std::min(min_col, col), max_col = std::max(max_col, col);
        min_row = std::min(min_row, row), max_row = std::max(max_row, row);
      }
  if (max_col < 0) return;
  // The map message's rows run up from its origin; a rotated origin is refused by predictions, ignored here.
  const common::Point2 centre(info.origin.position.x + 0.5 * (min_col + max_col + 1) * info.resolution,
                              info.origin.position.y + 0.5 * (min_row + max_row + 1) * info.resolution);
  if (view_centre_ && (centre - *view_centre_).norm() < kMoveDistance) return;
  view_centre_ = centre;
  geometry_msgs::TransformStamped transform;
  transform.header.stamp = ros::Time::now();
  transform.header.frame_id = map.header.frame_id.empty() ? options_.frame_id : map.header.frame_id;
  transform.child_frame_id = options_.view_frame;
  transform.transform.translation.x = centre.x();
  transform.transform.translation.y = centre.y();
  transform.transform.rotation.w = 1.0;
  view_broadcaster_.sendTransform(transform);
}

void RoomPredictorNode::predictAndLog(const std::string& why) {
  PredictRooms::Request request;  // the node's doors and method over the latest map
  PredictRooms::Response response;
  predictRooms(request, response);
  if (response.success)
    ROS_INFO("room_predictor: %s: %s", why.c_str(), response.message.c_str());
  else
    ROS_WARN("room_predictor: %s: %s", why.c_str(), response.message.c_str());
}

void RoomPredictorNode::reconfigure(RoomPredictorConfig& config, uint32_t) {
  dynamic_reconfigure::Config values, defaults;
  config.__toMessage__(values);
  RoomPredictorConfig::__getDefault__().__toMessage__(defaults);
  std::map<std::string, double> parameters;
  for (size_t k = 0; k < values.doubles.size(); ++k) {
    const dynamic_reconfigure::DoubleParameter& parameter = values.doubles[k];
    if (file_parameters_.count(parameter.name) || parameter.value != defaults.doubles[k].value)
      parameters[parameter.name] = parameter.value;
  }
  const std::string previous_method = method_;
  const std::map<std::string, double> previous_parameters = parameters_;
  method_ = config.method;
  parameters_ = parameters;
  std::string refused;
  try {
    prediction::resolveParameters(*prediction::makeRoomPredictor(method_), parameters_);
    if (latest_map_ != nullptr && default_doors_ && !default_doors_->doors.empty()) {
      PredictRooms::Response response;
      predict(PredictRooms::Request(), &response);
      ROS_INFO("room_predictor: reconfigured: %s", response.message.c_str());
    }
  } catch (const common::InputError& error) {
    // The method or a parameter value refused; other problems (the map, the doors) are not the settings'.
    if (error.source() == "method" || error.source().rfind("parameter", 0) == 0) refused = error.what();
    else ROS_WARN("room_predictor: reconfigured, but the prediction failed: %s", error.what());
  } catch (const std::exception& error) {  // a bug, reported as predictRooms reports it, not a crash of the node
    ROS_WARN("room_predictor: reconfigured, but the prediction failed: %s", error.what());
  }
  if (!refused.empty()) {
    ROS_WARN("room_predictor: settings not applied: %s", refused.c_str());
    method_ = previous_method;
    parameters_ = previous_parameters;
    config = applied_config_;
    return;
  }
  applied_config_ = config;
}

void RoomPredictorNode::receiveClick(const geometry_msgs::PointStamped::ConstPtr& click) {
  if (latest_map_ == nullptr) {
    ROS_WARN("room_predictor: click ignored: no map received on %s yet", map_topic_.c_str());
    return;
  }
  const std::string frame = latest_map_->header.frame_id.empty() ? options_.frame_id : latest_map_->header.frame_id;
  if (click->header.frame_id != frame) {
    ROS_WARN("room_predictor: click ignored: it is in frame '%s', the map in '%s' (set rviz's fixed frame to '%s')",
             click->header.frame_id.c_str(), frame.c_str(), frame.c_str());
    return;
  }
  if (!default_doors_) {
    default_doors_ = common::DoorsFile();
    default_doors_->frame = frame;
  }
  std::vector<common::MapDoor>& doors = default_doors_->doors;
  const common::Point2 point(click->point.x, click->point.y);
  // A click on a door removes it: within half its width of its centre (and at least half a metre).
  const auto clicked = std::find_if(doors.begin(), doors.end(), [&](const common::MapDoor& door) {
    return (door.position - point).norm() <= std::max(0.5, 0.5 * door.width);
  });
  if (clicked != doors.end()) {
    ROS_INFO("room_predictor: door %d removed; %zu doors left", clicked->id, doors.size() - 1);
    doors.erase(clicked);
    if (doors.empty()) {
      visualization_msgs::MarkerArray cleared;
      cleared.markers.resize(1);
      cleared.markers[0].action = visualization_msgs::Marker::DELETEALL;
      markers_publisher_.publish(cleared);
      return;
    }
  } else {
    if (static_cast<int>(doors.size()) >= options_.max_doors) {
      ROS_WARN("room_predictor: click ignored: the node has ~max_doors (%d) doors", options_.max_doors);
      return;
    }
    prediction::DoorAtPointOptions door_options;
    door_options.search_radius = options_.click_search_radius;
    door_options.default_width = options_.click_door_width;
    if (!doors.empty()) {  // as wide as the doors already known (their median)
      std::vector<double> widths;
      for (const common::MapDoor& door : doors) widths.push_back(door.width);
      std::nth_element(widths.begin(), widths.begin() + widths.size() / 2, widths.end());
      door_options.default_width = widths[widths.size() / 2];
    }
    std::string problem;
    const common::OccupancyGrid map = common::trinary(fromRos(*latest_map_));
    std::optional<common::MapDoor> door = prediction::doorAtPoint(map, point, door_options, &problem);
    if (!door) {
      ROS_WARN("room_predictor: no door added at (%.2f, %.2f): %s", point.x(), point.y(), problem.c_str());
      return;
    }
    door->id = 1;
    for (const common::MapDoor& other : doors) door->id = std::max(door->id, other.id + 1);
    ROS_INFO("room_predictor: door %d added at (%.2f, %.2f), %.2f m wide, along %s; %zu doors", door->id,
             door->position.x(), door->position.y(), door->width,
             door->orientation == common::DoorOrientation::kAlongX ? "x" : "y", doors.size() + 1);
    doors.push_back(*door);
  }
  predictAndLog("doors clicked");
}

bool RoomPredictorNode::saveDoors(SaveDoors::Request& request, SaveDoors::Response& response) {
  response = SaveDoors::Response();
  try {
    if (!default_doors_ || default_doors_->doors.empty())
      throw common::InputError("save_doors", "the node has no doors (no ~closed_doors_file, no door clicked)");
    if (request.path.empty()) throw common::InputError("save_doors", "the request names no file");
    common::saveDoors(*default_doors_, request.path);  // writes atomically, creating the file's folder
    response.success = true;
    response.message = "wrote " + std::to_string(default_doors_->doors.size()) + " doors to " + request.path;
  } catch (const std::exception& error) {
    response.success = false;
    response.message = error.what();
  }
  return true;
}

bool RoomPredictorNode::predictRooms(PredictRooms::Request& request, PredictRooms::Response& response) {
  response = PredictRooms::Response();
  try {
    predict(request, &response);
  } catch (const std::exception& error) {  // InputError: a bad request; anything else: a bug, reported too
    response = PredictRooms::Response();
    response.success = false;
    response.message = error.what();
  }
  return true;
}

const nav_msgs::OccupancyGrid& RoomPredictorNode::requestMap(const nav_msgs::OccupancyGrid& request_map) const {
  const bool own_map = request_map.info.width > 0 && request_map.info.height > 0;
  if (!own_map && latest_map_ == nullptr)
    throw common::InputError("map", "the request has no map and none was received on " + map_topic_ + " yet");
  const nav_msgs::OccupancyGrid& map_message = own_map ? request_map : *latest_map_;
  const double cells = static_cast<double>(map_message.info.width) * map_message.info.height;
  if (cells > options_.max_map_cells)
    throw common::InputError("map",
                             std::to_string(map_message.info.width) + " x " + std::to_string(map_message.info.height) +
                                 " cells is more than ~max_map_cells (" + std::to_string(options_.max_map_cells) + ")");
  return map_message;
}

std::string RoomPredictorNode::outputFrame(const nav_msgs::OccupancyGrid& map) const {
  return map.header.frame_id.empty() ? options_.frame_id : map.header.frame_id;
}

common::DoorsFile RoomPredictorNode::requestDoors(const std::vector<ClosedDoor>& request_doors,
                                                  const std::string& frame, bool required) const {
  if (request_doors.size() > static_cast<size_t>(options_.max_doors))
    throw common::InputError("doors", std::to_string(request_doors.size()) + " doors is more than ~max_doors (" +
                                          std::to_string(options_.max_doors) + ")");
  if (!request_doors.empty()) return fromRos(request_doors, frame);
  if (default_doors_) {
    if (default_doors_->frame != frame)
      throw common::InputError("~closed_doors_file", "its doors are in frame '" + default_doors_->frame +
                                                         "', the map in '" + frame + "'");
    return *default_doors_;
  }
  if (required)
    throw common::InputError("doors", "the request has no doors and the node has none (no ~closed_doors_file, "
                                      "no door clicked on clicked_point)");
  common::DoorsFile none;
  none.frame = frame;
  return none;
}

void RoomPredictorNode::predict(const PredictRooms::Request& request, PredictRooms::Response* response) {
  const nav_msgs::OccupancyGrid& map_message = requestMap(request.map);
  const std::string frame = outputFrame(map_message);
  prediction::PredictionRequest core;
  core.map = common::trinary(fromRos(map_message));  // as map_saver would save it: results equal offline ones
  prediction::checkUsableMap(core.map);
  core.doors = requestDoors(request.doors, frame, true);
  if (core.doors.doors.empty()) throw common::InputError("doors", "no closed doors to predict");
  common::checkDoorsInsideMap(core.map, core.doors);
  core.parameters = parameters_;
  for (const auto& [name, value] : fromRos(request.parameters)) core.parameters[name] = value;
  const std::string method = request.method.empty() ? method_ : request.method;
  const std::unique_ptr<prediction::RoomPredictor> predictor = prediction::makeRoomPredictor(method);

  const prediction::PredictionResult result = predictor->predict(core);

  const ros::Time stamp = ros::Time::now();
  const common::OccupancyGrid completed = prediction::insertRooms(core.map, core.doors, result.rooms);
  const cv::Mat1w labels = prediction::roomLabels(core.map, core.doors, result.rooms);
  std::string not_placed;
  response->rooms.reserve(result.rooms.size());
  int placed = 0;
  for (size_t k = 0; k < result.rooms.size(); ++k) {
    const prediction::RoomPrediction& room = result.rooms[k];
    response->rooms.push_back(toRos(room, static_cast<int>(k) + 1, core.map, frame, stamp));
    if (room.placed)
      ++placed;
    else
      not_placed += "; door " + std::to_string(room.door_id) + " not placed: " + room.problem;
  }
  response->success = true;
  response->method = method;
  response->computation_time = result.seconds;
  response->completed_map = toRos(completed, frame, stamp);
  response->completed_map.info.map_load_time = map_message.info.map_load_time;
  char summary[160];
  std::snprintf(summary, sizeof(summary), "predicted %d of %d rooms in %.3f s by %s", placed,
                static_cast<int>(result.rooms.size()), result.seconds, method.c_str());
  response->message = summary + not_placed;

  predicted_map_publisher_.publish(response->completed_map);
  visualization_msgs::MarkerArray markers = toMarkers(core.map, core.doors, result.rooms, labels, frame, stamp);
  if (options_.publish_debug) {
    prediction::LayoutOptions layout_options;  // the layout the method ran on, with its own defaults
    prediction::applyLayoutParameters(prediction::resolveParameters(*predictor, core.parameters), &layout_options);
    const prediction::Layout layout = prediction::analyzeLayout(core.map, core.doors.doors, layout_options);
    const visualization_msgs::MarkerArray debug = toDebugMarkers(core.map, layout, frame, stamp);
    markers.markers.insert(markers.markers.end(), debug.markers.begin(), debug.markers.end());
  }
  markers_publisher_.publish(markers);
  latest_prediction_labels_ = labels;
  latest_prediction_origin_ = core.map.origin;
  latest_prediction_resolution_ = core.map.resolution;
  if (options_.segment_on_prediction) {
    try {
      segment(core.map, core.doors, labels, options_.segmentation_method, frame);
    } catch (const common::InputError& error) {
      ROS_WARN("room_predictor: the prediction's map was not segmented: %s", error.what());
    }
  }

  if (!options_.octomap_out.empty()) {
    map3d::ExtrusionOptions extrusion;
    extrusion.height = options_.octomap_height;
    try {
      map3d::exportOctomap(completed, labels, extrusion, options_.octomap_out);
    } catch (const common::InputError& error) {
      response->success = false;
      response->message += "; but the 3D map was not written: " + std::string(error.what());
    }
  }
}

bool RoomPredictorNode::segmentRooms(SegmentRooms::Request& request, SegmentRooms::Response& response) {
  response = SegmentRooms::Response();
  try {
    const nav_msgs::OccupancyGrid& map_message = requestMap(request.map);
    const std::string frame = outputFrame(map_message);
    const common::OccupancyGrid map = common::trinary(fromRos(map_message));
    const common::DoorsFile doors = requestDoors(request.doors, frame, false);
    cv::Mat1w predicted;
    if (request.with_predicted_rooms) {
      if (latest_prediction_labels_.empty())
        throw common::InputError("with_predicted_rooms", "the node has predicted no rooms yet");
      if (latest_prediction_labels_.size() != map.cells.size() || latest_prediction_origin_ != map.origin ||
          latest_prediction_resolution_ != map.resolution)
        throw common::InputError("with_predicted_rooms", "the latest prediction was made on another map");
      predicted = latest_prediction_labels_;
    }
    const std::string method = request.method.empty() ? options_.segmentation_method : request.method;
    const auto start = std::chrono::steady_clock::now();
    const segmentation::SegmentedFloor floor = segment(map, doors, predicted, method, frame);
    response.computation_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const ros::Time stamp = ros::Time::now();
    response.labels = labelsToRos(floor.labels, frame, stamp);
    int corridors = 0, predicted_rooms = 0;
    for (const segmentation::Room& room : floor.rooms) {
      response.rooms.push_back(toRos(room));
      corridors += room.kind == segmentation::RoomKind::kCorridor;
      predicted_rooms += room.predicted;
    }
    for (const segmentation::Passage& passage : floor.passages) response.passages.push_back(toRos(passage));
    char summary[160];
    std::snprintf(summary, sizeof(summary), "%zu rooms (%d corridors, %d predicted), %zu passages in %.3f s by %s",
                  floor.rooms.size(), corridors, predicted_rooms, floor.passages.size(), response.computation_time,
                  method.c_str());
    response.message = summary;
    response.success = true;
  } catch (const std::exception& error) {  // InputError: a bad request; anything else: a bug, reported too
    response = SegmentRooms::Response();
    response.success = false;
    response.message = error.what();
  }
  return true;
}

segmentation::SegmentedFloor RoomPredictorNode::segment(const common::OccupancyGrid& map,
                                                        const common::DoorsFile& doors,
                                                        const cv::Mat1w& predicted_rooms, const std::string& method,
                                                        const std::string& frame) {
  segmentation::FloorSegmentationOptions floor_options;
  floor_options.method = method;
  floor_options.parameters = segmentation_parameters_;
  const segmentation::SegmentedFloor floor = segmentation::segmentFloor(map, doors, predicted_rooms, floor_options);
  segmentation_publisher_.publish(toMarkers(floor, frame, ros::Time::now()));
  return floor;
}

}  // namespace hidden_rooms
