// Pose logs, the door translation of docs/method.md#closed-doors-in-the-map, trajectory alignment and the truth
// moved into a map's grid.
#include <cmath>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/pose_log.h"
#include "hidden_rooms/common/range_scan.h"
#include "hidden_rooms/evaluation/door_translation.h"
#include "test_util.h"

namespace hidden_rooms::evaluation {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A robot driving an arc in the world, and the same run as the SLAM estimate in a map frame placed at
// `world_from_map`.
void arcRun(const common::Pose2& world_from_map, std::vector<common::TimedPose>* truth,
            std::vector<common::TimedPose>* estimate) {
  const common::Pose2 map_from_world = common::invertPose(world_from_map);
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.1 * k;
    const common::Pose2 world{2.0 + 3.0 * std::cos(0.1 * t), 1.0 + 3.0 * std::sin(0.1 * t), 0.1 * t + kPi / 2};
    truth->push_back({t, world});
    estimate->push_back({t, common::composePoses(map_from_world, world)});
  }
}

TEST(PoseLog, RoundTripsAndReadsFrames) {
  const std::string text = common::poseLogHeader("map", "base_link") + common::poseLogLine({1.0, {1.5, -2.0, 0.25}}) +
                           common::poseLogLine({1.1, {1.6, -2.0, 0.3}});
  const common::PoseLog log = common::parsePoseLog(text, "log");
  EXPECT_EQ(log.parent_frame, "map");
  EXPECT_EQ(log.child_frame, "base_link");
  ASSERT_EQ(log.poses.size(), 2u);
  EXPECT_DOUBLE_EQ(log.poses[0].pose.x, 1.5);
  EXPECT_DOUBLE_EQ(log.poses[1].pose.yaw, 0.3);
}

TEST(PoseLog, RejectsBadLogsNamingTheLine) {
  const auto problem = [](const std::string& text) {
    return testing::inputErrorMessage([&] { common::parsePoseLog(text, "bad.log"); });
  };
  EXPECT_NE(problem("# only a comment\n").find("no poses"), std::string::npos);
  EXPECT_NE(problem("0.0 1 2 3\n0.1 1 2\n").find("line 2"), std::string::npos);
  EXPECT_NE(problem("0.0 1 2 3 4\n").find("line 1"), std::string::npos);
  EXPECT_NE(problem("0.0 nan 2 3\n").find("line 1"), std::string::npos);
  EXPECT_NE(problem("0.2 1 2 3\n0.1 1 2 3\n").find("does not increase"), std::string::npos);
  EXPECT_THROW(common::loadPoseLog("/nonexistent/poses.log"), common::InputError);
}

TEST(PoseLog, PreparesAKilledLoggersLogForAppending) {
  const std::string dir = testing::makeTempDir("pose_log_append");
  const std::string path = dir + "/poses.log";
  EXPECT_EQ(common::preparePoseLogForAppend(path), -std::numeric_limits<double>::infinity());  // missing
  std::ofstream(path) << common::poseLogHeader("map", "base_link");
  EXPECT_EQ(common::preparePoseLogForAppend(path), -std::numeric_limits<double>::infinity());  // no pose yet
  // Killed while writing its third line.
  const std::string complete = common::poseLogHeader("map", "base_link") +
                               common::poseLogLine({1.0, {1.5, -2.0, 0.25}}) +
                               common::poseLogLine({1.1, {1.6, -2.0, 0.3}});
  std::ofstream(path, std::ios::trunc) << complete << "1.2000 1.70";
  EXPECT_DOUBLE_EQ(common::preparePoseLogForAppend(path), 1.1);
  std::ofstream(path, std::ios::app) << common::poseLogLine({1.2, {1.7, -2.0, 0.35}});
  const common::PoseLog continued = common::loadPoseLog(path);
  ASSERT_EQ(continued.poses.size(), 3u);
  EXPECT_DOUBLE_EQ(continued.poses[2].pose.x, 1.7);
  EXPECT_EQ(continued.parent_frame, "map");
  // Something else than a pose log is not continued.
  std::ofstream(path, std::ios::trunc) << "not a pose log\n";
  EXPECT_THROW(common::preparePoseLogForAppend(path), common::InputError);
}

TEST(PoseLog, InterpolatesPosesAndYawAcrossPi) {
  const std::vector<common::TimedPose> poses{{0.0, {0.0, 0.0, 3.0}}, {1.0, {1.0, 2.0, -3.0}}};
  const common::Pose2 middle = common::poseAt(poses, 0.5);
  EXPECT_NEAR(middle.x, 0.5, 1e-12);
  EXPECT_NEAR(middle.y, 1.0, 1e-12);
  EXPECT_NEAR(std::abs(middle.yaw), kPi, 1e-9);  // through pi, not through 0
  EXPECT_DOUBLE_EQ(common::poseAt(poses, -1.0).x, 0.0);
  EXPECT_DOUBLE_EQ(common::poseAt(poses, 5.0).x, 1.0);
  EXPECT_NEAR(pathLength(poses), std::sqrt(5.0), 1e-12);
}

TEST(DoorTranslation, EqualsTheThesisFormulaWhenFramesAreOnlyShifted) {
  std::vector<common::TimedPose> truth, estimate;
  arcRun({-1.0, 0.5, 0.0}, &truth, &estimate);
  const common::Point2 door(4.0, 4.0);
  const DoorInMap in_map = translateDoor(door, 0.0, truth, estimate);
  // M_d = M_r(t_min) + (GT_d - GT_r(t_min)) with the closest true pose.
  size_t closest = 0;
  for (size_t k = 1; k < truth.size(); ++k)
    if ((door - common::Point2(truth[k].pose.x, truth[k].pose.y)).norm() <
        (door - common::Point2(truth[closest].pose.x, truth[closest].pose.y)).norm())
      closest = k;
  const common::Point2 thesis = common::Point2(estimate[closest].pose.x, estimate[closest].pose.y) +
                                (door - common::Point2(truth[closest].pose.x, truth[closest].pose.y));
  EXPECT_NEAR((in_map.position - thesis).norm(), 0.0, 1e-9);
  EXPECT_NEAR((in_map.position - common::Point2(5.0, 3.5)).norm(), 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(in_map.time, truth[closest].time);
}

TEST(DoorTranslation, FollowsAMapFrameRotatedAgainstTheWorld) {
  std::vector<common::TimedPose> truth, estimate;
  const common::Pose2 world_from_map{3.0, -2.0, kPi / 2};
  arcRun(world_from_map, &truth, &estimate);
  world::Environment environment;
  world::Door door;
  door.number = 7;
  door.centre = common::Point2(4.5, 2.0);
  door.wall_angle = 0.0;  // the wall runs along the world's x: along the map's y
  environment.doors.push_back(door);
  const common::DoorsFile doors = translateDoors(environment, {0}, truth, estimate, 0.8);
  ASSERT_EQ(doors.doors.size(), 1u);
  EXPECT_EQ(doors.doors[0].id, 7);
  EXPECT_DOUBLE_EQ(doors.doors[0].width, 0.8);
  EXPECT_EQ(doors.doors[0].orientation, common::DoorOrientation::kAlongY);
  const common::Point2 expected = common::transformPoint(common::invertPose(world_from_map), door.centre);
  EXPECT_NEAR((doors.doors[0].position - expected).norm(), 0.0, 1e-9);
}

TEST(DoorTranslation, FitsTheWorldFromMapTransform) {
  std::vector<common::TimedPose> truth, estimate;
  const common::Pose2 world_from_map{3.0, -2.0, 0.7};
  arcRun(world_from_map, &truth, &estimate);
  const common::Pose2 fitted = fitWorldFromMap(truth, estimate);
  EXPECT_NEAR(fitted.x, 3.0, 1e-9);
  EXPECT_NEAR(fitted.y, -2.0, 1e-9);
  EXPECT_NEAR(fitted.yaw, 0.7, 1e-9);

  const std::vector<common::TimedPose> standing{{0.0, {1.0, 1.0, 0.0}}, {1.0, {1.0, 1.0, 0.0}}};
  EXPECT_THROW(fitWorldFromMap(standing, standing), common::InputError);
  EXPECT_THROW(fitWorldFromMap(truth, {{100.0, {0.0, 0.0, 0.0}}}), common::InputError);
}

TEST(DoorTranslation, FitsNearAPlaceWhereTheMapIsBent) {
  // The first half of the run mapped with one transform, the second half (x > 10) with another: the map is bent.
  const common::Pose2 first{1.0, 2.0, 0.0}, second{1.3, 2.1, 0.05};
  std::vector<common::TimedPose> truth, estimate;
  for (int k = 0; k <= 400; ++k) {
    const double t = 0.1 * k;
    const common::Pose2 world{0.5 * t, 0.2 * std::sin(0.3 * t), 0.0};
    truth.push_back({t, world});
    estimate.push_back({t, common::composePoses(common::invertPose(world.x <= 10.0 ? first : second), world)});
  }
  const common::Pose2 near_end = fitWorldFromMapNear(truth, estimate, common::Point2(18.0, 0.0), 5.0);
  EXPECT_NEAR(near_end.x, second.x, 1e-6);
  EXPECT_NEAR(near_end.yaw, second.yaw, 1e-6);
  const common::Pose2 near_start = fitWorldFromMapNear(truth, estimate, common::Point2(2.0, 0.0), 5.0);
  EXPECT_NEAR(near_start.y, first.y, 1e-6);
  // Nobody near: the whole run.
  const common::Pose2 nowhere = fitWorldFromMapNear(truth, estimate, common::Point2(100.0, 100.0), 5.0);
  const common::Pose2 whole = fitWorldFromMap(truth, estimate);
  EXPECT_DOUBLE_EQ(nowhere.x, whole.x);
}

TEST(DoorTranslation, ReachableFreeCellsStopAtWalls) {
  common::OccupancyGrid grid;
  grid.resolution = 0.1;
  grid.cells = cv::Mat_<int8_t>(20, 40, common::OccupancyGrid::kFree);
  grid.cells.col(20).setTo(common::OccupancyGrid::kOccupied);  // two rooms, no door
  grid.cells.row(0).setTo(common::OccupancyGrid::kUnknown);
  const cv::Mat1b reachable = reachableFreeArea(grid, common::Point2(0.55, 1.05));
  EXPECT_EQ(cv::countNonZero(reachable), 20 * 19);
  EXPECT_EQ(reachable(5, 30), 0);
  EXPECT_THROW(reachableFreeArea(grid, common::Point2(-1.0, 1.0)), common::InputError);
}

// Three rooms in a row, 2 m deep: a 1 m gap into the middle one, a 0.4 m gap on to the last. A robot 0.5 m wide
// (clearance 0.25 m) reaches the middle room but not the last; without a clearance every free cell counts.
TEST(DoorTranslation, ReachableAreaWithAClearanceStopsAtGapsNarrowerThanTheRobot) {
  common::OccupancyGrid grid;
  grid.resolution = 0.05;
  grid.cells = cv::Mat_<int8_t>(40, 180, common::OccupancyGrid::kFree);
  grid.cells.row(0).setTo(common::OccupancyGrid::kOccupied);
  grid.cells.row(39).setTo(common::OccupancyGrid::kOccupied);
  grid.cells.col(0).setTo(common::OccupancyGrid::kOccupied);
  grid.cells.col(179).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(60, 0, 2, 40)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(60, 10, 2, 20)).setTo(common::OccupancyGrid::kFree);  // 1 m gap
  grid.cells(cv::Rect(120, 0, 2, 40)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(120, 16, 2, 8)).setTo(common::OccupancyGrid::kFree);  // 0.4 m gap
  const common::Point2 start(1.0, 1.0);
  const cv::Mat1b all_free = reachableFreeArea(grid, start);
  EXPECT_EQ(cv::countNonZero(all_free), cv::countNonZero(grid.cells == common::OccupancyGrid::kFree));
  const cv::Mat1b robot = reachableFreeArea(grid, start, 0.25);
  EXPECT_EQ(cv::countNonZero(robot(cv::Rect(125, 0, 55, 40))), 0);  // the last room past the body poking in
  EXPECT_GT(cv::countNonZero(robot(cv::Rect(62, 0, 58, 40))), 0.9 * 58 * 38);  // the middle room, corners aside
  EXPECT_EQ(robot(20, 30), 255);
  EXPECT_EQ(cv::countNonZero(robot & (grid.cells != common::OccupancyGrid::kFree)), 0);
  EXPECT_THROW(reachableFreeArea(grid, start, -0.1), common::InputError);
}

// Two 2 m rooms side by side, with a wall 0.1 m thick at x = 2 m and a gap of `gap` metres in it centred at
// y = 1 m, drawn at `resolution` (a cell is a wall when its centre is in one, as the renderer draws).
common::OccupancyGrid twoRoomsWithAGap(double gap, double resolution) {
  common::OccupancyGrid grid;
  grid.resolution = resolution;
  const int cols = static_cast<int>(std::lround(4.2 / resolution));
  const int rows = static_cast<int>(std::lround(2.2 / resolution));
  grid.cells = cv::Mat_<int8_t>(rows, cols, common::OccupancyGrid::kFree);
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const common::Point2 centre = grid.cellCentre(col, row);
      const bool border = centre.x() < 0.1 || centre.x() > 4.1 || centre.y() < 0.1 || centre.y() > 2.1;
      const bool wall = std::abs(centre.x() - 2.1) < 0.05 && std::abs(centre.y() - 1.1) > 0.5 * gap;
      if (border || wall) grid.cells(row, col) = common::OccupancyGrid::kOccupied;
    }
  return grid;
}

// A door 0.47 m wide, drawn 0.50 m on a 5 cm grid, lets a body 0.5 m wide through there; decided on a 1 cm
// rendering it does not. A 0.56 m door passes on both.
TEST(DoorTranslation, ReachDecidedOnAFinerRenderingStopsAtADoorJustNarrowerThanTheBody) {
  const common::Point2 start(1.0, 1.0);
  const auto reaches_the_far_room = [](const cv::Mat1b& reached, const common::OccupancyGrid& grid) {
    int col = 0, row = 0;
    EXPECT_TRUE(grid.cellOf(common::Point2(3.2, 1.1), &col, &row));
    return reached(row, col) == 255;
  };
  const common::OccupancyGrid narrow = twoRoomsWithAGap(0.47, 0.05), narrow_fine = twoRoomsWithAGap(0.47, 0.01);
  EXPECT_TRUE(reaches_the_far_room(reachableFreeArea(narrow, start, 0.25), narrow));
  const cv::Mat1b decided_fine = reachableFreeArea(narrow, narrow_fine, start, 0.25);
  EXPECT_FALSE(reaches_the_far_room(decided_fine, narrow));
  EXPECT_EQ(decided_fine.size(), narrow.cells.size());
  EXPECT_GT(cv::countNonZero(decided_fine), 0.8 * 1.9 * 1.9 / (0.05 * 0.05));  // the start's room
  const common::OccupancyGrid wide = twoRoomsWithAGap(0.56, 0.05), wide_fine = twoRoomsWithAGap(0.56, 0.01);
  EXPECT_TRUE(reaches_the_far_room(reachableFreeArea(wide, wide_fine, start, 0.25), wide));
  // Only free cells of the coarse grid count.
  EXPECT_EQ(cv::countNonZero(decided_fine & (narrow.cells != common::OccupancyGrid::kFree)), 0);
}

TEST(DoorTranslation, MovesTheTrueRoomsIntoTheMapGrid) {
  const world::Environment environment =
      world::loadEnvironment(std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/worlds/small_1.xml");
  const std::vector<int> closable = world::closableDoors(environment);
  ASSERT_FALSE(closable.empty());
  const world::RenderedEnvironment rendered = world::renderEnvironment(environment, {closable.front()});
  // The map: the same grid placed 1 m further along x in the map frame (world = map - 1 m).
  common::OccupancyGrid map = rendered.map;
  map.origin += common::Point2(1.0, 0.0);
  const cv::Mat1w labels = spaceLabelsInMap(rendered, map, common::Pose2{-1.0, 0.0, 0.0});
  EXPECT_EQ(cv::countNonZero(labels != rendered.space_labels), 0);
  const cv::Mat1w rooms = trueRoomsInMap(environment, {closable.front()}, labels);
  const world::HiddenRoomsCase hidden = world::hideClosedRooms(environment, rendered);
  EXPECT_GT(cv::countNonZero(rooms), 0);
  EXPECT_EQ(cv::countNonZero(rooms != hidden.true_rooms), 0);
}

}  // namespace
}  // namespace hidden_rooms::evaluation
