// exploreOffline: the simulator, the RBPF mapper and the exploration policy in one process, on a corridor with
// two rooms: it explores until done, covers the reachable floor, is deterministic per seed and honours its stops.
#include <string>

#include <gtest/gtest.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/evaluation/door_translation.h"
#include "hidden_rooms/evaluation/map_quality.h"
#include "hidden_rooms/pipeline/offline_exploration.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"
#include "test_util.h"

namespace hidden_rooms::pipeline {
namespace {

const std::string kWorld = std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/test/data/simulator_corridor.xml";

OfflineExplorationOptions optionsWithConfig() {
  OfflineExplorationOptions options;
  options.mapper.config_file = std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/config/rbpf.ini";
  return options;
}

simulation::SimulationWorld corridorWorld(const std::set<int>& closed = {}) {
  return simulation::worldFromEnvironment(world::loadEnvironment(kWorld), closed);
}

TEST(OfflineExploration, ExploresTheCorridorAndBothRoomsUntilDone) {
  const world::Environment environment = world::loadEnvironment(kWorld);
  const OfflineExplorationResult result = exploreOffline(corridorWorld(), optionsWithConfig());
  EXPECT_EQ(result.stop, ExplorationStop::kDone);
  EXPECT_LT(result.simulated_seconds, 300.0);
  ASSERT_FALSE(result.map.empty());
  EXPECT_EQ(result.truth.size(), static_cast<size_t>(result.scans));
  EXPECT_EQ(result.estimate.size(), static_cast<size_t>(result.scans));
  EXPECT_GT(result.scans_inserted, 0);
  EXPECT_GT(result.goals, 0);

  // Coverage of the free floor the robot can reach, with the world placed by the trajectories.
  const world::RenderedEnvironment truth = world::renderEnvironment(environment, {});
  const common::Pose2 world_from_map = evaluation::fitWorldFromMap(result.truth, result.estimate);
  const common::Pose2 start = result.truth.front().pose;
  const cv::Mat1b reachable = evaluation::reachableFreeArea(truth.map, common::Point2(start.x, start.y), 0.25);
  const evaluation::MapQuality quality = evaluation::evaluateMap(result.map, world_from_map, truth.map, reachable);
  const double coverage = double(quality.intersection_cells) / double(quality.true_free_cells);
  std::printf("simulated %.1f s, %d scans (%d inserted), %d goals, coverage %.3f, free IoU %.3f\n",
              result.simulated_seconds, result.scans, result.scans_inserted, result.goals, coverage,
              quality.free_iou);
  EXPECT_GE(coverage, 0.95);
  EXPECT_GE(quality.free_iou, 0.90);
}

TEST(OfflineExploration, TheSameSeedGivesTheSameRun) {
  OfflineExplorationOptions options = optionsWithConfig();
  options.max_time = 30.0;
  options.simulation.seed = 7;
  options.mapper.seed = 7;
  const OfflineExplorationResult first = exploreOffline(corridorWorld(), options);
  const OfflineExplorationResult second = exploreOffline(corridorWorld(), options);
  ASSERT_EQ(first.map.cells.size(), second.map.cells.size());
  EXPECT_EQ(cv::countNonZero(first.map.cells != second.map.cells), 0);
  ASSERT_EQ(first.estimate.size(), second.estimate.size());
  EXPECT_DOUBLE_EQ(first.estimate.back().pose.x, second.estimate.back().pose.x);
  EXPECT_DOUBLE_EQ(first.truth.back().pose.y, second.truth.back().pose.y);
  EXPECT_EQ(first.goals, second.goals);
}

TEST(OfflineExploration, StopsAtMaxTimeAndWhenTheMapStopsGrowing) {
  OfflineExplorationOptions options = optionsWithConfig();
  options.max_time = 5.0;
  const OfflineExplorationResult short_run = exploreOffline(corridorWorld(), options);
  EXPECT_EQ(short_run.stop, ExplorationStop::kMaxTime);
  EXPECT_NEAR(short_run.simulated_seconds, 5.0, 1e-6);

  // No check can grow by 1000 %: the second check is the first without growth.
  options = optionsWithConfig();
  options.growth_interval = 4.0;
  options.growth = 10.0;
  options.patience = 1;
  const OfflineExplorationResult flat = exploreOffline(corridorWorld(), options);
  EXPECT_EQ(flat.stop, ExplorationStop::kNoGrowth);
  EXPECT_NEAR(flat.simulated_seconds, 8.0, 1e-6);
}

TEST(OfflineExploration, AClosedDoorKeepsItsRoomOutOfTheMap) {
  // Door 2 (door_b, at (7, 4)) closed: room B (x 4..10, y 0..4) stays unknown.
  const world::Environment environment = world::loadEnvironment(kWorld);
  const OfflineExplorationResult result =
      exploreOffline(corridorWorld({environment.findDoor("2")}), optionsWithConfig());
  EXPECT_EQ(result.stop, ExplorationStop::kDone);
  const common::Pose2 world_from_map = evaluation::fitWorldFromMap(result.truth, result.estimate);
  const common::Pose2 map_from_world = common::invertPose(world_from_map);
  int col = 0, row = 0;
  ASSERT_TRUE(result.map.cellOf(common::transformPoint(map_from_world, common::Point2(2.0, 2.0)), &col, &row));
  EXPECT_TRUE(result.map.cells(row, col) >= 0 && result.map.cells(row, col) <= 19) << "room A is explored";
  const bool inside = result.map.cellOf(common::transformPoint(map_from_world, common::Point2(7.0, 2.0)), &col, &row);
  EXPECT_TRUE(!inside || result.map.cells(row, col) < 0) << "room B behind the closed door is unknown";
}

TEST(OfflineExploration, RejectsBadOptions) {
  OfflineExplorationOptions options = optionsWithConfig();
  options.scan_period = 0.0;
  EXPECT_THROW(validate(options), common::InputError);
  options = optionsWithConfig();
  options.max_time = -1.0;
  EXPECT_THROW(exploreOffline(corridorWorld(), options), common::InputError);
  options = optionsWithConfig();
  options.patience = 0;
  EXPECT_THROW(validate(options), common::InputError);
  options = optionsWithConfig();
  options.mapper.config_file = "/nonexistent/rbpf.ini";
  EXPECT_THROW(exploreOffline(corridorWorld(), options), common::InputError);
}

}  // namespace
}  // namespace hidden_rooms::pipeline
