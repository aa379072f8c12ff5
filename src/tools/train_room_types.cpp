// train_room_types --environments DIR --out MODEL.yml [--folds K] [--repeats R]: trains the room type model on the
// labelled environments of DIR (each rendered with its doors open and segmented; a found room takes the label of the
// space that overlaps it most), reports its accuracy cross-validated by environment (the mean over R forest seeds),
// and writes the model trained on all.
#include <iomanip>
#include <iostream>
#include <algorithm>
#include <map>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/segmentation/room_graph.h"
#include "hidden_rooms/segmentation/room_types.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

struct Sample {
  int environment = 0;
  int type = 0;
};

// The type of each found room: that of the space overlapping it most, -1 when it has none.
std::vector<int> trueTypes(const segmentation::SegmentedFloor& floor, const cv::Mat1w& spaces,
                           const world::Environment& environment) {
  std::vector<std::map<int, int>> overlap(floor.rooms.size());
  for (int row = 0; row < spaces.rows; ++row)
    for (int col = 0; col < spaces.cols; ++col)
      if (floor.labels(row, col) != 0 && spaces(row, col) != 0) ++overlap[floor.labels(row, col) - 1][spaces(row, col)];
  std::vector<int> types;
  const std::vector<std::string>& names = segmentation::roomTypeNames();
  for (const auto& cells : overlap) {
    int best = 0;
    for (const auto& [space, count] : cells)
      if (best == 0 || count > cells.at(best)) best = space;
    const std::string type = best == 0 ? "" : segmentation::roomTypeOfLabel(environment.spaces[best - 1].label);
    types.push_back(type.empty() ? -1 : static_cast<int>(std::find(names.begin(), names.end(), type) - names.begin()));
  }
  return types;
}

int run(int argc, char** argv) {
  std::string environments_dir, out_path, method = "default";
  int folds = 5, repeats = 1;
  po::options_description options("Options");
  options.add_options()
      ("environments", po::value(&environments_dir)->required(), "folder of labelled environment XMLs (recursive)")
      ("out", po::value(&out_path)->required(), "the model file to write (OpenCV FileStorage YAML)")
      ("method", po::value(&method)->default_value(method), "segmentation method the rooms come from")
      ("folds", po::value(&folds)->default_value(folds), "cross-validation folds (environments split round robin)")
      ("repeats", po::value(&repeats)->default_value(repeats), "cross-validations, each with its own forest seed");
  po::variables_map values;
  if (!common::parseCommandLine(argc, argv,
                                "Usage: train_room_types --environments DIR --out MODEL.yml [--folds K] [--repeats R]\n"
                                "Trains the room type model and prints its accuracy per type, cross-validated by\n"
                                "environment (no environment's rooms are in the training set of its own fold).",
                                options, {}, &values))
    return common::kExitOk;
  if (folds < 2) throw common::InputError("--folds", "must be at least 2");
  if (repeats < 1) throw common::InputError("--repeats", "must be at least 1");
  const std::vector<std::string> paths = common::listFiles(environments_dir, ".xml", true);
  if (static_cast<int>(paths.size()) < folds) throw common::InputError(environments_dir, "has fewer environments than folds");

  segmentation::FloorSegmentationOptions floor_options;
  floor_options.method = method;
  floor_options.classify_rooms = false;
  cv::Mat1f features;
  std::vector<Sample> samples;
  for (size_t e = 0; e < paths.size(); ++e) {
    const world::Environment environment = world::loadEnvironment(paths[e]);
    const world::RenderedEnvironment rendered = world::renderEnvironment(environment, {});
    const segmentation::SegmentedFloor floor = segmentation::segmentFloor(rendered.map, {}, {}, floor_options);
    const cv::Mat1f rows = segmentation::roomFeatures(floor);
    const std::vector<int> types = trueTypes(floor, rendered.space_labels, environment);
    for (size_t i = 0; i < types.size(); ++i) {
      if (types[i] < 0) continue;
      features.push_back(rows.row(static_cast<int>(i)));
      samples.push_back({static_cast<int>(e), types[i]});
    }
  }

  // Cross-validation, once per forest seed: the accuracies are the means over the repeats.
  const std::vector<std::string>& names = segmentation::roomTypeNames();
  std::vector<int> total(names.size(), 0), correct(names.size(), 0);
  int kind_correct = 0;
  for (int repeat = 0; repeat < repeats; ++repeat) {
    for (int fold = 0; fold < folds; ++fold) {
      cv::Mat1f train_features, test_features;
      std::vector<int> train_types, test_types;
      for (size_t i = 0; i < samples.size(); ++i) {
        const bool test = samples[i].environment % folds == fold;
        (test ? test_features : train_features).push_back(features.row(static_cast<int>(i)));
        (test ? test_types : train_types).push_back(samples[i].type);
      }
      const std::vector<int> found =
          segmentation::RoomTypeClassifier::train(train_features, train_types, repeat + 1).classify(test_features);
      for (size_t i = 0; i < found.size(); ++i) {
        ++total[test_types[i]];
        correct[test_types[i]] += found[i] == test_types[i];
        kind_correct += (found[i] == 0) == (test_types[i] == 0);  // type 0: corridor
      }
    }
  }
  const double tested = static_cast<double>(samples.size()) * repeats;
  std::cout << std::fixed << std::setprecision(3) << samples.size() << " rooms of " << paths.size()
            << " environments, " << folds << "-fold cross-validation by environment, " << repeats
            << (repeats == 1 ? " forest seed\n" : " forest seeds (mean)\n");
  int all_correct = 0;
  for (size_t t = 0; t < names.size(); ++t) {
    all_correct += correct[t];
    std::cout << "  " << std::left << std::setw(10) << names[t] << std::right << std::setw(6) << total[t] / repeats
              << " rooms, accuracy " << (total[t] > 0 ? static_cast<double>(correct[t]) / total[t] : 0.0) << "\n";
  }
  std::cout << "  type accuracy " << all_correct / tested << ", corridor/room accuracy " << kind_correct / tested
            << "\n";

  const std::string text = segmentation::RoomTypeClassifier::train(features, [&] {
    std::vector<int> types;
    for (const Sample& sample : samples) types.push_back(sample.type);
    return types;
  }()).toText();
  common::writeTextAtomically(out_path, text, "room type model");
  std::cout << "model trained on all " << samples.size() << " rooms -> " << out_path << std::endl;
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("train_room_types", [&] { return run(argc, argv); });
}
