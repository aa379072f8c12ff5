// The command-line tools as a user runs them: outputs on good input, a clear message and exit code 2 on bad.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>

#include <opencv2/imgcodecs.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "test_util.h"

namespace hidden_rooms {
namespace {

using testing::runCommand;

const std::string kRender = RENDER_ENVIRONMENT_BIN;
const std::string kGenerate = GENERATE_WORLD_BIN;
const std::string kPredict = PREDICT_ROOMS_OFFLINE_BIN;
const std::string kExport = EXPORT_OCTOMAP_BIN;
const std::string kSlice = SLICE_OCTOMAP_BIN;
const std::string kSegment = SEGMENT_ROOMS_BIN;
const std::string kScoreSegmentation = SCORE_SEGMENTATION_BIN;
const std::string kTrainRoomTypes = TRAIN_ROOM_TYPES_BIN;
const std::string kHideRooms = HIDE_ROOMS_BIN;

std::string writeSynthetic(const std::string& dir, const std::string& xml) {
  const std::string path = dir + "/world.xml";
  std::ofstream(path) << xml;
  return path;
}

TEST(RenderEnvironmentTool, WritesMapLabelsDoorsAndPreview) {
  const std::string dir = testing::makeTempDir("render_tool");
  const std::string world = writeSynthetic(dir, testing::corridorWithTwoRoomsXml());
  const auto result = runCommand(kRender + " " + world + " --out " + dir + "/out --closed 2 --resolution 0.1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("3 spaces, 2 doors (2 closable), 1 closed"), std::string::npos) << result.output;
  const common::OccupancyGrid map = common::loadMap(dir + "/out/map.yaml");
  EXPECT_DOUBLE_EQ(map.resolution, 0.1);
  EXPECT_EQ(map.width(), 120);
  const cv::Mat labels = cv::imread(dir + "/out/spaces.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(labels.size(), map.cells.size());
  double max_label = 0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  EXPECT_EQ(max_label, 3.0);
  const common::DoorsFile doors = common::loadDoors(dir + "/out/doors.yaml");
  ASSERT_EQ(doors.doors.size(), 1u);
  EXPECT_EQ(doors.doors[0].id, 2);
  EXPECT_FALSE(cv::imread(dir + "/out/preview.png").empty());
}

void expectBadInput(const std::string& command, const std::string& expected);

TEST(RenderEnvironmentTool, RendersASharedEnvironmentWithAllDoorsClosed) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::string dir = testing::makeTempDir("render_tool_shared");
  const auto result = runCommand(kRender + " " + testing::sharedDir() +
                                 "/data/environments/school/Sabadell1.xml --out " + dir + " --closed all");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_EQ(common::loadDoors(dir + "/doors.yaml").doors.size(), 17u);
  // Hiding the rooms needs closable doors: Sabadell1 has 12 of its 17.
  expectBadInput(kRender + " " + testing::sharedDir() + "/data/environments/school/Sabadell1.xml --out " + dir +
                       "/hidden --closed all --hide-closed-rooms",
                   "is not closable");
  const auto hidden = runCommand(kRender + " " + testing::sharedDir() +
                                 "/data/environments/school/Sabadell1.xml --out " + dir +
                                 "/hidden --closed closable --hide-closed-rooms");
  ASSERT_EQ(hidden.exit_code, 0) << hidden.output;
  const cv::Mat truth = cv::imread(dir + "/hidden/true_rooms.png", cv::IMREAD_UNCHANGED);
  double max_label = 0;
  cv::minMaxLoc(truth, nullptr, &max_label);
  EXPECT_EQ(max_label, 12.0);
  EXPECT_EQ(common::loadDoors(dir + "/hidden/doors.yaml").doors.size(), 12u);
}

// Each bad input: exit code 2 and a message naming the input and the problem.
void expectBadInput(const std::string& command, const std::string& expected) {
  const auto result = runCommand(command);
  EXPECT_EQ(result.exit_code, 2) << command << "\n" << result.output;
  EXPECT_NE(result.output.find(expected), std::string::npos) << command << "\n" << result.output;
}

TEST(RenderEnvironmentTool, BadInputGivesAClearErrorAndExitCode2) {
  const std::string dir = testing::makeTempDir("render_tool_errors");
  const std::string good = writeSynthetic(dir, testing::corridorWithTwoRoomsXml());
  std::ofstream(dir + "/broken.xml") << "<building><scale>";
  std::ofstream(dir + "/no_scale.xml") << "<building><floor><spaces/></floor></building>";
  expectBadInput(kRender + " " + dir + "/broken.xml --out " + dir + "/o", dir + "/broken.xml: malformed XML");
  expectBadInput(kRender + " " + dir + "/no_scale.xml --out " + dir + "/o", "missing <scale>");
  expectBadInput(kRender + " " + dir + "/absent.xml --out " + dir + "/o", "absent.xml: cannot open");
  expectBadInput(kRender + " " + good + " --out " + dir + "/o --closed 9", "no door '9'");
  expectBadInput(kRender + " " + good + " --out " + dir + "/o --resolution -0.05", "resolution must be positive");
  expectBadInput(kRender + " " + good, "--out");
  expectBadInput(kRender + " " + good + " --out " + good, "cannot create output folder");
  expectBadInput(kRender + " " + good + " --out " + dir + "/o --bogus", "unrecognised option");
  EXPECT_FALSE(std::filesystem::exists(dir + "/o/map.yaml"));
}

TEST(GenerateWorldTool, BadInputGivesAClearErrorAndExitCode2) {
  const std::string dir = testing::makeTempDir("generate_tool_errors");
  expectBadInput(kGenerate + " --seed 1 --size huge --out " + dir + "/w.xml", "huge");
  expectBadInput(kGenerate + " --seed 1 --size small", "--out");
}

// The synthetic hidden-room case written as files: DIR/case/map.yaml, DIR/case/doors.yaml, DIR/case/truth.png.
std::string syntheticCase(const std::string& dir) {
  common::OccupancyGrid map;
  common::DoorsFile doors;
  cv::Mat1w truth;
  testing::syntheticHiddenRoomA(&map, &doors, &truth);
  std::filesystem::create_directories(dir + "/case");
  common::saveMap(map, dir + "/case/map");
  common::saveDoors(doors, dir + "/case/doors.yaml");
  cv::Mat1b truth8;
  truth.convertTo(truth8, CV_8U);
  cv::imwrite(dir + "/case/truth.png", truth8);
  return dir + "/case";
}

TEST(PredictRoomsOfflineTool, WritesRoomsCompletedMapAndMetrics) {
  const std::string dir = testing::makeTempDir("predict_tool");
  const std::string input = syntheticCase(dir);
  // Door 2 of this file lies far outside the map: reported, scored 0, door 1 still predicted.
  std::ofstream(dir + "/doors.yaml") << "frame: map\ndoors:\n- {id: 1, position: [2.0, 4.0], width: 0.9, orientation: O}\n"
                                        "- {id: 7, position: [90.0, 4.0], width: 0.9, orientation: O}\n";
  std::ofstream(dir + "/params.yaml") << "start_search_radius: 1.5\nskewnormal_sigma: 3.0\n";
  const auto result = runCommand(kPredict + " --map " + input + "/map.yaml --doors " + dir + "/doors.yaml" +
                                 " --method unstructured --out " + dir + "/out --params " + dir + "/params.yaml" +
                                 " --gt-rooms " + input + "/truth.png");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("door 7 not placed: door position"), std::string::npos) << result.output;
  const cv::Mat rooms = cv::imread(dir + "/out/rooms.png", cv::IMREAD_UNCHANGED);
  EXPECT_GT(cv::countNonZero(rooms == 1), 1000);
  EXPECT_EQ(cv::countNonZero(rooms == 2), 0);
  const YAML::Node yaml = YAML::LoadFile(dir + "/out/rooms.yaml");
  EXPECT_EQ(yaml["rooms"].size(), 2u);
  EXPECT_TRUE(yaml["rooms"][0]["placed"].as<bool>());
  EXPECT_FALSE(yaml["rooms"][1]["placed"].as<bool>());
  EXPECT_GE(yaml["rooms"][0]["polygon"].size(), 3u);
  const common::OccupancyGrid completed = common::loadMap(dir + "/out/map.yaml");
  EXPECT_GT(cv::countNonZero(completed.cells == common::OccupancyGrid::kFree),
            cv::countNonZero(common::loadMap(input + "/map.yaml").cells == common::OccupancyGrid::kFree));
  const YAML::Node metrics = YAML::LoadFile(dir + "/out/metrics.yaml");
  ASSERT_EQ(metrics["rooms"].size(), 2u);
  EXPECT_GT(metrics["rooms"][0]["iou"].as<double>(), 0.9);
  EXPECT_DOUBLE_EQ(metrics["rooms"][1]["iou"].as<double>(), 0.0);
}

// rooms.yaml without its first lines (the computation time differs between runs).
std::string roomsPart(const std::string& rooms_yaml) {
  const size_t at = rooms_yaml.find("\nrooms:");
  return at == std::string::npos ? rooms_yaml : rooms_yaml.substr(at);
}

// SIGKILL at times spread over a run, each into the same folder: every output there is always complete (equal to
// an uninterrupted run's), and a re-run completes the folder without any temporary left over.
TEST(PredictRoomsOfflineTool, SigkillLeavesNoPartialOutputAndTheRerunCompletes) {
  const std::string dir = testing::makeTempDir("predict_tool_sigkill");
  ASSERT_EQ(runCommand(kRender + " " + HIDDEN_ROOMS_SOURCE_DIR + "/worlds/large_2.xml --out " + dir +
                       "/case --closed closable --hide-closed-rooms").exit_code, 0);
  const std::vector<std::string> arguments{kPredict, "--map", dir + "/case/map.yaml", "--doors",
                                           dir + "/case/doors.yaml", "--method", "default", "--gt-rooms",
                                           dir + "/case/true_rooms.png", "--out"};
  const auto run = [&](const std::string& out) {
    std::vector<std::string> command = arguments;
    command.push_back(out);
    return testing::startProcess(command, dir + "/log.txt");
  };
  double seconds = 1e9;  // the fastest of three runs: the kills are spread over it
  for (int k = 0; k < 3; ++k) {
    const auto start = std::chrono::steady_clock::now();
    ASSERT_EQ(testing::waitProcess(run(dir + "/reference")), 0) << testing::readFile(dir + "/log.txt");
    seconds = std::min(seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  const std::vector<std::string> outputs{"map.pgm", "map.yaml", "metrics.yaml", "overlay.png", "rooms.png", "rooms.yaml"};
  ASSERT_EQ(testing::fileNames(dir + "/reference"), outputs);

  const std::string out = dir + "/out";
  int cut_while_writing = 0;
  constexpr int kAttempts = 16;
  const int killed = testing::killSpreadOver([&] { return run(out); }, seconds, kAttempts, [&](int attempt) {
    if (!std::filesystem::is_directory(out)) return;
    int complete = 0;
    for (const std::string& name : testing::fileNames(out)) {
      if (name.find(".partial") != std::string::npos) continue;  // the killed writer's temporary
      ASSERT_NE(std::find(outputs.begin(), outputs.end(), name), outputs.end()) << name;
      const std::string expected = testing::readFile(dir + "/reference/" + name);
      const std::string written = testing::readFile(out + "/" + name);
      if (name == "rooms.yaml") {
        EXPECT_EQ(roomsPart(written), roomsPart(expected)) << "attempt " << attempt << ": " << name;
      } else {
        EXPECT_EQ(written, expected) << "attempt " << attempt << ": " << name << " is not complete";
      }
      ++complete;
    }
    cut_while_writing += complete > 0 && complete < static_cast<int>(outputs.size());
  });
  std::printf("%d of %d runs killed (run %.2f s), %d with some outputs written\n", killed, kAttempts, seconds,
              cut_while_writing);
  EXPECT_GE(killed, kAttempts / 4) << "too few runs were still running when killed";

  ASSERT_EQ(testing::waitProcess(run(out)), 0) << testing::readFile(dir + "/log.txt");
  EXPECT_EQ(testing::fileNames(out), outputs);  // no temporary left
  for (const std::string& name : outputs) {
    if (name == "rooms.yaml") continue;
    EXPECT_EQ(testing::readFile(out + "/" + name), testing::readFile(dir + "/reference/" + name)) << name;
  }
}

TEST(PredictRoomsOfflineTool, ScoresABenchmarkCase) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::string dir = testing::makeTempDir("predict_tool_benchmark");
  const std::string input = testing::sharedDir() + "/data/closed_door_benchmark/Sabadell1/03_doors";
  const auto result = runCommand(kPredict + " --map " + input + "/map.yaml --doors " + input + "/doors.yaml" +
                                 " --method unstructured --out " + dir + " --gt-rooms " + input + "/gt_rooms.png" +
                                 " --debug-dir " + dir + "/debug");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("mean IoU"), std::string::npos);
  EXPECT_GT(YAML::LoadFile(dir + "/metrics.yaml")["mean_iou"].as<double>(), 0.5);
}

TEST(PredictRoomsOfflineTool, BadInputGivesAClearErrorAndWritesNothing) {
  const std::string dir = testing::makeTempDir("predict_tool_errors");
  const std::string input = syntheticCase(dir);
  const std::string base = kPredict + " --map " + input + "/map.yaml --doors " + input + "/doors.yaml --out " + dir + "/out";
  std::ofstream(dir + "/typo.yaml") << "start_serach_radius: 2\n";
  std::ofstream(dir + "/bad_doors.yaml") << "doors:\n- {id: 1, position: [.nan, 2], width: 1, orientation: O}\n";
  cv::imwrite(dir + "/small_truth.png", cv::Mat1b::zeros(3, 3));
  expectBadInput(base + " --method oracle", "unknown prediction method 'oracle'");
  expectBadInput(base + " --method unstructured --params " + dir + "/typo.yaml", "unknown parameter 'start_serach_radius'");
  expectBadInput(base + " --method unstructured --gt-rooms " + dir + "/small_truth.png", "true rooms image is 3x3");
  expectBadInput(base + " --method unstructured --gt-rooms " + dir + "/absent.png", "cannot read");
  expectBadInput(kPredict + " --map " + dir + "/absent.yaml --doors " + input + "/doors.yaml --out " + dir +
                     "/out --method unstructured", "absent.yaml: cannot open map yaml");
  expectBadInput(kPredict + " --map " + input + "/map.yaml --doors " + dir + "/bad_doors.yaml --out " + dir +
                     "/out --method unstructured", "not finite");
  expectBadInput(base, "--method");
  cv::imwrite(dir + "/colour_truth.png", cv::Mat3b::zeros(60, 200));
  expectBadInput(base + " --method unstructured --gt-rooms " + dir + "/colour_truth.png", "a label image is grey");
  EXPECT_FALSE(std::filesystem::exists(dir + "/out"));
  // An --out that holds the input map: refused before anything is replaced.
  const std::string map_before = testing::readFile(input + "/map.pgm");
  expectBadInput(kPredict + " --map " + input + "/map.yaml --doors " + input + "/doors.yaml --method unstructured" +
                     " --out " + input,
                 "would replace the input");
  EXPECT_EQ(testing::readFile(input + "/map.pgm"), map_before);
  EXPECT_EQ(testing::fileNames(input), (std::vector<std::string>{"doors.yaml", "map.pgm", "map.yaml", "truth.png"}));
  // A blocked output name (map.pgm a folder): nothing is moved into place.
  std::filesystem::create_directories(dir + "/blocked/map.pgm");
  expectBadInput(kPredict + " --map " + input + "/map.yaml --doors " + input + "/doors.yaml --method unstructured" +
                     " --out " + dir + "/blocked",
                 "map.pgm: is a folder");
  EXPECT_EQ(testing::fileNames(dir + "/blocked"), std::vector<std::string>{"map.pgm"});
}

TEST(SegmentRoomsTool, SegmentsAPredictedCaseIntoRoomsGraphAndEnvironment) {
  const std::string dir = testing::makeTempDir("segment_tool");
  const std::string input = syntheticCase(dir);
  ASSERT_EQ(runCommand(kPredict + " --map " + input + "/map.yaml --doors " + input + "/doors.yaml --method default" +
                       " --out " + dir + "/prediction").exit_code, 0);
  const auto result = runCommand(kSegment + " " + input + "/map.yaml --doors " + input + "/doors.yaml --rooms " + dir +
                                 "/prediction/rooms.yaml --out " + dir + "/out");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("1 predicted"), std::string::npos) << result.output;
  EXPECT_EQ(testing::fileNames(dir + "/out"),
            (std::vector<std::string>{"preview.png", "rooms.png", "rooms.xml", "rooms.yaml"}));
  const YAML::Node rooms = YAML::LoadFile(dir + "/out/rooms.yaml");
  const cv::Mat labels = cv::imread(dir + "/out/rooms.png", cv::IMREAD_UNCHANGED);
  const common::OccupancyGrid map = common::loadMap(input + "/map.yaml");
  ASSERT_EQ(labels.size(), map.cells.size());
  double max_label = 0.0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  EXPECT_EQ(max_label, static_cast<double>(rooms["rooms"].size()));
  bool predicted_door = false;
  for (const YAML::Node& passage : rooms["passages"])
    predicted_door |= passage["kind"].as<std::string>() == "predicted" && passage["door_id"].as<int>() == 1;
  EXPECT_TRUE(predicted_door);
  // The environment XML reads back with the package's own reader.
  const auto rendered = runCommand(kRender + " " + dir + "/out/rooms.xml --out " + dir + "/rendered");
  EXPECT_EQ(rendered.exit_code, 0) << rendered.output;
}

TEST(ScoreSegmentationTool, ScoresARenderedEnvironmentsSegmentationAndItsLabels) {
  const std::string dir = testing::makeTempDir("score_segmentation_tool");
  const std::string world = writeSynthetic(dir, testing::corridorWithTwoRoomsXml());
  ASSERT_EQ(runCommand(kRender + " " + world + " --out " + dir + "/rendered").exit_code, 0);
  ASSERT_EQ(runCommand(kSegment + " " + dir + "/rendered/map.yaml --out " + dir + "/rooms").exit_code, 0);
  const auto result = runCommand(kScoreSegmentation + " " + dir + "/rooms --truth " + dir +
                                 "/rendered/spaces.png --environment " + world);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const YAML::Node scores = YAML::Load(result.output);
  EXPECT_EQ(scores["truth_rooms"].as<int>(), 3);
  EXPECT_GT(scores["recall_micro"].as<double>(), 0.97);
  EXPECT_GT(scores["precision_micro"].as<double>(), 0.97);
  EXPECT_GT(scores["mcc"].as<double>(), 0.95);
  EXPECT_EQ(scores["kinds"]["rooms"].as<int>(), 3);
  EXPECT_TRUE(scores["types"]["accuracy"].IsDefined());
  // The segmentation against itself, as a label image: perfect.
  const auto same = runCommand(kScoreSegmentation + " " + dir + "/rooms/rooms.png --truth " + dir + "/rooms/rooms.png");
  ASSERT_EQ(same.exit_code, 0) << same.output;
  EXPECT_DOUBLE_EQ(YAML::Load(same.output)["mcc"].as<double>(), 1.0);

  cv::imwrite(dir + "/small.png", cv::Mat1b::zeros(3, 3));
  expectBadInput(kScoreSegmentation + " " + dir + "/rooms --truth " + dir + "/small.png", "the ground truth 3x3");
  expectBadInput(kScoreSegmentation + " " + dir + "/rooms/rooms.png --truth " + dir + "/rendered/spaces.png" +
                     " --environment " + world, "not of a label image");
  expectBadInput(kScoreSegmentation + " " + dir + "/absent --truth " + dir + "/rendered/spaces.png", "absent");
}

// The shipped room type model is what train_room_types makes of the shared environments (training is seeded), so
// it cannot go stale when the segmentation or the features change.
TEST(TrainRoomTypesTool, TheShippedModelIsTheOneTrainedOnTheSharedEnvironments) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::string dir = testing::makeTempDir("train_room_types_tool");
  const auto result = runCommand(kTrainRoomTypes + " --environments " + testing::sharedDir() +
                                 "/data/environments --out " + dir + "/room_types.yml");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("corridor/room accuracy"), std::string::npos);
  EXPECT_TRUE(testing::readFile(dir + "/room_types.yml") ==
              testing::readFile(std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/models/room_types.yml"))
      << "models/room_types.yml is stale: train_room_types --environments ../shared/data/environments "
         "--out models/room_types.yml";
  expectBadInput(kTrainRoomTypes + " --environments " + dir + " --out " + dir + "/m.yml", "fewer environments");
}

TEST(SegmentRoomsTool, BadInputGivesAClearErrorAndWritesNothing) {
  const std::string dir = testing::makeTempDir("segment_tool_errors");
  const std::string input = syntheticCase(dir);
  std::ofstream(dir + "/far_doors.yaml") << "doors:\n- {id: 3, position: [90.0, 4.0], width: 0.9, orientation: O}\n";
  std::ofstream(dir + "/typo.yaml") << "pasage_ratio: 0.5\n";
  const std::string base = kSegment + " " + input + "/map.yaml --out " + dir + "/out";
  expectBadInput(base + " --doors " + dir + "/far_doors.yaml", "door 3: position (90, 4) is outside the map");
  expectBadInput(base + " --method watershed", "unknown segmentation method 'watershed'");
  expectBadInput(base + " --params " + dir + "/typo.yaml", "no segmentation method reads 'pasage_ratio'");
  expectBadInput(base + " --rooms " + dir + "/absent.yaml", "absent.yaml");
  expectBadInput(kSegment + " " + dir + "/absent.yaml --out " + dir + "/out", "absent.yaml: cannot open map yaml");
  common::OccupancyGrid walls = common::loadMap(input + "/map.yaml");
  walls.cells.setTo(common::OccupancyGrid::kOccupied);
  common::saveMap(walls, dir + "/walls");
  expectBadInput(kSegment + " " + dir + "/walls.yaml --out " + dir + "/out", "has no free cell");
  EXPECT_FALSE(std::filesystem::exists(dir + "/out"));
}

// A complete map (here a rendering, every door open) made into a closed-door case and predicted on.
TEST(HideRoomsTool, MakesAClosedDoorCaseOfACompleteMapThatPredictionsScoreOn) {
  const std::string dir = testing::makeTempDir("hide_rooms_tool");
  const std::string world = writeSynthetic(dir, testing::corridorWithTwoRoomsXml());
  ASSERT_EQ(runCommand(kRender + " " + world + " --out " + dir + "/rendered").exit_code, 0);
  const auto result = runCommand(kHideRooms + " " + dir + "/rendered/map.yaml --out " + dir + "/case");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("2 of 3 rooms hidden"), std::string::npos) << result.output;
  EXPECT_EQ(testing::fileNames(dir + "/case"),
            (std::vector<std::string>{"doors.yaml", "gt_rooms.png", "map.pgm", "map.yaml"}));
  EXPECT_EQ(common::loadDoors(dir + "/case/doors.yaml").doors.size(), 2u);
  const auto predicted = runCommand(kPredict + " --map " + dir + "/case/map.yaml --doors " + dir +
                                    "/case/doors.yaml --method default --out " + dir + "/prediction --gt-rooms " +
                                    dir + "/case/gt_rooms.png");
  ASSERT_EQ(predicted.exit_code, 0) << predicted.output;
  const YAML::Node metrics = YAML::LoadFile(dir + "/prediction/metrics.yaml");
  std::printf("mean IoU on the case: %.3f\n", metrics["mean_iou"].as<double>());
  EXPECT_GT(metrics["mean_iou"].as<double>(), 0.6);

  const std::string base = kHideRooms + " " + dir + "/rendered/map.yaml --out " + dir + "/bad";
  expectBadInput(base + " --max-rooms -1", "--max-rooms: must be 0 or more");
  expectBadInput(base + " --max-door-width 0.3", "has no closable room");
  expectBadInput(kHideRooms + " " + dir + "/absent.yaml --out " + dir + "/bad", "absent.yaml: cannot open map yaml");
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad"));
}

// Oversized inputs, each tool run with its address space limited to 2 GB: exit 2 and a message naming the limit
// (before, an image declaring 1e10 pixels aborted the map readers, --height 100 took 23 GB, 5000 doors 4.8 GB).
TEST(Tools, OversizedInputsAreRefusedWithinTwoGigabytes) {
  const std::string dir = testing::makeTempDir("tools_oversized");
  const std::string input = syntheticCase(dir);
#ifdef __SANITIZE_ADDRESS__
  const std::string limited;  // AddressSanitizer reserves terabytes of address space for its shadow memory
#else
  const std::string limited = "ulimit -v 2000000; ";
#endif
  // 45 bytes of PNG declaring 100000 x 100000 pixels, as a map and as true rooms.
  const unsigned char png[] = {0x89, 'P',  'N',  'G',  0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 'I',  'H',  'D',
                               'R',  0x00, 0x01, 0x86, 0xa0, 0x00, 0x01, 0x86, 0xa0, 0x08, 0x00, 0x00, 0x00, 0x00, 0x8d,
                               0x39, 0x54, 0x14, 0x00, 0x00, 0x00, 0x00, 'I',  'D',  'A',  'T',  0x35, 0xaf, 0x06, 0x1e};
  std::ofstream(dir + "/huge.png", std::ios::binary).write(reinterpret_cast<const char*>(png), sizeof(png));
  std::ofstream(dir + "/huge.yaml") << "image: huge.png\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                       "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
  std::ofstream crowd(dir + "/crowd.yaml");
  crowd << "frame: map\ndoors:\n";
  for (int id = 1; id <= 5000; ++id) crowd << "- {id: " << id << ", position: [1, 1], width: 0.9, orientation: O}\n";
  crowd.close();
  const std::string out = " --out " + dir + "/out";
  const std::string pixels = "more than the limit of 25000000 pixels";
  for (const std::string method : {"default", "thesis"}) {
    const std::string predict = limited + kPredict + " --method " + method + out;
    expectBadInput(predict + " --map " + dir + "/huge.yaml --doors " + input + "/doors.yaml", pixels);
    expectBadInput(predict + " --map " + input + "/map.yaml --doors " + dir + "/crowd.yaml",
                   "the number of doors is 5000, more than the limit of 500");
    expectBadInput(predict + " --map " + input + "/map.yaml --doors " + input + "/doors.yaml --gt-rooms " + dir +
                       "/huge.png",
                   pixels);
  }
  expectBadInput(limited + kExport + " " + dir + "/huge.yaml --out " + dir + "/out/map.bt", pixels);
  for (const std::string height : {"100000", "1e9"})
    expectBadInput(limited + kExport + " " + input + "/map.yaml --height " + height + " --out " + dir + "/out/map.bt",
                   "more than the limit of 200000000: lower --height");
  ASSERT_EQ(runCommand(kExport + " " + input + "/map.yaml --out " + dir + "/tree/map.bt").exit_code, 0);
  expectBadInput(limited + kSlice + " " + dir + "/tree/map.bt --resolution 0.0001" + out + "/map.yaml",
                 "more than the limit of 25000000: slice it at a coarser resolution");
  expectBadInput(limited + kRender + " " + HIDDEN_ROOMS_SOURCE_DIR + "/worlds/large_2.xml --resolution 0.001" + out,
                 "the map's number of cells is");
  EXPECT_FALSE(std::filesystem::exists(dir + "/out"));
}

// One random corruption of a file's text: bytes flipped or inserted, the text cut, a number replaced by an extreme
// value, a line deleted or repeated.
std::string corrupted(const std::string& text, std::mt19937* random) {
  std::string result = text;
  const auto position = [&](size_t size) { return std::uniform_int_distribution<size_t>(0, size)(*random); };
  const auto byte = [&] { return static_cast<char>(std::uniform_int_distribution<int>(0, 255)(*random)); };
  switch (std::uniform_int_distribution<int>(0, 5)(*random)) {
    case 0:
      for (int k = std::uniform_int_distribution<int>(1, 8)(*random); k > 0 && !result.empty(); --k)
        result[position(result.size() - 1)] = byte();
      break;
    case 1:
      result.resize(position(result.size()));
      break;
    case 2:
      result.insert(position(result.size()), std::string(std::uniform_int_distribution<int>(1, 16)(*random), byte()));
      break;
    case 3: {  // a number replaced by an extreme value
      static const std::vector<std::string> extremes{"1e308", "-1e308", "nan", "inf", "-0", "0", "4294967296",
                                                     "-7",    "1e-300", "99999999999999999999"};
      std::vector<size_t> numbers;
      for (size_t i = 0; i < result.size(); ++i)
        if (std::isdigit(static_cast<unsigned char>(result[i])) && (i == 0 || !std::isalnum(static_cast<unsigned char>(result[i - 1]))))
          numbers.push_back(i);
      if (numbers.empty()) break;
      const size_t start = numbers[position(numbers.size() - 1)];
      size_t end = start;
      while (end < result.size() && (std::isalnum(static_cast<unsigned char>(result[end])) || result[end] == '.')) ++end;
      result.replace(start, end - start, extremes[position(extremes.size() - 1)]);
      break;
    }
    default: {  // a line deleted (4) or repeated (5)
      std::vector<size_t> starts{0};
      for (size_t i = 0; i + 1 < result.size(); ++i)
        if (result[i] == '\n') starts.push_back(i + 1);
      const size_t line = position(starts.size() - 1);
      const size_t begin = starts[line], end = line + 1 < starts.size() ? starts[line + 1] : result.size();
      const std::string text_of_line = result.substr(begin, end - begin);
      if (result.size() > 0 && std::uniform_int_distribution<int>(0, 1)(*random) == 0)
        result.erase(begin, end - begin);
      else
        result.insert(begin, text_of_line);
    }
  }
  return result;
}

// A few hundred seeded random corruptions of good inputs, each fed to a command-line tool with its address space
// limited to 2 GB: the tool exits 0 or 2, on exit 2 with exactly one line on stderr and no output left behind.
TEST(Tools, RandomCorruptionsOfGoodInputsExitZeroOrTwoWithOneLineAndNoPartialOutput) {
  const std::string dir = testing::makeTempDir("tools_corruptions");
  const std::string input = syntheticCase(dir);
  ASSERT_EQ(runCommand(kPredict + " --map " + input + "/map.yaml --doors " + input + "/doors.yaml --method default" +
                       " --out " + dir + "/prediction").exit_code, 0);
  ASSERT_EQ(runCommand(kExport + " " + input + "/map.yaml --out " + dir + "/tree.bt").exit_code, 0);
  const std::string world = dir + "/world.xml";
  std::ofstream(world) << testing::corridorWithTwoRoomsXml();
  ASSERT_EQ(runCommand(kRender + " " + world + " --out " + dir + "/rendered").exit_code, 0);  // every door open
  std::ofstream(dir + "/params.yaml") << "start_search_radius: 1.5\nwall_margin: 2\n";

  struct Target {
    std::string tool, file;                  // the tool and the input file corrupted (a copy of it)
    std::function<std::string(const std::string&)> command;  // the command line, given the corrupted copy's path
    std::string output;                      // what the tool writes (must be absent after exit 2)
  };
  const std::string out = dir + "/out";
  const std::string case_files = " --doors " + input + "/doors.yaml --out " + out;
  const std::vector<Target> targets{
      {"predict map.yaml", input + "/map.yaml",
       [&](const std::string& f) { return kPredict + " --method default --map " + f + case_files; }, out},
      {"predict map.pgm", input + "/map.pgm",
       [&](const std::string& f) {
         std::ofstream(dir + "/c/map.yaml") << "image: " + f + "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                               "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
         return kPredict + " --method thesis --map " + dir + "/c/map.yaml" + case_files;
       },
       out},
      {"predict doors.yaml", input + "/doors.yaml",
       [&](const std::string& f) {
         return kPredict + " --method default --map " + input + "/map.yaml --doors " + f + " --out " + out;
       },
       out},
      {"predict params", dir + "/params.yaml",
       [&](const std::string& f) { return kPredict + " --method structured --map " + input + "/map.yaml --params " + f + case_files; },
       out},
      {"export rooms.yaml", dir + "/prediction/rooms.yaml",
       [&](const std::string& f) { return kExport + " " + input + "/map.yaml --rooms " + f + " --out " + out + ".ot"; },
       out + ".ot"},
      {"slice tree.bt", dir + "/tree.bt",
       [&](const std::string& f) { return kSlice + " " + f + " --out " + out + "/map.yaml"; }, out},
      {"render world.xml", world,
       [&](const std::string& f) { return kRender + " " + f + " --closed all --hide-closed-rooms --out " + out; }, out},
      {"hide_rooms map.pgm", dir + "/rendered/map.pgm",
       [&](const std::string& f) {
         std::ofstream(dir + "/c/rendered.yaml") << "image: " + f + "\nresolution: 0.05\norigin: [0, 0, 0]\n"
                                                    "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
         return kHideRooms + " " + dir + "/c/rendered.yaml --out " + out;
       },
       out},
  };
#ifdef __SANITIZE_ADDRESS__
  const std::string limited;  // AddressSanitizer reserves terabytes of address space for its shadow memory
#else
  const std::string limited = "ulimit -v 2000000; ";
#endif
  constexpr int kPerTarget = 40;
  std::mt19937 random(20261203);
  std::map<std::string, std::array<int, 2>> handled;  // exits 0 and 2 per target
  std::filesystem::create_directories(dir + "/c");
  std::filesystem::copy_file(input + "/map.pgm", dir + "/c/map.pgm");  // the image of the corrupted map.yaml copies
  for (const Target& target : targets) {
    const std::string original = testing::readFile(target.file);
    ASSERT_FALSE(original.empty()) << target.file;
    const std::string copy = dir + "/c/" + std::filesystem::path(target.file).filename().string();
    for (int k = 0; k < kPerTarget; ++k) {
      std::ofstream(copy, std::ios::binary) << corrupted(original, &random);
      std::filesystem::remove_all(target.output);
      const std::string command = target.command(copy);
      const auto result = runCommand("{ (" + limited + command + ") 2>&1 >/dev/null; }");  // stderr only
      const std::string context = target.tool + " #" + std::to_string(k) + ": " + command + "\n" + result.output;
      ASSERT_TRUE(result.exit_code == 0 || result.exit_code == 2) << context;
      if (result.exit_code == 2) {
        EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << context;
        EXPECT_FALSE(std::filesystem::exists(target.output)) << context;
      }
      ++handled[target.tool][result.exit_code == 0 ? 0 : 1];
    }
  }
  for (const auto& [tool, counts] : handled)
    std::printf("%-20s %d corruptions: exit 0 %d, exit 2 %d\n", tool.c_str(), counts[0] + counts[1], counts[0],
                counts[1]);
}

TEST(Tools, HelpExitsZero) {
  EXPECT_EQ(runCommand(kRender + " --help").exit_code, 0);
  EXPECT_EQ(runCommand(kGenerate + " --help").exit_code, 0);
  EXPECT_EQ(runCommand(kPredict + " --help").exit_code, 0);
  EXPECT_EQ(runCommand(kSegment + " --help").exit_code, 0);
  EXPECT_EQ(runCommand(kScoreSegmentation + " --help").exit_code, 0);
  EXPECT_EQ(runCommand(kHideRooms + " --help").exit_code, 0);
}

}  // namespace
}  // namespace hidden_rooms
