// Frontier extraction (groups, small ones and unknown specks dropped) and the nearest-frontier goal by path cost.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/exploration/frontier.h"
#include "hidden_rooms/exploration/grid_planner.h"

namespace hidden_rooms::exploration {
namespace {

// 0.1 m cells, origin (0, 0); the whole grid unknown.
common::OccupancyGrid unknownGrid(int cols, int rows) {
  common::OccupancyGrid grid;
  grid.resolution = 0.1;
  grid.cells = cv::Mat_<int8_t>(rows, cols, common::OccupancyGrid::kUnknown);
  return grid;
}

TEST(Frontier, EmptyMapHasNone) {
  const FrontierMap frontiers = findFrontiers(common::OccupancyGrid());
  EXPECT_TRUE(frontiers.frontiers.empty());
}

TEST(Frontier, FullyKnownRoomHasNone) {
  common::OccupancyGrid grid = unknownGrid(30, 20);
  grid.cells.setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(1, 1, 28, 18)).setTo(common::OccupancyGrid::kFree);
  EXPECT_TRUE(findFrontiers(grid).frontiers.empty());
}

TEST(Frontier, GroupsTwoOpeningsAndDropsSmallOnes) {
  // A walled free room (cols 5..24, rows 5..14) in unknown space with two gaps in its walls: 6 cells on the left
  // wall and 2 cells on the right wall, which is below min_frontier_cells.
  common::OccupancyGrid grid = unknownGrid(40, 20);
  grid.cells(cv::Rect(4, 4, 22, 12)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(5, 5, 20, 10)).setTo(common::OccupancyGrid::kFree);
  grid.cells(cv::Rect(4, 7, 1, 6)).setTo(common::OccupancyGrid::kFree);   // left gap: rows 7..12
  grid.cells(cv::Rect(25, 9, 1, 2)).setTo(common::OccupancyGrid::kFree);  // right gap: rows 9..10
  FrontierOptions options;
  options.min_frontier_cells = 4;
  const FrontierMap frontiers = findFrontiers(grid, options);
  ASSERT_EQ(frontiers.frontiers.size(), 1u);
  const Frontier& left = frontiers.frontiers[0];
  EXPECT_EQ(left.label, 1);
  EXPECT_EQ(left.cells.size(), 6u);  // the gap cells touch unknown on their left
  EXPECT_NEAR(left.centroid.x(), 0.45, 1e-9);
  EXPECT_NEAR(left.centroid.y(), 1.0, 1e-9);  // rows 7..12 of 20 -> y from 1.25 down to 0.75
  for (const cv::Point& cell : left.cells) EXPECT_EQ(frontiers.labels(cell.y, cell.x), 1);
  EXPECT_EQ(frontiers.labels(10, 25), 0);

  options.min_frontier_cells = 2;
  const FrontierMap with_small = findFrontiers(grid, options);
  ASSERT_EQ(with_small.frontiers.size(), 2u);
  EXPECT_EQ(with_small.frontiers[0].cells.size(), 6u);  // largest first
  EXPECT_EQ(with_small.frontiers[1].cells.size(), 2u);
}

TEST(Frontier, IgnoresUnknownSpecksAndCountsTheGridEdgeAsUnknown) {
  common::OccupancyGrid grid = unknownGrid(30, 20);
  grid.cells.setTo(common::OccupancyGrid::kFree);
  grid.cells(cv::Rect(10, 10, 2, 2)).setTo(common::OccupancyGrid::kUnknown);  // a 4-cell speck
  FrontierOptions options;
  options.min_unknown_cells = 5;
  options.min_frontier_cells = 1;
  const FrontierMap frontiers = findFrontiers(grid, options);
  // Only the free border (beyond which nothing is known): one ring of 2 * 30 + 2 * 18 cells.
  ASSERT_EQ(frontiers.frontiers.size(), 1u);
  EXPECT_EQ(frontiers.frontiers[0].cells.size(), 96u);
  EXPECT_EQ(frontiers.labels(9, 10), 0);

  options.min_unknown_cells = 4;
  EXPECT_EQ(findFrontiers(grid, options).frontiers.size(), 2u);  // now the speck's 8-cell ring counts
}

TEST(Frontier, UncertainCellsCountAsUnknown) {
  // A free room whose right part (cols 20..29) was seen too rarely to be free or occupied (value 40).
  common::OccupancyGrid grid = unknownGrid(30, 20);
  grid.cells.setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(1, 1, 28, 18)).setTo(common::OccupancyGrid::kFree);
  grid.cells(cv::Rect(20, 1, 9, 18)).setTo(40);
  const FrontierMap frontiers = findFrontiers(grid);
  ASSERT_EQ(frontiers.frontiers.size(), 1u);
  EXPECT_EQ(frontiers.frontiers[0].cells.size(), 18u);  // column 19
  for (const cv::Point& cell : frontiers.frontiers[0].cells) EXPECT_EQ(cell.x, 19);
}

TEST(Frontier, FreeCellsAtAWallTheLaserSeesAreNoFrontier) {
  // A free room (cols 5..24, rows 2..17) in unknown space. Its right wall (col 25) is drawn with holes in rows
  // 5..12, as passes with slightly different pose estimates leave it; its left wall has a real opening (rows
  // 7..12). The robot at (1.5, 1.0) sees the right wall at x = 2.55 behind the holes; its beams through the
  // opening end 4.5 m away (beyond seen_wall_range).
  common::OccupancyGrid grid = unknownGrid(40, 20);
  grid.cells(cv::Rect(4, 1, 22, 18)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(5, 2, 20, 16)).setTo(common::OccupancyGrid::kFree);
  grid.cells(cv::Rect(25, 5, 1, 8)).setTo(common::OccupancyGrid::kFree);  // the holes
  grid.cells(cv::Rect(4, 7, 1, 6)).setTo(common::OccupancyGrid::kFree);   // the opening
  FrontierOptions options;
  options.min_frontier_cells = 4;
  const common::Pose2 robot{1.5, 1.0, 0.0};
  std::vector<common::Point2> points;
  for (double y = 0.25; y <= 1.75; y += 0.02) points.emplace_back(1.05, y - robot.y);  // the right wall
  for (double y = 0.75; y <= 1.25; y += 0.02) points.emplace_back(-4.5, y - robot.y);  // through the opening

  SeenWalls seen(options.seen_wall_range, options.seen_wall_margin);
  seen.addScan(points, robot, 0.5);  // before any map: not kept
  EXPECT_TRUE(seen.seenBy(1.0).empty());
  seen.setGrid(grid);
  seen.addScan(points, robot, 1.0);
  EXPECT_EQ(findFrontiers(grid, options, seen.seenBy(0.9)).frontiers.size(), 2u);  // the scan came later
  const FrontierMap frontiers = findFrontiers(grid, options, seen.seenBy(1.0));
  ASSERT_EQ(frontiers.frontiers.size(), 1u);
  for (const cv::Point& cell : frontiers.frontiers[0].cells) EXPECT_EQ(cell.x, 4);  // the opening is left

  // The map grows by 1 m to the left: the seen cells stay where they are in the map frame.
  const int seen_cells = cv::countNonZero(seen.seenBy(1.0));
  EXPECT_GT(seen_cells, 0);
  common::OccupancyGrid grown = unknownGrid(50, 20);
  grown.origin = common::Point2(-1.0, 0.0);
  grid.cells.copyTo(grown.cells(cv::Rect(10, 0, 40, 20)));
  seen.setGrid(grown);
  const cv::Mat1b moved = seen.seenBy(1.0);
  EXPECT_EQ(cv::countNonZero(moved), seen_cells);
  EXPECT_EQ(findFrontiers(grown, options, moved).frontiers.size(), 1u);
  EXPECT_EQ(cv::countNonZero(moved(cv::Rect(35, 5, 1, 8))), 8);  // col 25 of the first grid
}

// A 10 m x 4 m free corridor (0.1 m cells) closed by walls, with unknown strips at both ends behind gaps:
// frontier at the left end (x ~ 0.2) and at the right end (x ~ 9.8).
common::OccupancyGrid corridorWithTwoEnds() {
  common::OccupancyGrid grid = unknownGrid(100, 40);
  grid.cells(cv::Rect(2, 0, 96, 40)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(2, 1, 96, 38)).setTo(common::OccupancyGrid::kFree);
  return grid;
}

TEST(Frontier, NearestGoalIsTheCheaperEndAndSkipsTheBlacklist) {
  const common::OccupancyGrid grid = corridorWithTwoEnds();
  GridPlanner planner;
  planner.setMap(grid);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(7.0, 2.0)));
  const FrontierMap frontiers = findFrontiers(grid);
  ASSERT_EQ(frontiers.frontiers.size(), 2u);
  FrontierOptions options;
  const std::optional<FrontierGoal> goal = nearestFrontierGoal(frontiers, planner, Blacklist(), options);
  ASSERT_TRUE(goal.has_value());
  EXPECT_GT(goal->position.x(), 9.0);   // the right end is 3 m away, the left one 7 m
  EXPECT_LE(std::abs(goal->position.x() - 9.75), options.goal_reach + 1e-6);  // frontier cells at x = 9.75
  EXPECT_NEAR(goal->cost, planner.costTo(goal->cell.x, goal->cell.y), 1e-12);
  EXPECT_LT(goal->cost, 4.0);

  Blacklist blacklist;
  blacklist.radius = 3.0;
  blacklist.points.push_back(common::Point2(9.8, 2.0));
  const std::optional<FrontierGoal> other = nearestFrontierGoal(frontiers, planner, blacklist, options);
  ASSERT_TRUE(other.has_value());
  EXPECT_LT(other->position.x(), 1.0);
  EXPECT_GT(other->cost, 5.5);

  // Hysteresis: a previous goal at the left end is kept only while it costs at most `hysteresis` more.
  EXPECT_GT(nearestFrontierGoal(frontiers, planner, Blacklist(), options, other->position, 1.0)->position.x(), 9.0);
  EXPECT_LT(nearestFrontierGoal(frontiers, planner, Blacklist(), options, other->position, 100.0)->position.x(), 1.0);
}

// A search bounded by the goal candidates finds the goals of a full one (the nearest, the one the blacklist leaves,
// a previous goal within the hysteresis) and stops short of the far end; its costs up to the bound are exact.
TEST(Frontier, ASearchBoundedByTheCandidatesFindsTheSameGoals) {
  const common::OccupancyGrid grid = corridorWithTwoEnds();
  const FrontierMap frontiers = findFrontiers(grid);
  const common::Point2 robot(7.0, 2.0);
  const FrontierOptions options;
  GridPlanner full, bounded;
  full.setMap(grid);
  bounded.setMap(grid);
  ASSERT_TRUE(full.computeCostsFrom(robot));
  EXPECT_FALSE(full.searchWasBounded());
  Blacklist far_end;  // the right end blacklisted: the goal is the left one
  far_end.radius = 3.0;
  far_end.points.push_back(common::Point2(9.8, 2.0));
  for (const Blacklist& blacklist : {Blacklist(), far_end}) {
    for (double hysteresis : {0.0, 1.0, 100.0}) {
      const cv::Mat1b targets = goalCandidates(frontiers, bounded, blacklist, options, robot, 0.5);
      ASSERT_GT(cv::countNonZero(targets), 0);
      ASSERT_TRUE(bounded.computeCostsFrom(robot, targets, hysteresis));
      const common::Point2 left_goal(0.75, 2.05);
      for (const std::optional<common::Point2>& previous : {std::optional<common::Point2>(), std::optional(left_goal)}) {
        const auto expected = nearestFrontierGoal(frontiers, full, blacklist, options, previous, hysteresis);
        const auto actual = nearestFrontierGoal(frontiers, bounded, blacklist, options, previous, hysteresis);
        ASSERT_EQ(expected.has_value(), actual.has_value());
        ASSERT_TRUE(actual.has_value());
        EXPECT_EQ(actual->cell, expected->cell) << "hysteresis " << hysteresis;
        EXPECT_DOUBLE_EQ(actual->cost, expected->cost);
      }
      int finite = 0;
      for (int row = 0; row < grid.height(); ++row)
        for (int col = 0; col < grid.width(); ++col)
          if (std::isfinite(bounded.costTo(col, row))) {
            ++finite;
            EXPECT_DOUBLE_EQ(bounded.costTo(col, row), full.costTo(col, row));
          }
      if (blacklist.points.empty() && hysteresis == 0.0) {
        EXPECT_TRUE(bounded.searchWasBounded());
        EXPECT_FALSE(std::isfinite(bounded.costTo(5, 20))) << "the search went on to the far (left) end";
      }
      EXPECT_GT(finite, 0);
    }
  }
}

// The corridor with two frontier ends, searched from (7, 2), and a blacklist whose radius covers either end.
class BlacklistRelease : public ::testing::Test {
 protected:
  void SetUp() override {
    planner_.setMap(grid_);
    ASSERT_TRUE(planner_.computeCostsFrom(common::Point2(7.0, 2.0)));
    blacklist_.radius = 3.0;
  }
  std::optional<FrontierGoal> goal() const {
    return nearestFrontierGoal(frontiers_, planner_, blacklist_, FrontierOptions());
  }
  const common::OccupancyGrid grid_ = corridorWithTwoEnds();
  const FrontierMap frontiers_ = findFrontiers(grid_);
  GridPlanner planner_;
  Blacklist blacklist_;
};

TEST_F(BlacklistRelease, PlacesWhereTheRobotWasStuckAreTriedAgain) {
  EXPECT_TRUE(blacklist_.add(common::Point2(9.8, 2.0), GoalOutcome::kRobotStuck));  // failed, the robot could not move
  EXPECT_FALSE(blacklist_.add(common::Point2(0.2, 2.0), GoalOutcome::kReached));    // reached, its frontier still there
  EXPECT_FALSE(goal().has_value());
  EXPECT_EQ(blacklist_.releaseFailed(), 0u);
  EXPECT_EQ(blacklist_.releaseStuck(), 1u);
  EXPECT_EQ(blacklist_.points.size(), 1u);
  EXPECT_TRUE(blacklist_.stuck_points.empty());
  const std::optional<FrontierGoal> again = goal();
  ASSERT_TRUE(again.has_value());
  EXPECT_GT(again->position.x(), 9.0);
  EXPECT_EQ(blacklist_.releaseStuck(), 0u);
  // Stuck there again: released again next time (the recoveries are what may free the robot).
  blacklist_.add(again->position, GoalOutcome::kRobotStuck);
  EXPECT_FALSE(goal().has_value());
  EXPECT_EQ(blacklist_.releaseStuck(), 1u);
}

TEST_F(BlacklistRelease, FailedPlacesGetOneSecondTry) {
  EXPECT_FALSE(blacklist_.add(common::Point2(0.2, 2.0), GoalOutcome::kReached));
  EXPECT_TRUE(blacklist_.add(common::Point2(9.8, 2.0), GoalOutcome::kFailed));
  EXPECT_FALSE(goal().has_value());
  EXPECT_EQ(blacklist_.releaseStuck(), 0u);
  // The failed place is released, the reached one is not.
  EXPECT_EQ(blacklist_.releaseFailed(), 1u);
  ASSERT_EQ(blacklist_.points.size(), 1u);
  EXPECT_EQ(blacklist_.points[0], common::Point2(0.2, 2.0));
  const std::optional<FrontierGoal> again = goal();
  ASSERT_TRUE(again.has_value());
  EXPECT_GT(again->position.x(), 9.0);
  // It fails again (near the retried place): blacklisted for good.
  EXPECT_FALSE(blacklist_.add(again->position, GoalOutcome::kFailed));
  EXPECT_TRUE(blacklist_.failed_points.empty());
  EXPECT_EQ(blacklist_.releaseFailed(), 0u);
  EXPECT_FALSE(goal().has_value());
  // A failure elsewhere gets its own second try.
  EXPECT_TRUE(blacklist_.add(common::Point2(5.0, 9.0), GoalOutcome::kFailed));
  EXPECT_EQ(blacklist_.releaseFailed(), 1u);
  EXPECT_EQ(blacklist_.points.size(), 2u);
}

// A straight path along y = 2 from x = 0 to x = 5 in 0.05 m steps.
std::vector<common::Point2> straightPath() {
  std::vector<common::Point2> path;
  for (int i = 0; i <= 100; ++i) path.emplace_back(0.05 * i, 2.0);
  return path;
}

TEST(BlockedPassages, TwoFailuresFromOnePlaceBlockThePathAheadOfTheRobot) {
  BlockedPassages passages;  // 2 failures, same place within 0.5 m, stretch 0.25..1.0 m ahead
  EXPECT_FALSE(passages.addFailure(common::Point2(2.0, 2.1), straightPath()));
  EXPECT_TRUE(passages.blockedPoints().empty());
  EXPECT_FALSE(passages.addFailure(common::Point2(4.0, 2.0), straightPath()));  // another place
  EXPECT_TRUE(passages.blockedPoints().empty());
  EXPECT_TRUE(passages.addFailure(common::Point2(2.3, 2.0), straightPath()));  // 0.3 m from the first, same way
  ASSERT_FALSE(passages.blockedPoints().empty());
  for (const common::Point2& point : passages.blockedPoints()) {
    EXPECT_GE(point.x(), 2.0 + 0.25 - 1e-9);  // ahead of the first failure's robot, not where it stood ...
    EXPECT_LE(point.x(), 2.3 + 1.0 + 1e-9);   // ... up to 1 m ahead of the second's
  }
  // The failure at x = 4 is still pending: one more there blocks its stretch too; a release opens all, once.
  EXPECT_TRUE(passages.addFailure(common::Point2(4.1, 2.0), straightPath()));
  EXPECT_GT(passages.releaseOnce(), 0u);
  EXPECT_TRUE(passages.blockedPoints().empty());
  EXPECT_FALSE(passages.addFailure(common::Point2(1.0, 2.0), straightPath()));
  EXPECT_TRUE(passages.addFailure(common::Point2(1.0, 2.0), straightPath()));
  EXPECT_EQ(passages.releaseOnce(), 0u);  // blocked for good now
  EXPECT_FALSE(passages.blockedPoints().empty());

  // Failures from one place in different directions: the robot is stuck there; what was blocked from there is
  // opened, and later failures there block nothing.
  BlockedPassages wedged;
  std::vector<common::Point2> back = straightPath();
  std::reverse(back.begin(), back.end());
  EXPECT_FALSE(wedged.addFailure(common::Point2(2.0, 2.0), straightPath()));
  EXPECT_TRUE(wedged.addFailure(common::Point2(2.1, 2.0), straightPath()));
  EXPECT_FALSE(wedged.blockedPoints().empty());
  EXPECT_TRUE(wedged.addFailure(common::Point2(2.0, 2.0), back));  // the other way
  EXPECT_TRUE(wedged.blockedPoints().empty());
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(wedged.addFailure(common::Point2(2.0, 2.1), straightPath()));
  EXPECT_TRUE(wedged.blockedPoints().empty());

  BlockedPassagesOptions never;
  never.failures = 0;
  BlockedPassages off(never);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(off.addFailure(common::Point2(2.0, 2.0), straightPath()));
  EXPECT_TRUE(off.blockedPoints().empty());
  BlockedPassagesOptions bad;
  bad.skip = 2.0;  // beyond length
  EXPECT_THROW(BlockedPassages{bad}, common::InputError);
  bad = BlockedPassagesOptions();
  bad.radius = -0.1;
  EXPECT_THROW(BlockedPassages{bad}, common::InputError);
}

TEST(Frontier, UnreachableFrontierGivesNoGoal) {
  // A frontier in a second room that a wall separates from the robot's.
  common::OccupancyGrid grid = corridorWithTwoEnds();
  grid.cells(cv::Rect(50, 0, 2, 40)).setTo(common::OccupancyGrid::kOccupied);  // wall across at x = 5.0..5.2
  grid.cells(cv::Rect(0, 0, 2, 40))
      .setTo(common::OccupancyGrid::kOccupied);  // left end closed: only the right frontier
  GridPlanner planner;
  planner.setMap(grid);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 2.0)));
  const FrontierMap frontiers = findFrontiers(grid);
  ASSERT_EQ(frontiers.frontiers.size(), 1u);
  EXPECT_FALSE(nearestFrontierGoal(frontiers, planner, Blacklist(), FrontierOptions()).has_value());
  // From the other side it is reachable.
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(8.0, 2.0)));
  EXPECT_TRUE(nearestFrontierGoal(frontiers, planner, Blacklist(), FrontierOptions()).has_value());
}

TEST(Frontier, GoalsKeepRobotRadiusButPathsPassNarrowDoors) {
  // Known room x = 0.2..4.0 with a wall at x = 4.0..4.2 and a 0.6 m door in it (6 free cells: its centre is 0.3 m
  // from the jambs); behind the door 1 m of known floor, then unknown space (a frontier at x = 5.15).
  common::OccupancyGrid grid = unknownGrid(100, 40);
  grid.cells(cv::Rect(2, 0, 50, 40)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(3, 1, 37, 38)).setTo(common::OccupancyGrid::kFree);
  grid.cells(cv::Rect(40, 17, 2, 6)).setTo(common::OccupancyGrid::kFree);   // the door, rows 17..22
  grid.cells(cv::Rect(42, 1, 10, 38)).setTo(common::OccupancyGrid::kFree);  // behind it, up to the frontier
  const FrontierMap frontiers = findFrontiers(grid);
  ASSERT_EQ(frontiers.frontiers.size(), 1u);

  GridPlannerOptions planner_options;
  planner_options.robot_radius = 0.38;
  planner_options.min_clearance = 0.25;
  GridPlanner planner(planner_options);
  planner.setMap(grid);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 2.0)));
  const std::optional<FrontierGoal> goal = nearestFrontierGoal(frontiers, planner, Blacklist(), FrontierOptions());
  ASSERT_TRUE(goal.has_value());
  EXPECT_GT(goal->position.x(), 4.2);  // through the door
  EXPECT_NE(planner.roomy()(goal->cell.y, goal->cell.x), 0);

  // With the inflation at robot_radius the door is closed and the frontier unreachable.
  planner_options.min_clearance = planner_options.robot_radius;
  GridPlanner strict(planner_options);
  strict.setMap(grid);
  ASSERT_TRUE(strict.computeCostsFrom(common::Point2(2.0, 2.0)));
  EXPECT_FALSE(nearestFrontierGoal(frontiers, strict, Blacklist(), FrontierOptions()).has_value());

  // A frontier in the door (the floor beyond it unknown): the cells within goal_reach (0.3 m here) of it are in
  // the door's narrow band, traversable and reachable but not roomy, so no goal there.
  grid.cells(cv::Rect(42, 0, 10, 39)).setTo(common::OccupancyGrid::kUnknown);
  planner_options.min_clearance = 0.25;
  GridPlanner narrow(planner_options);
  narrow.setMap(grid);
  ASSERT_TRUE(narrow.computeCostsFrom(common::Point2(2.0, 2.0)));
  FrontierOptions door_options;
  door_options.min_frontier_cells = 4;  // the door's 6 cells
  door_options.goal_reach = 0.3;
  const FrontierMap door_frontier = findFrontiers(grid, door_options);
  ASSERT_EQ(door_frontier.frontiers.size(), 1u);
  EXPECT_EQ(door_frontier.frontiers[0].cells.front().x, 41);
  EXPECT_TRUE(std::isfinite(narrow.costTo(40, 19)));  // in the door: reachable ...
  EXPECT_EQ(narrow.roomy()(19, 40), 0);                // ... but not roomy
  EXPECT_FALSE(nearestFrontierGoal(door_frontier, narrow, Blacklist(), door_options).has_value());
  door_options.goal_reach = 0.6;  // roomy cells of the room within reach: a goal before the door
  const std::optional<FrontierGoal> before_door = nearestFrontierGoal(door_frontier, narrow, Blacklist(), door_options);
  ASSERT_TRUE(before_door.has_value());
  EXPECT_LT(before_door->position.x(), 3.9);
}

TEST(Frontier, ALookGoalSeesPastAFrontierBehindAGapTooNarrowToPass) {
  // Known room x = 0.2..4.0, a wall at x = 4.0..4.2 with a 0.4 m gap (rows 18..21: its centre 0.2 m from the
  // jambs, under min_clearance); behind it only the strip the laser saw through the gap (x = 4.2..5.0), all else
  // unknown. The strip's frontier cannot be reached, and no roomy cell of the room is within goal_reach of it.
  common::OccupancyGrid grid = unknownGrid(100, 40);
  grid.cells(cv::Rect(2, 0, 40, 40)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(3, 1, 37, 38)).setTo(common::OccupancyGrid::kFree);
  grid.cells(cv::Rect(40, 18, 10, 4)).setTo(common::OccupancyGrid::kFree);  // the gap and the strip behind it
  const FrontierMap frontiers = findFrontiers(grid);
  ASSERT_EQ(frontiers.frontiers.size(), 1u);
  GridPlanner planner;  // robot_radius 0.38, min_clearance 0.30
  planner.setMap(grid);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(1.0, 1.0)));
  EXPECT_FALSE(nearestFrontierGoal(frontiers, planner, Blacklist(), FrontierOptions()).has_value());

  const std::optional<FrontierGoal> look = nearestLookGoal(frontiers, planner, Blacklist(), FrontierOptions());
  ASSERT_TRUE(look.has_value());
  EXPECT_TRUE(look->look);
  EXPECT_LT(look->position.x(), 4.0);  // in the room, ...
  EXPECT_GT(look->position.x(), 4.0 - FrontierOptions().look_range - 0.05);  // ... within look_range of the strip
  EXPECT_NE(planner.roomy()(look->cell.y, look->cell.x), 0);
  EXPECT_TRUE(std::isfinite(look->cost));
  // It sees through the gap: the straight line from it to the gap's middle crosses only free cells.
  const common::Point2 gap(4.1, 2.0);
  for (double t = 0.0; t <= 1.0; t += 0.01) {
    int col = 0, row = 0;
    ASSERT_TRUE(grid.cellOf(look->position + t * (gap - look->position), &col, &row));
    EXPECT_EQ(grid.cells(row, col), common::OccupancyGrid::kFree) << "at t = " << t;
  }

  // Blacklisted there, another place; off with look_range 0; none with the gap walled up.
  Blacklist blacklist;
  blacklist.points.push_back(look->position);
  const std::optional<FrontierGoal> other = nearestLookGoal(frontiers, planner, blacklist, FrontierOptions());
  ASSERT_TRUE(other.has_value());
  EXPECT_GT((other->position - look->position).norm(), blacklist.radius);
  FrontierOptions off;
  off.look_range = 0.0;
  EXPECT_FALSE(nearestLookGoal(frontiers, planner, Blacklist(), off).has_value());
  grid.cells(cv::Rect(40, 18, 2, 4)).setTo(common::OccupancyGrid::kOccupied);
  planner.setMap(grid);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(1.0, 1.0)));
  const FrontierMap walled = findFrontiers(grid);
  ASSERT_EQ(walled.frontiers.size(), 1u);
  EXPECT_FALSE(nearestLookGoal(walled, planner, Blacklist(), FrontierOptions()).has_value());
}

}  // namespace
}  // namespace hidden_rooms::exploration
