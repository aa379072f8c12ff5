// predict_rooms_offline --map MAP.yaml --doors DOORS.yaml --method NAME --out DIR [--params FILE.yaml]
//                       [--gt-rooms LABELS.png] [--debug-dir D]
// Predicts the rooms behind the closed doors of a map without a ROS graph, and scores them when the true rooms
// are given.
#include <iostream>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/evaluation/prediction_output.h"
#include "hidden_rooms/prediction/room_predictor.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

int run(int argc, char** argv) {
  std::string map_path, doors_path, method, out_dir, params_path, gt_path, debug_dir;
  po::options_description options("Options");
  options.add_options()
      ("map", po::value(&map_path)->required(), "input map (map_server yaml)")
      ("doors", po::value(&doors_path)->required(), "closed doors (doors.yaml, map frame)")
      ("method", po::value(&method)->required(), "prediction method")
      ("out", po::value(&out_dir)->required(), "output folder (created)")
      ("params", po::value(&params_path), "parameter overrides: flat YAML of name: number")
      ("gt-rooms", po::value(&gt_path), "true rooms: label image, k = room behind the k-th door")
      ("debug-dir", po::value(&debug_dir), "folder for per-stage debug images");
  std::string methods;
  for (const std::string& name : prediction::roomPredictorNames()) methods += (methods.empty() ? "" : ", ") + name;
  po::variables_map values;
  const std::string usage =
      "Usage: predict_rooms_offline --map MAP.yaml --doors DOORS.yaml --method NAME --out DIR\n"
      "       [--params FILE.yaml] [--gt-rooms LABELS.png] [--debug-dir D]\n"
      "Methods: " + methods + "\n"
      "Writes DIR/rooms.png (label k = room of the k-th door), DIR/rooms.yaml, DIR/map.yaml +\n"
      "DIR/map.pgm (the map completed with the rooms), DIR/overlay.png (a picture: predicted rooms\n"
      "tinted, true rooms outlined in green) and, with --gt-rooms, DIR/metrics.yaml.";
  if (!common::parseCommandLine(argc, argv, usage, options, po::positional_options_description(), &values))
    return common::kExitOk;

  // Read and check everything before writing anything.
  const std::unique_ptr<prediction::RoomPredictor> predictor = prediction::makeRoomPredictor(method);
  prediction::PredictionRequest request;
  request.map = common::loadMap(map_path);
  request.doors = common::loadDoors(doors_path);
  if (!params_path.empty()) request.parameters = common::loadParameterFile(params_path);
  request.debug_dir = debug_dir;
  cv::Mat truth;
  if (!gt_path.empty()) truth = evaluation::loadTrueRooms(gt_path, request.map);
  if (!debug_dir.empty()) common::createOutputDirectory(debug_dir);
  common::OutputFolder out(out_dir, {map_path, common::mapImagePath(map_path), doors_path, params_path, gt_path});

  const prediction::PredictionResult result = predictor->predict(request);

  const evaluation::PredictionOutputs outputs = evaluation::writePredictionOutputs(request, result, method, &out, truth);
  evaluation::printPredictionSummary(std::cout, request, result, method, out_dir, outputs);
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("predict_rooms_offline", [&] { return run(argc, argv); });
}
