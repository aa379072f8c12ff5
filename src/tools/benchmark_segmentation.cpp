// benchmark_segmentation [--survey-maps DIR] [--environments DIR] --methods A,B [options]: scores room segmentation
// methods against ground truth with the survey's per-room recall and precision and Matthews' correlation
// coefficient, and times them. Survey maps: DIR/NAME.png (free: pixels above 250, as the survey reads them) with
// DIR/NAME_gt_segmentation.png; environments: every *.xml under DIR rendered with its doors open, the spaces as
// ground truth; explored maps: exploration runs, the spaces carried into each map by the run's fit.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <vector>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/segmentation/floor_output.h"
#include "hidden_rooms/segmentation/room_graph.h"
#include "hidden_rooms/segmentation/room_segmenter.h"
#include "hidden_rooms/segmentation/room_types.h"
#include "hidden_rooms/segmentation/segmentation_metrics.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace hidden_rooms;

namespace {

struct Case {
  std::string name;
  common::OccupancyGrid map;
  common::DoorsFile doors;  // closed doors (explored maps)
  cv::Mat1w truth;
  std::vector<std::string> truth_kinds;  // per truth label, "corridor" or "room"; empty: none known
  double free_iou = 1.0;  // explored maps: how well the map agrees with the building (exploration.yaml)
};

constexpr double kSurveyResolution = 0.05;  // metres per pixel of the survey's maps

std::vector<Case> surveyCases(const std::string& folder) {
  std::vector<Case> cases;
  const std::string suffix = "_gt_segmentation.png";
  for (const std::string& truth_path : common::listFiles(folder, suffix, false)) {
    const std::string map_path = truth_path.substr(0, truth_path.size() - suffix.size()) + ".png";
    Case each;
    each.name = fs::path(map_path).stem().string();
    const cv::Mat1b map = common::readGreyImage(map_path);
    const cv::Mat1b truth = common::readGreyImage(truth_path);
    if (map.size() != truth.size()) throw common::InputError(truth_path, "differs in size from " + map_path);
    each.map.resolution = kSurveyResolution;
    each.map.cells = cv::Mat_<int8_t>(map.size(), common::OccupancyGrid::kOccupied);
    each.map.cells.setTo(common::OccupancyGrid::kFree, map > 250);  // the survey's free pixels: white
    each.truth = segmentation::roomsFromBorderImage(truth);
    cases.push_back(each);
  }
  if (cases.empty()) throw common::InputError(folder, "holds no NAME_gt_segmentation.png");
  return cases;
}

// The labelled spaces of an environment: its ground truth (space labels, kinds) rendered with its doors open.
struct SpaceTruth {
  world::RenderedEnvironment rendered;
  std::vector<std::string> kinds;  // per space (label - 1): "corridor" or "room"
};

SpaceTruth spaceTruth(const std::string& path) {
  const world::Environment environment = world::loadEnvironment(path);
  SpaceTruth truth{world::renderEnvironment(environment, {}), {}};
  for (const world::Space& space : environment.spaces)
    truth.kinds.push_back(segmentation::toString(segmentation::roomKindOfLabel(space.label)));
  return truth;
}

std::vector<Case> environmentCases(const std::string& folder) {
  std::vector<Case> cases;
  for (const std::string& path : common::listFiles(folder, ".xml", true)) {
    SpaceTruth truth = spaceTruth(path);
    Case each;
    each.name = fs::path(path).stem().string();
    each.map = truth.rendered.map;
    each.truth = truth.rendered.space_labels;
    each.truth_kinds = truth.kinds;
    cases.push_back(each);
  }
  if (cases.empty()) throw common::InputError(folder, "holds no environment XML");
  return cases;
}

// Exploration runs (folders RUNS/NAME of explore_worlds or of the closed-door corpus's store: map.yaml, doors.yaml,
// exploration.yaml with the fitted world_from_map): each explored map with its closed doors (none when the run's
// run.yaml says no door was closed: the corpus store's doors.yaml then lists open doors), the spaces of environment
// NAME (an XML under one of `world_folders`) carried into the map by the fit, on the map's free cells (and on those
// up to 0.15 m off a space: the fit and the raster are off by a cell or two).
std::vector<Case> exploredCases(const std::string& runs, const std::vector<std::string>& world_folders) {
  std::map<std::string, std::string> worlds;
  for (const std::string& folder : world_folders)
    for (const std::string& path : common::listFiles(folder, ".xml", true)) worlds[fs::path(path).stem().string()] = path;
  std::vector<Case> cases;
  for (const std::string& fit_path : common::listFiles(runs, "/exploration.yaml", true)) {
    const std::string folder = fs::path(fit_path).parent_path().string();
    const std::string name = fs::path(folder).filename().string();
    if (!worlds.count(name)) throw common::InputError(folder, "names no environment of --worlds");
    const YAML::Node summary = common::loadYamlFile(fit_path, "exploration summary");
    const YAML::Node fit = summary["world_from_map"];
    if (!fit || !fit.IsSequence() || fit.size() != 3) throw common::InputError(fit_path, "has no world_from_map");
    const common::Pose2 world_from_map{fit[0].as<double>(), fit[1].as<double>(), fit[2].as<double>()};
    const SpaceTruth truth = spaceTruth(worlds.at(name));
    Case each;
    each.name = name;
    if (summary["free_iou"]) each.free_iou = summary["free_iou"].as<double>();
    each.map = common::trinary(common::loadMap(folder + "/map.yaml"));
    const bool doors_closed = !common::isFile(folder + "/run.yaml") ||
                              common::loadYamlFile(folder + "/run.yaml", "run summary")["closed"].as<std::string>("") != "";
    if (doors_closed) each.doors = common::loadDoors(folder + "/doors.yaml");
    each.truth_kinds = truth.kinds;
    const common::OccupancyGrid& world = truth.rendered.map;
    const cv::Mat1b free = each.map.cells == common::OccupancyGrid::kFree;
    cv::Mat1i spaces(free.size(), 0);
    for (int row = 0; row < each.map.height(); ++row)
      for (int col = 0; col < each.map.width(); ++col) {
        if (free(row, col) == 0) continue;
        const common::Point2 point = common::transformPoint(world_from_map, each.map.cellCentre(col, row));
        int world_col = 0, world_row = 0;
        if (world.cellOf(point, &world_col, &world_row)) spaces(row, col) = truth.rendered.space_labels(world_row, world_col);
      }
    // Free cells of the map that land on a wall of the rendering (the fit and the raster are off by a cell or two)
    // take the space next to them, up to 0.15 m away.
    segmentation::spreadLabels(free, &spaces, static_cast<int>(std::lround(0.15 / each.map.resolution)));
    spaces.convertTo(each.truth, CV_16U);
    cases.push_back(each);
  }
  if (cases.empty()) throw common::InputError(runs, "holds no exploration run (NAME/exploration.yaml)");
  return cases;
}

std::map<std::string, double> parseSettings(const std::vector<std::string>& settings) {
  std::map<std::string, double> values;
  for (const std::string& setting : settings) {
    const size_t equals = setting.find('=');
    size_t used = 0;
    double value = 0.0;
    try {
      if (equals != std::string::npos) value = std::stod(setting.substr(equals + 1), &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (equals == std::string::npos || used == 0 || equals + 1 + used != setting.size())
      throw common::InputError("--set", "'" + setting + "' is not NAME=NUMBER");
    values[setting.substr(0, equals)] = value;
  }
  return values;
}

int run(int argc, char** argv) {
  po::options_description options("Options");
  std::string survey_dir, environments_dir, explored_dir, worlds_text, methods_text = "default", params_path, only_text,
      out_dir;
  std::vector<std::string> settings;
  bool per_map = false;
  double min_free_iou = 0.0;
  segmentation::FloorSegmentationOptions floor_options;
  options.add_options()
      ("survey-maps", po::value(&survey_dir), "folder of NAME.png + NAME_gt_segmentation.png (the survey's maps)")
      ("environments", po::value(&environments_dir), "folder of environment XMLs (searched recursively)")
      ("explored", po::value(&explored_dir), "folder of exploration runs (explore_worlds' NAME/ folders)")
      ("worlds", po::value(&worlds_text), "comma-separated folders holding the explored environments' XMLs")
      ("min-free-iou", po::value(&min_free_iou)->default_value(0.0),
       "leave out exploration runs whose map agrees less with the building (exploration.yaml's free_iou)")
      ("methods", po::value(&methods_text)->default_value(methods_text), "comma-separated segmentation methods")
      ("params", po::value(&params_path), "parameter overrides: flat YAML of name: number")
      ("set", po::value(&settings)->composing(), "NAME=VALUE: one parameter override (repeatable, after --params)")
      ("only", po::value(&only_text), "comma-separated map names to score (default: all)")
      ("per-map", po::bool_switch(&per_map), "print every map's scores, not only the means")
      ("out", po::value(&out_dir),
       "folder for each map's labels (METHOD/NAME.png), pictures (METHOD/NAME_preview.png) and ground truth "
       "(truth/NAME.png)");
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: benchmark_segmentation [--survey-maps DIR] [--environments DIR]\n"
          "                              [--explored RUNS --worlds DIR,...] [--methods A,B]\n"
          "                              [--params FILE] [--set NAME=VALUE ...] [--only NAME,...] [--per-map]\n"
          "                              [--out DIR]\n"
          "Scores room segmentation methods against ground truth: the survey's per-room recall and precision\n"
          "(micro: mean over rooms, macro: pooled over cells), Matthews' correlation coefficient over pairs of\n"
          "cells, the seconds per map (segmentation and room graph), and on environments the share of rooms\n"
          "given the right kind (corridor or room; a corridor: a space labelled CORRIDOR) and of corridors found.",
          options, {}, &values))
    return common::kExitOk;
  if (survey_dir.empty() && environments_dir.empty() && explored_dir.empty())
    throw common::InputError("command line", "give --survey-maps, --environments and/or --explored");
  if (!explored_dir.empty() && worlds_text.empty())
    throw common::InputError("--explored", "needs --worlds, the folders of the explored environments' XMLs");
  std::map<std::string, double> overrides;
  if (!params_path.empty()) overrides = common::loadParameterFile(params_path);
  for (const auto& [name, value] : parseSettings(settings)) overrides[name] = value;
  std::vector<std::unique_ptr<segmentation::RoomSegmenter>> methods;
  for (const std::string& name : common::splitList(methods_text)) {
    methods.push_back(segmentation::makeRoomSegmenter(name));
    segmentation::resolveSegmenterParameters(*methods.back(), overrides);  // bad overrides fail before any work
  }
  const std::vector<std::string> only = common::splitList(only_text);

  std::vector<Case> cases;
  if (!survey_dir.empty()) cases = surveyCases(survey_dir);
  if (!environments_dir.empty())
    for (Case& each : environmentCases(environments_dir)) cases.push_back(std::move(each));
  if (!explored_dir.empty())
    for (Case& each : exploredCases(explored_dir, common::splitList(worlds_text))) cases.push_back(std::move(each));
  if (!only.empty()) {
    for (const std::string& name : only)
      if (std::none_of(cases.begin(), cases.end(), [&](const Case& each) { return each.name == name; }))
        throw common::InputError("--only", "no map named '" + name + "'");
    cases.erase(std::remove_if(cases.begin(), cases.end(),
                               [&](const Case& each) {
                                 return std::find(only.begin(), only.end(), each.name) == only.end();
                               }),
                cases.end());
  }
  // Explored maps that agree less with the building than --min-free-iou (SLAM drift that the run's one rigid fit
  // cannot follow, so that the spaces land off their rooms) are left out.
  const size_t before = cases.size();
  cases.erase(std::remove_if(cases.begin(), cases.end(), [&](const Case& each) { return each.free_iou < min_free_iou; }),
              cases.end());
  if (cases.size() < before)
    std::cout << "left out " << before - cases.size() << " exploration runs with free_iou below " << min_free_iou << "\n";
  if (cases.empty()) throw common::InputError("--min-free-iou", "leaves no map");
  if (!out_dir.empty()) {
    common::createOutputDirectory(out_dir + "/truth");
    for (const Case& each : cases) common::saveLabelImage(each.truth, out_dir + "/truth/" + each.name + ".png");
  }

  std::cout << std::fixed << std::setprecision(3);
  std::cout << std::left << std::setw(16) << "method" << std::setw(24) << "map" << std::right
            << "  rec_mi  pre_mi  rec_ma  pre_ma     mcc  rooms  found  seconds    kind corridor\n";
  const auto printRow = [&](const std::string& method, const std::string& map,
                            const segmentation::SegmentationScores& scores, double seconds,
                            const segmentation::LabelScores& kinds) {
    std::cout << std::left << std::setw(16) << method << std::setw(24) << map << std::right << std::setw(8)
              << scores.recall_micro << std::setw(8) << scores.precision_micro << std::setw(8) << scores.recall_macro
              << std::setw(8) << scores.precision_macro << std::setw(8) << scores.mcc << std::setw(7)
              << scores.truth_rooms << std::setw(7) << scores.found_rooms << std::setw(9) << seconds;
    if (kinds.rooms > 0)
      std::cout << std::setw(8) << kinds.accuracy() << std::setw(9) << kinds.recall("corridor");
    std::cout << "\n";
  };
  for (const auto& method : methods) {
    floor_options.method = method->name();
    floor_options.parameters = overrides;
    segmentation::SegmentationScores sum;
    segmentation::LabelScores kinds_sum;
    std::vector<double> seconds;
    for (const Case& each : cases) {
      const auto start = std::chrono::steady_clock::now();
      const segmentation::SegmentedFloor floor = segmentation::segmentFloor(each.map, each.doors, {}, floor_options);
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      const segmentation::SegmentationScores scores = segmentation::scoreSegmentation(floor.labels, each.truth);
      segmentation::LabelScores kinds;
      if (!each.truth_kinds.empty()) {
        std::vector<std::string> found_kinds;
        for (const segmentation::Room& room : floor.rooms) found_kinds.push_back(segmentation::toString(room.kind));
        kinds = segmentation::scoreRoomLabels(floor.labels, found_kinds, each.truth, each.truth_kinds);
      }
      if (!out_dir.empty()) {
        const std::string folder = out_dir + "/" + method->name();
        common::createOutputDirectory(folder);
        common::saveLabelImage(floor.labels, folder + "/" + each.name + ".png");
        common::writeImage(folder + "/" + each.name + "_preview.png", segmentation::floorPreview(floor, each.map));
      }
      if (per_map) printRow(method->name(), each.name, scores, seconds.back(), kinds);
      sum.recall_micro += scores.recall_micro;
      sum.precision_micro += scores.precision_micro;
      sum.recall_macro += scores.recall_macro;
      sum.precision_macro += scores.precision_macro;
      sum.mcc += scores.mcc;
      sum.truth_rooms += scores.truth_rooms;
      sum.found_rooms += scores.found_rooms;
      kinds_sum.rooms += kinds.rooms;
      kinds_sum.correct += kinds.correct;
      for (const auto& [label, counts] : kinds.per_label) {
        kinds_sum.per_label[label].first += counts.first;
        kinds_sum.per_label[label].second += counts.second;
      }
    }
    const double n = static_cast<double>(cases.size());
    sum.recall_micro /= n;
    sum.precision_micro /= n;
    sum.recall_macro /= n;
    sum.precision_macro /= n;
    sum.mcc /= n;
    std::sort(seconds.begin(), seconds.end());
    const double median = seconds.size() % 2 ? seconds[seconds.size() / 2]
                                             : 0.5 * (seconds[seconds.size() / 2 - 1] + seconds[seconds.size() / 2]);
    printRow(method->name(), "mean of " + std::to_string(cases.size()), sum, median, kinds_sum);
    std::cout << std::flush;
  }
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("benchmark_segmentation", [&] { return run(argc, argv); });
}
