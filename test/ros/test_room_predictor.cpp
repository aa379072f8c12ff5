// rostest: room_predictor on a closed-door benchmark case answers predict_rooms with exactly the rooms of
// predict_rooms_offline, publishes its overlays latched, answers bad requests with success = false and a clear
// message, and keeps serving; predict_rooms_client saves the same files as the offline command; its method and
// parameters change live through dynamic_reconfigure.
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <geometry_msgs/PointStamped.h>
#include <hidden_rooms/PredictRooms.h>
#include <hidden_rooms/SaveDoors.h>
#include <hidden_rooms/SegmentRooms.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/map3d/octomap_io.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/ros/conversions.h"
#include "test_util.h"

namespace {

using hidden_rooms::PredictRooms;
namespace testing_util = hidden_rooms::testing;

std::string caseDir() {
  std::string dir;
  ros::NodeHandle("~").getParam("case", dir);
  return dir;
}

// The node has the map once it has published its first prediction (~predict_on_map is on in the launch file).
bool nodeHasTheMap() {
  ros::NodeHandle nh;
  return ros::topic::waitForMessage<nav_msgs::OccupancyGrid>("predicted_map", nh, ros::Duration(30.0)) != nullptr;
}

#define REQUIRE_CASE()                                                                                       \
  do {                                                                                                       \
    HIDDEN_ROOMS_REQUIRE_SHARED_DATA();                                                                      \
    ASSERT_TRUE(std::filesystem::exists(caseDir() + "/map.yaml")) << "benchmark case missing: " << caseDir(); \
    ASSERT_TRUE(nodeHasTheMap()) << "room_predictor published no prediction within 30 s";                    \
  } while (0)

bool call(PredictRooms* service, const std::string& name = "predict_rooms") {
  if (!ros::service::waitForService(name, ros::Duration(30.0))) return false;
  return ros::service::call(name, *service);
}

std::string readFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

// predict_rooms_offline on the case into a fresh folder.
std::string runOffline(const std::string& method) {
  const std::string out = testing_util::makeTempDir("room_predictor_offline_" + method);
  const testing_util::CommandResult result =
      testing_util::runCommand(std::string(PREDICT_ROOMS_OFFLINE_BIN) + " --map " + caseDir() + "/map.yaml --doors " +
                               caseDir() + "/doors.yaml --method " + method + " --out " + out);
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return out;
}

TEST(RoomPredictor, ServiceGivesTheOfflineCommandsRooms) {
  REQUIRE_CASE();
  const hidden_rooms::common::OccupancyGrid map = hidden_rooms::common::loadMap(caseDir() + "/map.yaml");
  const hidden_rooms::common::DoorsFile doors = hidden_rooms::common::loadDoors(caseDir() + "/doors.yaml");
  for (const std::string method : {"default", "thesis"}) {
    SCOPED_TRACE(method);
    PredictRooms service;
    service.request.doors = hidden_rooms::toRos(doors);
    service.request.method = method;  // map empty: the latest map on `map`, published by map_publisher
    ASSERT_TRUE(call(&service));
    ASSERT_TRUE(service.response.success) << service.response.message;
    EXPECT_EQ(service.response.method, method);
    ASSERT_EQ(service.response.rooms.size(), doors.doors.size());
    EXPECT_GE(service.response.computation_time, 0.0);
    EXPECT_EQ(service.response.completed_map.header.frame_id, "map");

    const std::string offline = runOffline(method);
    std::vector<hidden_rooms::prediction::RoomPrediction> rooms;
    for (const hidden_rooms::PredictedRoom& room : service.response.rooms)
      rooms.push_back(hidden_rooms::fromRos(room, map));
    const cv::Mat1w labels = hidden_rooms::prediction::roomLabels(map, doors, rooms);
    const cv::Mat expected = cv::imread(offline + "/rooms.png", cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(expected.empty());
    cv::Mat1w expected_labels;
    expected.convertTo(expected_labels, CV_16U);
    EXPECT_EQ(cv::countNonZero(labels != expected_labels), 0) << "rooms differ from predict_rooms_offline's";
    EXPECT_GT(cv::countNonZero(labels), 1000);

    const hidden_rooms::common::OccupancyGrid completed = hidden_rooms::fromRos(service.response.completed_map);
    const hidden_rooms::common::OccupancyGrid expected_completed = hidden_rooms::common::loadMap(offline + "/map.yaml");
    ASSERT_EQ(completed.cells.size(), expected_completed.cells.size());
    EXPECT_EQ(completed.resolution, expected_completed.resolution);
    EXPECT_EQ(completed.origin, expected_completed.origin);
    EXPECT_EQ(cv::countNonZero(completed.cells != expected_completed.cells), 0);

    const YAML::Node yaml = YAML::LoadFile(offline + "/rooms.yaml");
    for (size_t k = 0; k < rooms.size(); ++k) {
      const hidden_rooms::PredictedRoom& room = service.response.rooms[k];
      EXPECT_EQ(room.door_id, yaml["rooms"][k]["door_id"].as<int>());
      EXPECT_EQ(room.label, k + 1);
      EXPECT_EQ(room.status == hidden_rooms::PredictedRoom::PREDICTED, yaml["rooms"][k]["placed"].as<bool>());
      EXPECT_NEAR(room.area, yaml["rooms"][k]["area"].as<double>(), 1e-9);
      EXPECT_EQ(room.polygon.size(), yaml["rooms"][k]["polygon"].size());
      EXPECT_EQ(room.term_names.size(), room.term_values.size());
      if (room.status == hidden_rooms::PredictedRoom::PREDICTED) {
        EXPECT_EQ(cv::countNonZero(rooms[k].mask), static_cast<int>(std::lround(room.area / (0.05 * 0.05))));
        EXPECT_TRUE(room.problem.empty());
      }
    }
  }
}

TEST(RoomPredictor, ClientSavesWhatTheOfflineCommandSaves) {
  REQUIRE_CASE();
  const std::string offline = runOffline("default");
  const std::string out = testing_util::makeTempDir("room_predictor_client");
  const testing_util::CommandResult result = testing_util::runCommand(
      std::string(PREDICT_ROOMS_CLIENT_BIN) + " --doors " + caseDir() + "/doors.yaml --method default --out " + out);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("default: 15 doors in"), std::string::npos) << result.output;
  for (const std::string file : {"rooms.png", "map.yaml", "map.pgm", "overlay.png"})
    EXPECT_EQ(readFile(out + "/" + file), readFile(offline + "/" + file)) << file << " differs";
  const YAML::Node client_yaml = YAML::LoadFile(out + "/rooms.yaml");
  const YAML::Node offline_yaml = YAML::LoadFile(offline + "/rooms.yaml");
  ASSERT_EQ(client_yaml["rooms"].size(), offline_yaml["rooms"].size());
  for (size_t k = 0; k < client_yaml["rooms"].size(); ++k)
    EXPECT_EQ(YAML::Dump(client_yaml["rooms"][k]), YAML::Dump(offline_yaml["rooms"][k]));

  // Bad input: nothing written, exit code 2, the node's message.
  const std::string bad_out = testing_util::makeTempDir("room_predictor_client_bad") + "/out";
  const testing_util::CommandResult bad = testing_util::runCommand(std::string(PREDICT_ROOMS_CLIENT_BIN) + " --doors " +
                                                                   caseDir() + "/doors.yaml --method nosuch --out " +
                                                                   bad_out);
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("nosuch"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(bad_out));
}

TEST(RoomPredictor, EmptyRequestUsesTheDoorsFileAndTheNodesMethod) {
  REQUIRE_CASE();
  PredictRooms service;
  ASSERT_TRUE(call(&service));
  ASSERT_TRUE(service.response.success) << service.response.message;
  EXPECT_EQ(service.response.method, "default");
  EXPECT_EQ(service.response.rooms.size(), hidden_rooms::common::loadDoors(caseDir() + "/doors.yaml").doors.size());
}

// dynamic_reconfigure's set_parameters of the node in namespace `reconfigure`: one string and/or one double.
dynamic_reconfigure::Config reconfigure(const std::string& method, const std::string& parameter = "",
                                        double value = 0.0) {
  dynamic_reconfigure::Reconfigure service;
  if (!method.empty()) {
    dynamic_reconfigure::StrParameter text;
    text.name = "method";
    text.value = method;
    service.request.config.strs.push_back(text);
  }
  if (!parameter.empty()) {
    dynamic_reconfigure::DoubleParameter number;
    number.name = parameter;
    number.value = value;
    service.request.config.doubles.push_back(number);
  }
  const std::string name = "reconfigure/room_predictor/set_parameters";
  EXPECT_TRUE(ros::service::waitForService(name, ros::Duration(30.0)) && ros::service::call(name, service)) << name;
  return service.response.config;
}

std::string stringOf(const dynamic_reconfigure::Config& config, const std::string& name) {
  for (const auto& entry : config.strs)
    if (entry.name == name) return entry.value;
  return "<missing>";
}

double doubleOf(const dynamic_reconfigure::Config& config, const std::string& name) {
  for (const auto& entry : config.doubles)
    if (entry.name == name) return entry.value;
  return std::numeric_limits<double>::quiet_NaN();
}

double totalArea(const PredictRooms::Response& response) {
  double area = 0.0;
  for (const auto& room : response.rooms) area += room.area;
  return area;
}

TEST(RoomPredictor, MethodAndParametersChangeLiveAndARefusedValueIsPutBack) {
  REQUIRE_CASE();
  ros::NodeHandle nh;
  const auto first = ros::topic::waitForMessage<nav_msgs::OccupancyGrid>("reconfigure/predicted_map", nh,
                                                                          ros::Duration(30.0));
  ASSERT_TRUE(first != nullptr) << "the reconfigurable node published no prediction";

  // The method: requests that name none get it, and the node predicts its doors again with it.
  dynamic_reconfigure::Config config = reconfigure("skewnormal");
  EXPECT_EQ(stringOf(config, "method"), "skewnormal");
  const auto again = ros::topic::waitForMessage<nav_msgs::OccupancyGrid>("reconfigure/predicted_map", nh,
                                                                          ros::Duration(30.0));
  ASSERT_TRUE(again != nullptr);
  EXPECT_NE(again->data, first->data) << "the overlays did not change with the method";
  PredictRooms by_default;
  ASSERT_TRUE(call(&by_default, "reconfigure/predict_rooms"));
  ASSERT_TRUE(by_default.response.success) << by_default.response.message;
  EXPECT_EQ(by_default.response.method, "skewnormal");

  // A parameter: a higher density threshold gives smaller rooms; a request's own value still wins.
  config = reconfigure("", "skewnormal_p_th", 0.8);
  EXPECT_DOUBLE_EQ(doubleOf(config, "skewnormal_p_th"), 0.8);
  PredictRooms tuned, explicit_value;
  ASSERT_TRUE(call(&tuned, "reconfigure/predict_rooms"));
  hidden_rooms::PredictionParameter half;
  half.name = "skewnormal_p_th";
  half.value = 0.5;
  explicit_value.request.parameters.push_back(half);
  ASSERT_TRUE(call(&explicit_value, "reconfigure/predict_rooms"));
  ASSERT_TRUE(tuned.response.success && explicit_value.response.success);
  EXPECT_LT(totalArea(tuned.response), totalArea(explicit_value.response));
  EXPECT_NEAR(totalArea(explicit_value.response), totalArea(by_default.response), 1e-9);

  // A value the method refuses, and an unknown method: both put back, the node keeps the settings before.
  config = reconfigure("", "skewnormal_p_th", 1.5);
  EXPECT_DOUBLE_EQ(doubleOf(config, "skewnormal_p_th"), 0.8);
  config = reconfigure("nosuch");
  EXPECT_EQ(stringOf(config, "method"), "skewnormal");
  PredictRooms after;
  ASSERT_TRUE(call(&after, "reconfigure/predict_rooms"));
  EXPECT_EQ(after.response.method, "skewnormal");
  EXPECT_NEAR(totalArea(after.response), totalArea(tuned.response), 1e-9);
}

TEST(RoomPredictor, PublishesLatchedOverlays) {
  REQUIRE_CASE();
  ros::NodeHandle nh;
  // ~predict_on_map: the node predicted the file's doors as soon as the map arrived.
  const auto completed = ros::topic::waitForMessage<nav_msgs::OccupancyGrid>("predicted_map", nh, ros::Duration(30.0));
  ASSERT_TRUE(completed != nullptr);
  const hidden_rooms::common::OccupancyGrid map = hidden_rooms::common::loadMap(caseDir() + "/map.yaml");
  EXPECT_EQ(completed->info.width, static_cast<uint32_t>(map.width()));
  EXPECT_EQ(completed->info.height, static_cast<uint32_t>(map.height()));
  const auto markers =
      ros::topic::waitForMessage<visualization_msgs::MarkerArray>("predicted_rooms", nh, ros::Duration(30.0));
  ASSERT_TRUE(markers != nullptr);
  std::map<std::string, int> per_namespace;
  for (const visualization_msgs::Marker& marker : markers->markers) {
    if (marker.action == visualization_msgs::Marker::DELETEALL) continue;
    ++per_namespace[marker.ns];
    EXPECT_EQ(marker.header.frame_id, "map");
  }
  EXPECT_EQ(markers->markers.front().action, visualization_msgs::Marker::DELETEALL);
  EXPECT_GE(per_namespace["rooms"], 10);
  EXPECT_EQ(per_namespace["rooms"], per_namespace["outlines"]);
  EXPECT_EQ(per_namespace["rooms"], per_namespace["labels"]);
  EXPECT_EQ(per_namespace["doors"], 1);
  EXPECT_EQ(per_namespace["debug_extended_lines"], 1);  // ~publish_debug is on in the launch file
  EXPECT_EQ(per_namespace["debug_in_out_cells"], 1);
}

// segment_rooms with the predicted rooms: the rooms of segment_rooms (the tool) on the map, doors and prediction,
// its markers latched on room_segmentation; bad requests fail with a message.
TEST(RoomPredictor, SegmentsTheMapWithThePredictedRooms) {
  REQUIRE_CASE();
  const hidden_rooms::common::DoorsFile doors = hidden_rooms::common::loadDoors(caseDir() + "/doors.yaml");
  PredictRooms prediction_call;  // the latest prediction: the doors file's, by default
  prediction_call.request.doors = hidden_rooms::toRos(doors);
  prediction_call.request.method = "default";
  ASSERT_TRUE(call(&prediction_call));
  ASSERT_TRUE(prediction_call.response.success) << prediction_call.response.message;
  hidden_rooms::SegmentRooms service;
  service.request.with_predicted_rooms = true;
  ASSERT_TRUE(ros::service::waitForService("segment_rooms", ros::Duration(30.0)));
  ASSERT_TRUE(ros::service::call("segment_rooms", service));
  ASSERT_TRUE(service.response.success) << service.response.message;
  int predicted = 0, corridors = 0;
  for (const hidden_rooms::SegmentedRoom& room : service.response.rooms) {
    predicted += room.predicted;
    corridors += room.kind == hidden_rooms::SegmentedRoom::CORRIDOR;
    EXPECT_GE(room.outline.size(), 3u);
  }
  EXPECT_GE(predicted, static_cast<int>(doors.doors.size()) - 2);  // a door or two may be not placed
  EXPECT_GE(corridors, 1);
  int door_passages = 0;
  for (const hidden_rooms::RoomPassage& passage : service.response.passages) {
    EXPECT_GE(passage.room_a, 1u);
    EXPECT_LE(passage.room_a, service.response.rooms.size());
    door_passages += passage.kind != hidden_rooms::RoomPassage::OPEN;
  }
  EXPECT_EQ(door_passages, static_cast<int>(doors.doors.size()));
  const hidden_rooms::common::OccupancyGrid map = hidden_rooms::common::loadMap(caseDir() + "/map.yaml");
  EXPECT_EQ(service.response.labels.width, static_cast<uint32_t>(map.width()));
  EXPECT_EQ(service.response.labels.height, static_cast<uint32_t>(map.height()));
  EXPECT_EQ(service.response.labels.encoding, "mono16");

  // The same as the offline tool on the offline prediction (labels flipped back to the file's row order).
  const std::string prediction = runOffline("default");
  const std::string out = testing_util::makeTempDir("room_predictor_segment");
  const testing_util::CommandResult result = testing_util::runCommand(
      std::string(SEGMENT_ROOMS_BIN) + " " + caseDir() + "/map.yaml --doors " + caseDir() + "/doors.yaml --rooms " +
      prediction + "/rooms.yaml --out " + out);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const YAML::Node offline = YAML::LoadFile(out + "/rooms.yaml");
  EXPECT_EQ(offline["rooms"].size(), service.response.rooms.size());
  EXPECT_EQ(offline["passages"].size(), service.response.passages.size());

  ros::NodeHandle nh;
  const auto markers =
      ros::topic::waitForMessage<visualization_msgs::MarkerArray>("room_segmentation", nh, ros::Duration(30.0));
  ASSERT_TRUE(markers != nullptr);
  std::map<std::string, int> per_namespace;
  for (const visualization_msgs::Marker& marker : markers->markers) ++per_namespace[marker.ns];
  EXPECT_EQ(per_namespace["room_labels"], static_cast<int>(service.response.rooms.size()));
  EXPECT_GE(per_namespace["room_graph"], 2);

  hidden_rooms::SegmentRooms bad;
  bad.request.method = "nope";
  ASSERT_TRUE(ros::service::call("segment_rooms", bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("unknown segmentation method 'nope'"), std::string::npos);
  hidden_rooms::SegmentRooms no_map;
  ASSERT_TRUE(ros::service::waitForService("no_map/segment_rooms", ros::Duration(30.0)));
  ASSERT_TRUE(ros::service::call("no_map/segment_rooms", no_map));
  EXPECT_FALSE(no_map.response.success);
  EXPECT_NE(no_map.response.message.find("none was received"), std::string::npos) << no_map.response.message;
}

TEST(RoomPredictor, WritesTheCompletedMapAsAnOctomap) {
  REQUIRE_CASE();
  ros::NodeHandle nh;
  const auto completed =
      ros::topic::waitForMessage<nav_msgs::OccupancyGrid>("octomap/predicted_map", nh, ros::Duration(60.0));
  ASSERT_TRUE(completed != nullptr);
  std::string path;
  ASSERT_TRUE(nh.getParam("/octomap/room_predictor/octomap_out", path));
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while (!std::filesystem::exists(path) && ros::WallTime::now() < deadline) ros::WallDuration(0.1).sleep();
  ASSERT_TRUE(std::filesystem::exists(path)) << "no 3D map written";
  // Its band between floor and ceiling is the completed map, cut to its known cells.
  const hidden_rooms::common::OccupancyGrid map = hidden_rooms::fromRos(*completed);
  const hidden_rooms::common::OccupancyGrid sliced =
      hidden_rooms::map3d::sliceOctomap(path, hidden_rooms::map3d::SliceOptions());
  const cv::Rect known = cv::boundingRect(map.cells != hidden_rooms::common::OccupancyGrid::kUnknown);
  ASSERT_EQ(sliced.cells.size(), known.size());
  EXPECT_EQ(cv::countNonZero(sliced.cells != map.cells(known)), 0);
}

void expectFailure(PredictRooms* service, const std::vector<std::string>& words, const std::string& name = "predict_rooms") {
  ASSERT_TRUE(call(service, name)) << "the service call itself failed (node down?)";
  EXPECT_FALSE(service->response.success);
  for (const std::string& word : words)
    EXPECT_NE(service->response.message.find(word), std::string::npos)
        << "message '" << service->response.message << "' does not say '" << word << "'";
  EXPECT_TRUE(service->response.rooms.empty());
  EXPECT_EQ(service->response.completed_map.data.size(), 0u);
}

TEST(RoomPredictor, BadRequestsFailWithAMessageAndTheNodeKeepsServing) {
  REQUIRE_CASE();
  const hidden_rooms::common::DoorsFile doors = hidden_rooms::common::loadDoors(caseDir() + "/doors.yaml");
  {
    SCOPED_TRACE("door outside the map");
    PredictRooms service;
    service.request.doors = hidden_rooms::toRos(doors);
    service.request.doors[1].position.x = -50.0;
    expectFailure(&service, {"door " + std::to_string(doors.doors[1].id), "outside the map"});
  }
  {
    SCOPED_TRACE("map with no known cell");
    PredictRooms service;
    service.request.doors = hidden_rooms::toRos(doors);
    hidden_rooms::common::OccupancyGrid empty;
    empty.cells = cv::Mat_<int8_t>(400, 400, hidden_rooms::common::OccupancyGrid::kUnknown);
    service.request.map = hidden_rooms::toRos(empty, "map", ros::Time::now());
    expectFailure(&service, {"map", "no known cell"});
  }
  {
    SCOPED_TRACE("map with no free cell");
    PredictRooms service;
    service.request.doors = hidden_rooms::toRos(doors);
    hidden_rooms::common::OccupancyGrid walls = hidden_rooms::common::loadMap(caseDir() + "/map.yaml");
    walls.cells.setTo(hidden_rooms::common::OccupancyGrid::kOccupied);
    service.request.map = hidden_rooms::toRos(walls, "map", ros::Time::now());
    expectFailure(&service, {"map", "no free cell"});
  }
  {
    SCOPED_TRACE("a map too large, thousands of doors, a NaN position");
    PredictRooms huge;
    huge.request.map.info.width = 100000;
    huge.request.map.info.height = 100000;
    huge.request.map.info.resolution = 0.05f;
    const ros::WallTime start = ros::WallTime::now();
    expectFailure(&huge, {"map", "max_map_cells"});
    PredictRooms many;
    many.request.doors.resize(5000, hidden_rooms::toRos(doors).front());
    for (size_t k = 0; k < many.request.doors.size(); ++k) many.request.doors[k].id = static_cast<int>(k);
    expectFailure(&many, {"5000 doors", "max_doors"});
    EXPECT_LT((ros::WallTime::now() - start).toSec(), 5.0);
    PredictRooms nan_door;
    nan_door.request.doors = hidden_rooms::toRos(doors);
    nan_door.request.doors[0].position.y = std::numeric_limits<double>::quiet_NaN();
    expectFailure(&nan_door, {"door " + std::to_string(doors.doors[0].id), "finite"});
  }
  {
    SCOPED_TRACE("map whose data does not match its size");
    PredictRooms service;
    service.request.map.info.width = 10;
    service.request.map.info.height = 10;
    service.request.map.info.resolution = 0.05f;
    service.request.map.data.resize(7);
    expectFailure(&service, {"map", "7 cells"});
  }
  {
    SCOPED_TRACE("cell values beyond -1..100, a zero or NaN orientation (before: success with no door placed)");
    const hidden_rooms::common::OccupancyGrid map = hidden_rooms::common::loadMap(caseDir() + "/map.yaml");
    for (const int8_t value : {int8_t(127), int8_t(-50)}) {
      PredictRooms service;
      service.request.doors = hidden_rooms::toRos(doors);
      service.request.map = hidden_rooms::toRos(map, "map", ros::Time::now());
      std::replace(service.request.map.data.begin(), service.request.map.data.end(), int8_t(0), value);
      expectFailure(&service, {"map message", "is " + std::to_string(value), "-1 unknown or 0..100"});
    }
    for (const double w : {0.0, std::numeric_limits<double>::quiet_NaN()}) {
      PredictRooms service;
      service.request.doors = hidden_rooms::toRos(doors);
      service.request.map = hidden_rooms::toRos(map, "map", ros::Time::now());
      service.request.map.info.origin.orientation.w = w;
      expectFailure(&service, {"map message", "not a unit quaternion"});
    }
  }
  {
    SCOPED_TRACE("unknown method");
    PredictRooms service;
    service.request.method = "no_such_method";
    expectFailure(&service, {"no_such_method", "default"});
  }
  {
    SCOPED_TRACE("unknown parameter");
    PredictRooms service;
    hidden_rooms::PredictionParameter parameter;
    parameter.name = "no_such_parameter";
    parameter.value = 1.0;
    service.request.parameters.push_back(parameter);
    expectFailure(&service, {"no_such_parameter"});
  }
  {
    SCOPED_TRACE("bad door width and orientation");
    PredictRooms service;
    service.request.doors = hidden_rooms::toRos(doors);
    service.request.doors[0].width = -1.0;
    expectFailure(&service, {"door " + std::to_string(doors.doors[0].id), "width"});
    service.request.doors = hidden_rooms::toRos(doors);
    service.request.doors[0].orientation = 7;
    expectFailure(&service, {"orientation"});
  }
  {
    SCOPED_TRACE("duplicate door id");
    PredictRooms service;
    service.request.doors = hidden_rooms::toRos(doors);
    service.request.doors[1].id = service.request.doors[0].id;
    expectFailure(&service, {"used twice"});
  }
  {
    SCOPED_TRACE("no map yet, no doors file");
    PredictRooms service;
    service.request.doors = hidden_rooms::toRos(doors);
    expectFailure(&service, {"no map", "/no_map/map"}, "/no_map/predict_rooms");
    PredictRooms no_doors;
    no_doors.request.map =
        hidden_rooms::toRos(hidden_rooms::common::loadMap(caseDir() + "/map.yaml"), "map", ros::Time::now());
    expectFailure(&no_doors, {"no doors", "closed_doors_file"}, "/no_map/predict_rooms");
  }
  {
    SCOPED_TRACE("the doors file's frame is not the map's");
    PredictRooms service;  // no doors: the node's ~closed_doors_file (frame map) for a map in frame odom
    service.request.map =
        hidden_rooms::toRos(hidden_rooms::common::loadMap(caseDir() + "/map.yaml"), "odom", ros::Time::now());
    expectFailure(&service, {"~closed_doors_file", "its doors are in frame 'map', the map in 'odom'"});
  }
  // Still serving, and a good request with its own map and a parameter override works.
  PredictRooms service;
  service.request.doors = hidden_rooms::toRos(doors);
  service.request.map =
      hidden_rooms::toRos(hidden_rooms::common::loadMap(caseDir() + "/map.yaml"), "map", ros::Time::now());
  service.request.method = "thesis";
  hidden_rooms::PredictionParameter parameter;
  parameter.name = "thesis_depth";
  parameter.value = 3.0;
  service.request.parameters.push_back(parameter);
  ASSERT_TRUE(call(&service));
  EXPECT_TRUE(service.response.success) << service.response.message;
  EXPECT_EQ(service.response.rooms.size(), doors.doors.size());
  PredictRooms again;
  ASSERT_TRUE(call(&again, "/no_map/predict_rooms"));  // the other node is alive too
  EXPECT_FALSE(again.response.success);
}

// The node's doors, as save_doors writes them; nullopt when the call fails.
std::optional<hidden_rooms::common::DoorsFile> savedDoors(const std::string& path) {
  hidden_rooms::SaveDoors save;
  save.request.path = path;
  if (!ros::service::waitForService("save_doors", ros::Duration(30.0)) || !ros::service::call("save_doors", save) ||
      !save.response.success)
    return std::nullopt;
  return hidden_rooms::common::loadDoors(path);
}

// Waits up to 10 s for the node to have `count` doors.
std::optional<hidden_rooms::common::DoorsFile> waitForDoors(const std::string& path, size_t count) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    const auto doors = savedDoors(path);
    if (doors && doors->doors.size() == count) return doors;
    ros::Duration(0.1).sleep();
  }
  return savedDoors(path);
}

// Runs last: it changes the node's doors.
TEST(RoomPredictor, ClickedPointsRemoveAndAddDoorsThatSaveDoorsWrites) {
  REQUIRE_CASE();
  const hidden_rooms::common::DoorsFile file = hidden_rooms::common::loadDoors(caseDir() + "/doors.yaml");
  const hidden_rooms::common::MapDoor first = file.doors.front();
  const std::string path = testing_util::makeTempDir("room_predictor_doors") + "/new/folder/doors.yaml";
  ros::NodeHandle nh;
  ros::Publisher clicks = nh.advertise<geometry_msgs::PointStamped>("clicked_point", 10);
  for (int attempt = 0; attempt < 100 && clicks.getNumSubscribers() == 0; ++attempt) ros::Duration(0.1).sleep();
  ASSERT_GT(clicks.getNumSubscribers(), 0u);
  auto click = [&](const hidden_rooms::common::Point2& point, const std::string& frame) {
    geometry_msgs::PointStamped message;
    message.header.frame_id = frame;
    message.header.stamp = ros::Time::now();
    message.point.x = point.x();
    message.point.y = point.y();
    clicks.publish(message);
  };
  // A click on a door removes it.
  click(first.position, "map");
  auto doors = waitForDoors(path, file.doors.size() - 1);
  ASSERT_TRUE(doors);
  ASSERT_EQ(doors->doors.size(), file.doors.size() - 1);
  EXPECT_EQ(doors->frame, "map");
  // A click 0.2 m beside where it was adds it back, with a new id, on its wall, as wide as the other doors.
  const hidden_rooms::common::Point2 along =
      first.orientation == hidden_rooms::common::DoorOrientation::kAlongX ? hidden_rooms::common::Point2(1, 0)
                                                                          : hidden_rooms::common::Point2(0, 1);
  click(first.position + 0.2 * along, "map");
  doors = waitForDoors(path, file.doors.size());
  ASSERT_TRUE(doors);
  ASSERT_EQ(doors->doors.size(), file.doors.size());
  const hidden_rooms::common::MapDoor& added = doors->doors.back();
  EXPECT_EQ(added.id, 16);
  EXPECT_EQ(added.orientation, first.orientation);
  EXPECT_LT((added.position - first.position).norm(), 0.3);
  EXPECT_GT(added.width, 1.0);  // the benchmark's doors are 1.3 to 2 m wide
  // The node predicts on its doors: an empty request gets all of them.
  PredictRooms service;
  ASSERT_TRUE(call(&service));
  EXPECT_TRUE(service.response.success) << service.response.message;
  EXPECT_EQ(service.response.rooms.size(), file.doors.size());
  // A click in another frame than the map's, or far from any wall, changes nothing.
  click(first.position + 0.2 * along, "odom");
  click(hidden_rooms::common::Point2(-1000.0, -1000.0), "map");
  ros::Duration(1.0).sleep();
  doors = savedDoors(path);
  ASSERT_TRUE(doors);
  EXPECT_EQ(doors->doors.size(), file.doors.size());
  hidden_rooms::SaveDoors nameless;
  ASSERT_TRUE(ros::service::call("save_doors", nameless));
  EXPECT_FALSE(nameless.response.success);
  EXPECT_NE(nameless.response.message.find("names no file"), std::string::npos) << nameless.response.message;
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_room_predictor");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
