// The command-line tools as a user runs them: outputs on good input, a clear message and exit code 2 on bad.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "hidden_rooms/doors_file.h"
#include "hidden_rooms/occupancy_grid.h"
#include "test_util.h"

namespace hidden_rooms {
namespace {

using testing::runCommand;

const std::string kRender = RENDER_ENVIRONMENT_BIN;
const std::string kGenerate = GENERATE_WORLD_BIN;

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
  const OccupancyGrid map = loadMap(dir + "/out/map.yaml");
  EXPECT_DOUBLE_EQ(map.resolution, 0.1);
  EXPECT_EQ(map.width(), 120);
  const cv::Mat labels = cv::imread(dir + "/out/spaces.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(labels.size(), map.cells.size());
  double max_label = 0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  EXPECT_EQ(max_label, 3.0);
  const DoorsFile doors = loadDoors(dir + "/out/doors.yaml");
  ASSERT_EQ(doors.doors.size(), 1u);
  EXPECT_EQ(doors.doors[0].id, 2);
  EXPECT_FALSE(cv::imread(dir + "/out/preview.png").empty());
}

TEST(RenderEnvironmentTool, RendersASharedEnvironmentWithAllDoorsClosed) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::string dir = testing::makeTempDir("render_tool_shared");
  const auto result = runCommand(kRender + " " + testing::sharedDir() +
                                 "/data/environments/school/Sabadell1.xml --out " + dir + " --closed all");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_EQ(loadDoors(dir + "/doors.yaml").doors.size(), 17u);
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

TEST(Tools, HelpExitsZero) {
  EXPECT_EQ(runCommand(kRender + " --help").exit_code, 0);
  EXPECT_EQ(runCommand(kGenerate + " --help").exit_code, 0);
}

}  // namespace
}  // namespace hidden_rooms
