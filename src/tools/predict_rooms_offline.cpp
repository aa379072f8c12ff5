// predict_rooms_offline --map MAP.yaml --doors DOORS.yaml --method NAME --out DIR [--params FILE.yaml]
//                       [--gt-rooms LABELS.png] [--debug-dir D]
// Predicts the rooms behind the closed doors of a map without a ROS graph, and scores them when the true rooms
// are given.
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>

#include <opencv2/imgcodecs.hpp>

#include "hidden_rooms/command_line.h"
#include "hidden_rooms/evaluation.h"
#include "hidden_rooms/input_error.h"
#include "hidden_rooms/prediction_support.h"
#include "hidden_rooms/render.h"
#include "hidden_rooms/room_predictor.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

void writeRoomsYaml(const PredictionRequest& request, const PredictionResult& result, const std::string& method,
                    const std::string& path) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "method" << YAML::Value << method;
  out << YAML::Key << "frame" << YAML::Value << request.doors.frame;
  out << YAML::Key << "seconds" << YAML::Value << result.seconds;
  out << YAML::Key << "rooms" << YAML::Value << YAML::BeginSeq;
  for (size_t k = 0; k < result.rooms.size(); ++k) {
    const RoomPrediction& room = result.rooms[k];
    out << YAML::BeginMap;
    out << YAML::Key << "door_id" << YAML::Value << room.door_id;
    out << YAML::Key << "label" << YAML::Value << k + 1;
    out << YAML::Key << "placed" << YAML::Value << room.placed;
    if (!room.placed) out << YAML::Key << "problem" << YAML::Value << room.problem;
    out << YAML::Key << "area" << YAML::Value << room.area;
    out << YAML::Key << "polygon" << YAML::Value << YAML::BeginSeq;
    for (const Point2& p : room.polygon) out << YAML::Flow << YAML::BeginSeq << p.x() << p.y() << YAML::EndSeq;
    out << YAML::EndSeq;
    out << YAML::Key << "terms" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, value] : room.terms) out << YAML::Key << name << YAML::Value << value;
    out << YAML::EndMap << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  std::ofstream file(path);
  file << out.c_str() << "\n";
  if (!file) throw InputError(path, "cannot write");
}

void writeMetrics(const PredictionRequest& request, const RoomScores& scores, const std::string& path) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "mean_iou" << YAML::Value << scores.mean_iou;
  out << YAML::Key << "iou_total" << YAML::Value << scores.iou_total;
  out << YAML::Key << "rooms" << YAML::Value << YAML::BeginSeq;
  for (size_t k = 0; k < scores.iou.size(); ++k)
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "door_id" << YAML::Value << request.doors.doors[k].id
        << YAML::Key << "iou" << YAML::Value << scores.iou[k] << YAML::EndMap;
  out << YAML::EndSeq << YAML::EndMap;
  std::ofstream file(path);
  file << out.c_str() << "\n";
  if (!file) throw InputError(path, "cannot write");
}

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
  for (const std::string& name : roomPredictorNames()) methods += (methods.empty() ? "" : ", ") + name;
  po::variables_map values;
  if (!parseCommandLine(argc, argv,
                        "Usage: predict_rooms_offline --map MAP.yaml --doors DOORS.yaml --method NAME --out DIR\n"
                        "       [--params FILE.yaml] [--gt-rooms LABELS.png] [--debug-dir D]\n"
                        "Methods: " + methods + "\n"
                        "Writes DIR/rooms.png (label k = room of the k-th door), DIR/rooms.yaml, DIR/map.yaml +\n"
                        "DIR/map.pgm (the map completed with the rooms), DIR/overlay.png (a picture: predicted rooms\n"
                        "tinted, true rooms outlined in green) and, with --gt-rooms, DIR/metrics.yaml.",
                        options, po::positional_options_description(), &values))
    return kExitOk;

  // Read and check everything before writing anything.
  const std::unique_ptr<RoomPredictor> predictor = makeRoomPredictor(method);
  PredictionRequest request;
  request.map = loadMap(map_path);
  request.doors = loadDoors(doors_path);
  if (!params_path.empty()) request.parameters = loadParameterFile(params_path);
  request.debug_dir = debug_dir;
  cv::Mat truth;
  if (!gt_path.empty()) {
    truth = cv::imread(gt_path, cv::IMREAD_UNCHANGED);
    if (truth.empty()) throw InputError(gt_path, "cannot read the true rooms image");
    if (truth.size() != request.map.cells.size())
      throw InputError(gt_path, "true rooms image is " + std::to_string(truth.cols) + "x" + std::to_string(truth.rows) +
                                    ", the map " + std::to_string(request.map.width()) + "x" +
                                    std::to_string(request.map.height()));
  }
  if (!debug_dir.empty()) createOutputDirectory(debug_dir);

  const PredictionResult result = predictor->predict(request);

  createOutputDirectory(out_dir);
  const std::filesystem::path out(out_dir);
  const cv::Mat1w labels = roomLabels(request.map, request.doors, result.rooms);
  saveLabelImage(labels, (out / "rooms.png").string());
  writeRoomsYaml(request, result, method, (out / "rooms.yaml").string());
  saveMap(insertRooms(request.map, request.doors, result.rooms), (out / "map").string());
  const std::string overlay_path = (out / "overlay.png").string();
  if (!cv::imwrite(overlay_path, renderPredictionOverlay(request.map, labels, truth)))
    throw InputError(overlay_path, "cannot write overlay");

  std::cout << method << ": " << result.rooms.size() << " doors in " << std::fixed << std::setprecision(3)
            << result.seconds << " s -> " << out_dir << std::endl;
  for (const RoomPrediction& room : result.rooms)
    if (!room.placed) std::cout << "  door " << room.door_id << " not placed: " << room.problem << std::endl;
  if (!truth.empty()) {
    const RoomScores scores = scoreRooms(labels, truth, static_cast<int>(request.doors.doors.size()));
    for (size_t k = 0; k < scores.iou.size(); ++k)
      std::cout << "  door " << request.doors.doors[k].id << ": IoU " << scores.iou[k] << std::endl;
    std::cout << "mean IoU " << scores.mean_iou << ", IoU_tot " << scores.iou_total << std::endl;
    writeMetrics(request, scores, (out / "metrics.yaml").string());
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return runTool("predict_rooms_offline", [&] { return run(argc, argv); });
}
