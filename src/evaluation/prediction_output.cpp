#include "hidden_rooms/evaluation/prediction_output.h"

#include <yaml-cpp/yaml.h>

#include <iomanip>
#include <ostream>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/prediction/prediction_support.h"

namespace hidden_rooms::evaluation {
namespace {

void writeYaml(const YAML::Emitter& out, const std::string& path) {
  common::writeTextAtomically(path, std::string(out.c_str()) + "\n", "YAML file");
}

void writeRoomsYaml(const prediction::PredictionRequest& request, const prediction::PredictionResult& result,
                    const std::string& method, const std::string& path) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "method" << YAML::Value << method;
  out << YAML::Key << "frame" << YAML::Value << request.doors.frame;
  out << YAML::Key << "seconds" << YAML::Value << result.seconds;
  out << YAML::Key << "rooms" << YAML::Value << YAML::BeginSeq;
  for (size_t k = 0; k < result.rooms.size(); ++k) {
    const prediction::RoomPrediction& room = result.rooms[k];
    out << YAML::BeginMap;
    out << YAML::Key << "door_id" << YAML::Value << room.door_id;
    out << YAML::Key << "label" << YAML::Value << k + 1;
    out << YAML::Key << "placed" << YAML::Value << room.placed;
    if (!room.placed) out << YAML::Key << "problem" << YAML::Value << room.problem;
    out << YAML::Key << "area" << YAML::Value << room.area;
    out << YAML::Key << "polygon" << YAML::Value << YAML::BeginSeq;
    for (const common::Point2& p : room.polygon) out << YAML::Flow << YAML::BeginSeq << p.x() << p.y() << YAML::EndSeq;
    out << YAML::EndSeq;
    out << YAML::Key << "terms" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, value] : room.terms) out << YAML::Key << name << YAML::Value << value;
    out << YAML::EndMap << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  writeYaml(out, path);
}

void writeMetrics(const prediction::PredictionRequest& request, const RoomScores& scores, const std::string& path) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "mean_iou" << YAML::Value << scores.mean_iou;
  out << YAML::Key << "iou_total" << YAML::Value << scores.iou_total;
  out << YAML::Key << "rooms" << YAML::Value << YAML::BeginSeq;
  for (size_t k = 0; k < scores.iou.size(); ++k)
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "door_id" << YAML::Value << request.doors.doors[k].id
        << YAML::Key << "iou" << YAML::Value << scores.iou[k] << YAML::EndMap;
  out << YAML::EndSeq << YAML::EndMap;
  writeYaml(out, path);
}

}  // namespace

PredictionOutputs writePredictionOutputs(const prediction::PredictionRequest& request,
                                         const prediction::PredictionResult& result, const std::string& method,
                                         common::OutputFolder* out, const cv::Mat& true_labels) {
  PredictionOutputs outputs;
  outputs.labels = prediction::roomLabels(request.map, request.doors, result.rooms);
  if (!true_labels.empty())
    outputs.scores = scoreRooms(outputs.labels, true_labels, static_cast<int>(request.doors.doors.size()));
  common::saveLabelImage(outputs.labels, out->file("rooms.png"));
  writeRoomsYaml(request, result, method, out->file("rooms.yaml"));
  common::saveMap(prediction::insertRooms(request.map, request.doors, result.rooms), out->mapPrefix("map"));
  common::writeImage(out->file("overlay.png"),
                     prediction::renderPredictionOverlay(request.map, outputs.labels, true_labels));
  if (outputs.scores) writeMetrics(request, *outputs.scores, out->file("metrics.yaml"));
  out->commit();
  return outputs;
}

cv::Mat loadTrueRooms(const std::string& path, const common::OccupancyGrid& map) {
  cv::Mat truth;
  try {
    truth = common::readImage(path);
  } catch (const common::InputError& error) {
    throw common::InputError(path, "cannot read the true rooms image: " + error.problem());
  }
  if (truth.channels() != 1 || (truth.depth() != CV_8U && truth.depth() != CV_16U))
    throw common::InputError(path, "true rooms image has " + std::to_string(truth.channels()) +
                                       " channels or a depth other than 8 or 16 bits: a label image is grey");
  if (truth.size() != map.cells.size())
    throw common::InputError(path, "true rooms image is " + std::to_string(truth.cols) + "x" +
                                       std::to_string(truth.rows) + ", the map " + std::to_string(map.width()) + "x" +
                                       std::to_string(map.height()));
  return truth;
}

void printPredictionSummary(std::ostream& out, const prediction::PredictionRequest& request,
                            const prediction::PredictionResult& result, const std::string& method,
                            const std::string& out_dir, const PredictionOutputs& outputs) {
  out << method << ": " << result.rooms.size() << " doors in " << std::fixed << std::setprecision(3)
      << result.seconds << " s -> " << out_dir << std::endl;
  for (const prediction::RoomPrediction& room : result.rooms)
    if (!room.placed) out << "  door " << room.door_id << " not placed: " << room.problem << std::endl;
  if (outputs.scores) {
    const RoomScores& scores = *outputs.scores;
    for (size_t k = 0; k < scores.iou.size(); ++k)
      out << "  door " << request.doors.doors[k].id << ": IoU " << scores.iou[k] << std::endl;
    out << "mean IoU " << scores.mean_iou << ", IoU_tot " << scores.iou_total << std::endl;
  }
}

}  // namespace hidden_rooms::evaluation
