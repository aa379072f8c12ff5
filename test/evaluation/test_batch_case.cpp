// The batch analysis's cases (batch_case.h) and the batch_cases tool.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/evaluation/batch_case.h"
#include "test_util.h"

namespace hidden_rooms::evaluation {
namespace {

const std::string kBatchCases = BATCH_CASES_BIN;

world::Environment corridorWorld() {
  return world::parseEnvironment(testing::corridorWithTwoRoomsXml(), "corridor.xml");
}

TEST(BatchCase, ErasesTheClosedRoomsAndScoresTheMethods) {
  const world::Environment environment = corridorWorld();
  const BatchCase one = makeBatchCase(environment, {2});
  ASSERT_EQ(one.input.closed_doors.doors.size(), 1u);
  EXPECT_EQ(one.input.closed_doors.doors[0].id, 2);
  // Room B is 6 m x 4 m of 10 m x 2 m + 4 m x 4 m + 6 m x 4 m: about 24 / 60 of the free cells.
  EXPECT_NEAR(one.hidden_percent, 40.0, 3.0);
  const cv::Mat1b room_b = one.input.true_rooms == 1;
  EXPECT_GT(cv::countNonZero(room_b), 0);
  EXPECT_EQ(cv::countNonZero((one.input.map.cells != common::OccupancyGrid::kUnknown) & room_b), 0);

  const BatchCase both = makeBatchCase(environment, {2, 1});
  ASSERT_EQ(both.input.closed_doors.doors.size(), 2u);
  EXPECT_EQ(both.input.closed_doors.doors[0].id, 1);  // environment order, as render_environment writes
  EXPECT_EQ(both.closed_door_numbers, (std::vector<int>{2, 1}));
  EXPECT_GT(both.hidden_percent, one.hidden_percent);

  for (const std::string& name : prediction::roomPredictorNames()) {
    const MethodOutcome outcome = runMethodOnCase(*prediction::makeRoomPredictor(name), both);
    EXPECT_EQ(outcome.method, name);
    EXPECT_TRUE(outcome.problem.empty()) << name << ": " << outcome.problem;
    ASSERT_EQ(outcome.scores.iou.size(), 2u) << name;
    EXPECT_GE(outcome.scores.mean_iou, 0.0);
    EXPECT_LE(outcome.scores.mean_iou, 1.0);
    EXPECT_GT(outcome.seconds, 0.0);
  }
  // With room A known, the unstructured baseline's bounding box holds room B.
  EXPECT_GT(runMethodOnCase(*prediction::makeRoomPredictor("unstructured"), one).scores.mean_iou, 0.5);
}

TEST(BatchCase, AMethodThatFailsScoresZeroWithItsProblem) {
  const BatchCase batch_case = makeBatchCase(corridorWorld(), {1});
  const MethodOutcome outcome =
      runMethodOnCase(*prediction::makeRoomPredictor("unstructured"), batch_case, {{"no_such_parameter", 1.0}});
  EXPECT_FALSE(outcome.problem.empty());
  EXPECT_EQ(outcome.scores.mean_iou, 0.0);
  EXPECT_EQ(outcome.scores.iou.size(), 1u);
}

TEST(BatchCase, BadDoorsThrow) {
  const world::Environment environment = corridorWorld();
  EXPECT_THROW(makeBatchCase(environment, {3}), common::InputError);     // no such door
  EXPECT_THROW(makeBatchCase(environment, {1, 1}), common::InputError);  // closed twice
}

TEST(BatchCase, FromACompleteMapMatchesTheRendering) {
  const world::Environment environment = corridorWorld();
  const world::RenderedEnvironment complete = world::renderEnvironment(environment, {});
  const cv::Mat complete_before = complete.map.cells.clone();
  common::DoorsFile doors_in_map;  // every door where the rendering puts it, in a frame shifted by (3, -2)
  common::OccupancyGrid shifted = complete.map;
  shifted.origin += common::Point2(3.0, -2.0);
  for (const world::Door& door : environment.doors) {
    common::MapDoor entry;
    entry.id = door.number;
    entry.position = door.centre + common::Point2(3.0, -2.0);
    doors_in_map.doors.push_back(entry);
  }
  const BatchCase from_map = makeBatchCaseFromMap(environment, shifted, doors_in_map, {2});
  const BatchCase rendered = makeBatchCase(environment, {2});
  EXPECT_EQ(cv::countNonZero(complete.map.cells != complete_before), 0);  // the caller's map is left alone
  ASSERT_EQ(from_map.input.closed_doors.doors.size(), 1u);
  EXPECT_NEAR(from_map.input.closed_doors.doors[0].position.x(), environment.doors[1].centre.x() + 3.0, 1e-9);
  const cv::Mat1b a = from_map.input.true_rooms == 1, b = rendered.input.true_rooms == 1;
  const double iou = static_cast<double>(cv::countNonZero(a & b)) / cv::countNonZero(a | b);
  EXPECT_GT(iou, 0.95);
  EXPECT_NEAR(from_map.hidden_percent, rendered.hidden_percent, 3.0);
  EXPECT_EQ(cv::countNonZero((from_map.input.map.cells != common::OccupancyGrid::kUnknown) & a), 0);
  const MethodOutcome outcome = runMethodOnCase(*prediction::makeRoomPredictor("unstructured"), from_map);
  EXPECT_GT(outcome.scores.mean_iou, 0.5) << outcome.problem;

  // A door with its own transform places its room by it: here the room behind door 2 is drawn 1 m further in x
  // than the door-centre fit puts it.
  common::DoorsFile drifted = doors_in_map;
  drifted.doors[1].map_from_world = common::Pose2{4.0, -2.0, 0.0};
  const BatchCase by_door = makeBatchCaseFromMap(environment, shifted, drifted, {2});
  const cv::Mat1b moved = by_door.input.true_rooms == 1;
  cv::Mat1b expected;
  const int cells = static_cast<int>(std::lround(1.0 / shifted.resolution));
  cv::Mat1b shifted_room = cv::Mat1b::zeros(a.size());
  a(cv::Rect(0, 0, a.cols - cells, a.rows)).copyTo(shifted_room(cv::Rect(cells, 0, a.cols - cells, a.rows)));
  const cv::Mat1b complete_free = shifted.cells == common::OccupancyGrid::kFree;
  expected = shifted_room & complete_free;
  EXPECT_GT(cv::countNonZero(moved & expected), 0.9 * cv::countNonZero(moved | expected));
  ASSERT_EQ(by_door.room_coverage.size(), 1u);
  ASSERT_EQ(from_map.room_coverage.size(), 1u);
  EXPECT_GT(from_map.room_coverage[0], 0.95);  // the map is the rendering: it shows (nearly) all of the room
  EXPECT_LE(from_map.room_coverage[0], 1.0);
  ASSERT_EQ(rendered.room_coverage.size(), 1u);
  EXPECT_GT(rendered.room_coverage[0], 0.95);

  common::DoorsFile one_door;
  one_door.doors.push_back(doors_in_map.doors[1]);
  EXPECT_THROW(makeBatchCaseFromMap(environment, shifted, one_door, {2}), common::InputError);
  EXPECT_THROW(makeBatchCaseFromMap(environment, shifted, doors_in_map, {3}), common::InputError);
}

TEST(BatchCasesTool, PrintsOneJsonLinePerCaseAndFailsClearly) {
  const std::string dir = testing::makeTempDir("batch_cases_tool");
  const std::string world = dir + "/world.xml";
  std::ofstream(world) << testing::corridorWithTwoRoomsXml();
  auto result = testing::runCommand(kBatchCases + " --help 2>&1");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("Methods: "), std::string::npos) << result.output;
  result = testing::runCommand(kBatchCases + " " + world + " --info 2>&1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("\"closable\": [1, 2]"), std::string::npos) << result.output;

  result = testing::runCommand(kBatchCases + " " + world + " --sequence 2,1 --methods unstructured,thesis --cases 2 "
                               "--write-cases " + dir + "/cases 2>&1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("{\"closed_doors\": 2, \"door_ids\": [2, 1]"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("\"unstructured\": {\"mean_iou\""), std::string::npos) << result.output;
  EXPECT_EQ(result.output.find("\"closed_doors\": 1,"), std::string::npos) << result.output;
  EXPECT_TRUE(std::filesystem::is_regular_file(dir + "/cases/2_doors/true_rooms.png"));
  EXPECT_TRUE(std::filesystem::is_regular_file(dir + "/cases/2_doors/map.yaml"));

  const std::vector<std::string> bad_arguments{" --sequence 1 --methods nope", " --sequence 7 --methods thesis",
                                               " --sequence 1 --methods thesis --cases 2", " --methods thesis"};
  for (const std::string& bad : bad_arguments) {
    result = testing::runCommand(kBatchCases + " " + world + bad + " 2>&1");
    EXPECT_EQ(result.exit_code, 2) << bad << ": " << result.output;
    EXPECT_NE(result.output.find("batch_cases: error:"), std::string::npos) << result.output;
  }
  std::ofstream(dir + "/bad.xml") << "<building><scale>";
  result = testing::runCommand(kBatchCases + " " + dir + "/bad.xml --info 2>&1");
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("bad.xml"), std::string::npos) << result.output;
}

// SIGKILL at times spread over a batch, each into the same --write-cases folder: every case file there is always
// complete (equal to an uninterrupted run's), and a re-run completes the folder without any temporary left over.
TEST(BatchCasesTool, SigkillLeavesNoPartialCaseFiles) {
  const std::string dir = testing::makeTempDir("batch_cases_sigkill");
  const auto read = testing::readFile;
  const auto run = [&](const std::string& out) {
    return testing::startProcess({kBatchCases, std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/worlds/medium_1.xml",
                                  "--sequence", "1,2,3,4,5,6", "--methods", "unstructured", "--write-cases", out},
                                 dir + "/log.txt");
  };
  double seconds = 1e9;  // the fastest of three runs: the kills are spread over it
  for (int k = 0; k < 3; ++k) {
    const auto start = std::chrono::steady_clock::now();
    ASSERT_EQ(testing::waitProcess(run(dir + "/reference")), 0) << read(dir + "/log.txt");
    seconds = std::min(seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  const std::vector<std::string> files{"doors.yaml", "map.pgm", "map.yaml", "true_rooms.png"};

  const std::string out = dir + "/out";
  constexpr int kAttempts = 16;
  const int killed = testing::killSpreadOver([&] { return run(out); }, seconds, kAttempts, [&](int attempt) {
    if (!std::filesystem::is_directory(out)) return;
    for (const std::string& case_dir : testing::fileNames(out))
      for (const std::string& name : testing::fileNames(out + "/" + case_dir)) {
        if (name.find(".partial") != std::string::npos) continue;  // the killed writer's temporary
        EXPECT_EQ(read(out + "/" + case_dir + "/" + name), read(dir + "/reference/" + case_dir + "/" + name))
            << "attempt " << attempt << ": " << case_dir << "/" << name << " is not complete";
      }
  });
  std::printf("%d of %d runs killed (run %.2f s)\n", killed, kAttempts, seconds);
  EXPECT_GE(killed, kAttempts / 4) << "too few runs were still running when killed";

  ASSERT_EQ(testing::waitProcess(run(out)), 0) << read(dir + "/log.txt");
  ASSERT_EQ(testing::fileNames(out), testing::fileNames(dir + "/reference"));
  for (const std::string& case_dir : testing::fileNames(out)) {
    EXPECT_EQ(testing::fileNames(out + "/" + case_dir), files) << case_dir;  // no temporary left
    for (const std::string& name : files)
      EXPECT_EQ(read(out + "/" + case_dir + "/" + name), read(dir + "/reference/" + case_dir + "/" + name))
          << case_dir << "/" << name;
  }
}

}  // namespace
}  // namespace hidden_rooms::evaluation
