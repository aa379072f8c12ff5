// The command-line tools as a user runs them: outputs on good input, a clear message and exit code 2 on bad.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>

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
  EXPECT_FALSE(std::filesystem::exists(dir + "/out"));
}

TEST(Tools, HelpExitsZero) {
  EXPECT_EQ(runCommand(kRender + " --help").exit_code, 0);
  EXPECT_EQ(runCommand(kGenerate + " --help").exit_code, 0);
  EXPECT_EQ(runCommand(kPredict + " --help").exit_code, 0);
}

}  // namespace
}  // namespace hidden_rooms
