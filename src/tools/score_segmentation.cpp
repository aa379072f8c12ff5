// score_segmentation SEGMENTATION --truth TRUTH.png [--truth-borders] [--environment ENV.xml]: scores a room
// segmentation against ground truth (the survey's per-room recall and precision, Matthews' correlation coefficient)
// and, with the environment the ground truth comes from, its rooms' kinds and types against the environment's labels.
#include <yaml-cpp/yaml.h>

#include <iomanip>
#include <iostream>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/segmentation/room_types.h"
#include "hidden_rooms/segmentation/segmentation_metrics.h"
#include "hidden_rooms/world/environment.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

cv::Mat1w labelImage(const std::string& path) {
  const cv::Mat image = common::readImage(path);
  if (image.channels() != 1) throw common::InputError(path, "is not a label image (one grey channel)");
  cv::Mat1w labels;
  image.convertTo(labels, CV_16U);
  return labels;
}

// The kind and type of each room of a segment_rooms rooms.yaml, in label order.
void roomLabels(const std::string& path, std::vector<std::string>* kinds, std::vector<std::string>* types) {
  const YAML::Node rooms = common::loadYamlFile(path, "rooms file")["rooms"];
  if (!rooms || !rooms.IsSequence()) throw common::InputError(path, "has no 'rooms' list");
  try {
    for (size_t k = 0; k < rooms.size(); ++k) {
      if (rooms[k]["label"].as<size_t>() != k + 1)
        throw common::InputError(path, "rooms[" + std::to_string(k) + "] is not room " + std::to_string(k + 1));
      kinds->push_back(rooms[k]["kind"].as<std::string>());
      types->push_back(rooms[k]["type"] ? rooms[k]["type"].as<std::string>() : "");
    }
  } catch (const YAML::Exception& error) {
    throw common::InputError(path, "is malformed: " + error.msg);
  }
}

void printLabelScores(const std::string& name, const segmentation::LabelScores& scores) {
  std::cout << name << ":\n  rooms: " << scores.rooms << "\n  accuracy: " << scores.accuracy() << "\n  per_label:\n";
  for (const auto& [label, counts] : scores.per_label)
    std::cout << "    " << label << ": {rooms: " << counts.second << ", correct: " << counts.first << "}\n";
}

int run(int argc, char** argv) {
  std::string segmentation_path, truth_path, environment_path;
  bool truth_borders = false;
  po::options_description options("Options");
  options.add_options()
      ("segmentation", po::value(&segmentation_path)->required(),
       "a segment_rooms output folder (rooms.png, rooms.yaml) or a label image")
      ("truth", po::value(&truth_path)->required(), "ground truth: a label image (k on the cells of room k)")
      ("truth-borders", po::bool_switch(&truth_borders),
       "the ground truth is a map with the room borders drawn in black, as the survey's *_gt_segmentation.png")
      ("environment", po::value(&environment_path),
       "the environment XML of a label image from render_environment (label = 1 + space index): scores the kinds "
       "and types of a segment_rooms folder against the spaces' labels");
  po::positional_options_description positional;
  positional.add("segmentation", 1);
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: score_segmentation SEGMENTATION --truth TRUTH.png [--truth-borders] [--environment ENV.xml]\n"
          "Prints (YAML) the survey's per-room recall and precision (micro: mean over rooms, macro: pooled over\n"
          "cells; regions of up to 100 cells left out), Matthews' correlation coefficient over pairs of cells\n"
          "and, with --environment, the share of rooms given the right kind (corridor: a space labelled\n"
          "CORRIDOR) and type.",
          options, positional, &values))
    return common::kExitOk;

  const bool folder = common::isFolder(segmentation_path);
  const cv::Mat1w found = labelImage(folder ? segmentation_path + "/rooms.png" : segmentation_path);
  const cv::Mat1w truth = truth_borders ? segmentation::roomsFromBorderImage(common::readGreyImage(truth_path))
                                        : labelImage(truth_path);
  std::vector<std::string> kinds, types;
  if (folder) roomLabels(segmentation_path + "/rooms.yaml", &kinds, &types);
  if (!environment_path.empty() && !folder)
    throw common::InputError("--environment", "scores the labels of a segment_rooms folder, not of a label image");
  const segmentation::SegmentationScores scores = segmentation::scoreSegmentation(found, truth);
  std::cout << std::fixed << std::setprecision(4) << "truth_rooms: " << scores.truth_rooms
            << "\nfound_rooms: " << scores.found_rooms << "\nrecall_micro: " << scores.recall_micro
            << "\nprecision_micro: " << scores.precision_micro << "\nrecall_macro: " << scores.recall_macro
            << "\nprecision_macro: " << scores.precision_macro << "\nmcc: " << scores.mcc << "\n";
  if (!environment_path.empty()) {
    const world::Environment environment = world::loadEnvironment(environment_path);
    std::vector<std::string> truth_kinds, truth_types;
    for (const world::Space& space : environment.spaces) {
      truth_kinds.push_back(segmentation::toString(segmentation::roomKindOfLabel(space.label)));
      truth_types.push_back(segmentation::roomTypeOfLabel(space.label));
    }
    printLabelScores("kinds", segmentation::scoreRoomLabels(found, kinds, truth, truth_kinds));
    printLabelScores("types", segmentation::scoreRoomLabels(found, types, truth, truth_types));
  }
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("score_segmentation", [&] { return run(argc, argv); });
}
