// predict_rooms_client --doors DOORS.yaml [--method M] [--map MAP.yaml] [--params FILE.yaml] [--out DIR]
//                      [--gt-rooms LABELS.png] [--service NAME] [--timeout S]
// Calls the predict_rooms service of a running room_predictor and saves the answer as predict_rooms_offline
// saves its own (the same core writer): rooms.png, rooms.yaml, map.yaml + map.pgm, overlay.png, metrics.yaml.
#include <iostream>

#include <hidden_rooms/PredictRooms.h>
#include <ros/ros.h>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/evaluation/prediction_output.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "hidden_rooms/ros/conversions.h"

namespace po = boost::program_options;

namespace hidden_rooms {
namespace {

int run(int argc, char** argv) {
  std::string doors_path, method, map_path, params_path, out_dir = "prediction", gt_path,
                                                         service_name = "predict_rooms";
  double timeout = 30.0;
  po::options_description options("Options");
  options.add_options()
      ("doors", po::value(&doors_path)->required(), "closed doors (doors.yaml, map frame)")
      ("method", po::value(&method), "prediction method (default: the node's ~method)")
      ("map", po::value(&map_path), "map to predict on (map_server yaml); default: the latest map on `map`")
      ("params", po::value(&params_path), "parameter overrides: flat YAML of name: number")
      ("out", po::value(&out_dir), "output folder (created; default: prediction)")
      ("gt-rooms", po::value(&gt_path), "true rooms: label image, k = room behind the k-th door")
      ("service", po::value(&service_name), "service to call (default: predict_rooms)")
      ("timeout", po::value(&timeout), "seconds to wait for the service and the map (default: 30)");
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: predict_rooms_client --doors DOORS.yaml [--method M] [--map MAP.yaml] [--out DIR]\n"
          "       [--params FILE.yaml] [--gt-rooms LABELS.png] [--service NAME] [--timeout S]\n"
          "Calls the predict_rooms service (node room_predictor) and writes what predict_rooms_offline\n"
          "writes: DIR/rooms.png, DIR/rooms.yaml, DIR/map.yaml + DIR/map.pgm, DIR/overlay.png and,\n"
          "with --gt-rooms, DIR/metrics.yaml.",
          options, po::positional_options_description(), &values))
    return common::kExitOk;

  // Read and check the files before asking the node anything.
  prediction::PredictionRequest request;
  request.doors = common::loadDoors(doors_path);
  if (!params_path.empty()) request.parameters = common::loadParameterFile(params_path);
  if (!map_path.empty()) request.map = common::loadMap(map_path);

  ros::NodeHandle nh;
  PredictRooms service;
  if (request.map.empty()) {
    // The map goes into the request, so that the outputs are drawn over the very map the node predicted on.
    const auto map = ros::topic::waitForMessage<nav_msgs::OccupancyGrid>("map", nh, ros::Duration(timeout));
    if (map == nullptr)
      throw common::InputError(ros::names::resolve("map"), "no map received within " + std::to_string(timeout) + " s");
    service.request.map = *map;
    request.map = fromRos(*map);
  } else {
    service.request.map = toRos(request.map, request.doors.frame, ros::Time::now());
  }
  cv::Mat truth;
  if (!gt_path.empty()) truth = evaluation::loadTrueRooms(gt_path, request.map);
  common::OutputFolder out(
      out_dir, {doors_path, params_path, gt_path, map_path, map_path.empty() ? "" : common::mapImagePath(map_path)});
  service.request.doors = toRos(request.doors);
  service.request.method = method;
  service.request.parameters = toRos(request.parameters);

  const std::string resolved = ros::names::resolve(service_name);
  if (!ros::service::waitForService(resolved, ros::Duration(timeout)))
    throw common::InputError(resolved, "service not available within " + std::to_string(timeout) + " s");
  if (!ros::service::call(resolved, service)) throw common::InputError(resolved, "service call failed");
  if (!service.response.success) throw common::InputError(resolved, service.response.message);

  prediction::PredictionResult result;
  result.seconds = service.response.computation_time;
  for (const PredictedRoom& room : service.response.rooms) result.rooms.push_back(fromRos(room, request.map));
  if (result.rooms.size() != request.doors.doors.size())
    throw common::InputError(resolved, "answered " + std::to_string(result.rooms.size()) + " rooms for " +
                                           std::to_string(request.doors.doors.size()) + " doors");
  const evaluation::PredictionOutputs outputs =
      evaluation::writePredictionOutputs(request, result, service.response.method, &out, truth);
  evaluation::printPredictionSummary(std::cout, request, result, service.response.method, out_dir, outputs);
  return common::kExitOk;
}

}  // namespace
}  // namespace hidden_rooms

int main(int argc, char** argv) {
  ros::init(argc, argv, "predict_rooms_client", ros::init_options::AnonymousName | ros::init_options::NoSigintHandler);
  return hidden_rooms::common::runTool("predict_rooms_client", [&] { return hidden_rooms::run(argc, argv); });
}
