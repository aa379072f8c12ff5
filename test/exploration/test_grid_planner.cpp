// The wavefront planner: exact costs in the open, the detour around a wall, inflation, unreachable goals, the
// start escaping the inflated zone, bad options.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/exploration/grid_planner.h"

namespace hidden_rooms::exploration {
namespace {

// An 8 m x 6 m room of 0.1 m cells (80 x 60) with one-cell border walls and, when `wall`, a wall at x = 4.0..4.1
// from the bottom up to y = 4.0 (a 1.9 m gap above it).
common::OccupancyGrid room(bool wall) {
  common::OccupancyGrid grid;
  grid.resolution = 0.1;
  grid.cells = cv::Mat_<int8_t>(60, 80, common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(1, 1, 78, 58)).setTo(common::OccupancyGrid::kFree);
  if (wall) grid.cells(cv::Rect(40, 20, 1, 40)).setTo(common::OccupancyGrid::kOccupied);
  return grid;
}

GridPlannerOptions plainLengths() {
  GridPlannerOptions options;
  options.robot_radius = 0.33;
  options.min_clearance = 0.33;  // no narrow band: the inflation is robot_radius
  options.cost_weight = 0.0;  // cost = length
  options.smoothing_window = 0.0;
  return options;
}

TEST(GridPlanner, OpenSpaceCostIsTheOctileDistance) {
  GridPlanner planner(plainLengths());
  planner.setMap(room(false));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.05, 2.05)));  // cell (20, 39)
  int col = 0, row = 0;
  ASSERT_TRUE(planner.map().cellOf(common::Point2(3.05, 2.55), &col, &row));  // 10 cells right, 5 up
  EXPECT_NEAR(planner.costTo(col, row), 0.1 * (5 * std::sqrt(2.0) + 5), 1e-9);
  const std::vector<common::Point2> path = planner.pathTo(col, row);
  ASSERT_EQ(path.size(), 11u);
  EXPECT_NEAR(pathLength(path), planner.costTo(col, row), 1e-9);
  EXPECT_NEAR(path.front().x(), 2.05, 1e-9);
  EXPECT_NEAR(path.back().y(), 2.55, 1e-9);
}

TEST(GridPlanner, GoesAroundAWallOutsideTheInflation) {
  GridPlanner planner(plainLengths());
  planner.setMap(room(true));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 1.0)));
  int col = 0, row = 0;
  ASSERT_TRUE(planner.map().cellOf(common::Point2(6.0, 1.0), &col, &row));
  const double cost = planner.costTo(col, row);
  // Euclidean shortest way around the inflated wall end (4.05, 4.0 + 0.33): 2 x 3.88 m; the 8-connected grid is
  // at most 12% longer (about 8.5 m).
  EXPECT_GT(cost, 7.7);
  EXPECT_LT(cost, 7.77 * 1.12);
  const std::vector<common::Point2> path = planner.pathTo(col, row);
  ASSERT_FALSE(path.empty());
  EXPECT_NEAR(pathLength(path), cost, 1e-9);
  double highest = 0.0;
  for (const common::Point2& point : path) {
    int c = 0, r = 0;
    ASSERT_TRUE(planner.map().cellOf(point, &c, &r));
    EXPECT_GE(planner.obstacleDistance()(r, c), 0.33 - 1e-6);
    EXPECT_NE(planner.traversable()(r, c), 0);
    highest = std::max(highest, point.y());
  }
  EXPECT_GT(highest, 4.3);  // over the wall's end
}

TEST(GridPlanner, ProximityCostAndSmoothingKeepThePathValid) {
  GridPlannerOptions options;  // defaults: cost near walls, smoothing
  GridPlanner planner(options);
  planner.setMap(room(true));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 1.0)));
  int col = 0, row = 0;
  ASSERT_TRUE(planner.map().cellOf(common::Point2(6.0, 1.0), &col, &row));
  const std::vector<common::Point2> path = planner.pathTo(col, row);
  ASSERT_GT(path.size(), 10u);
  EXPECT_GT(planner.costTo(col, row), pathLength(path));  // the gap and the walls cost extra
  EXPECT_LT(pathLength(path), 10.5);  // longer than the shortest: it keeps to the middle of the gap
  for (const common::Point2& point : path) {
    int c = 0, r = 0;
    ASSERT_TRUE(planner.map().cellOf(point, &c, &r));
    EXPECT_NE(planner.traversable()(r, c), 0);
  }
}

TEST(GridPlanner, ClosedWallMakesTheOtherSideUnreachable) {
  common::OccupancyGrid grid = room(true);
  grid.cells(cv::Rect(40, 0, 1, 60)).setTo(common::OccupancyGrid::kOccupied);
  GridPlanner planner;
  planner.setMap(grid);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 1.0)));
  EXPECT_TRUE(std::isinf(planner.costTo(common::Point2(6.0, 1.0))));
  int col = 0, row = 0;
  ASSERT_TRUE(grid.cellOf(common::Point2(6.0, 1.0), &col, &row));
  EXPECT_TRUE(planner.pathTo(col, row).empty());
  EXPECT_TRUE(std::isinf(planner.costTo(-100, 5)));  // outside the grid
}

TEST(GridPlanner, UnknownCellsAreNotTraversable) {
  common::OccupancyGrid grid = room(false);
  grid.cells(cv::Rect(40, 0, 3, 60)).setTo(common::OccupancyGrid::kUnknown);
  GridPlanner planner;
  planner.setMap(grid);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 1.0)));
  EXPECT_TRUE(std::isinf(planner.costTo(common::Point2(6.0, 1.0))));
}

TEST(GridPlanner, StartInTheInflationEscapesToTheNearestFreeCell) {
  GridPlannerOptions options;
  options.robot_radius = 0.33;
  options.min_clearance = 0.33;
  GridPlanner planner(options);
  planner.setMap(room(false));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(0.2, 3.0)));  // 0.1 m from the left wall
  const cv::Point start = planner.startCell();
  EXPECT_NE(planner.traversable()(start.y, start.x), 0);
  EXPECT_NEAR(planner.map().cellCentre(start.x, start.y).x(), 0.45, 1e-9);  // first cell >= 0.33 m from the wall
  EXPECT_TRUE(std::isfinite(planner.costTo(common::Point2(6.0, 3.0))));
  EXPECT_FALSE(planner.computeCostsFrom(common::Point2(-5.0, 3.0)));  // outside the map
}

// The room split by a wall at x = 4.0..4.1 with a door of `gap` metres (centred at y = 3.0).
common::OccupancyGrid roomWithDoor(double gap) {
  common::OccupancyGrid grid = room(false);
  grid.cells(cv::Rect(40, 0, 1, 60)).setTo(common::OccupancyGrid::kOccupied);
  const int cells = static_cast<int>(std::lround(gap / grid.resolution));
  grid.cells(cv::Rect(40, 30 - cells / 2, 1, cells)).setTo(common::OccupancyGrid::kFree);
  return grid;
}

TEST(GridPlanner, DoorNarrowerThanTwoRobotRadiiIsPassableThroughTheNarrowBand) {
  // A door of 6 free cells (0.6 m): the centre keeps at most 0.3 m from its jambs (cell centres), under
  // robot_radius but above min_clearance.
  GridPlannerOptions options;
  options.robot_radius = 0.38;
  options.min_clearance = 0.25;
  GridPlanner planner(options);
  planner.setMap(roomWithDoor(0.6));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  int col = 0, row = 0;
  ASSERT_TRUE(planner.map().cellOf(common::Point2(6.0, 3.0), &col, &row));
  ASSERT_TRUE(std::isfinite(planner.costTo(col, row)));
  EXPECT_NE(planner.roomy()(row, col), 0);
  bool narrow = false;
  for (const common::Point2& point : planner.pathTo(col, row)) {
    int c = 0, r = 0;
    ASSERT_TRUE(planner.map().cellOf(point, &c, &r));
    EXPECT_GE(planner.obstacleDistance()(r, c), 0.25 - 1e-6);
    narrow |= planner.roomy()(r, c) == 0;
  }
  EXPECT_TRUE(narrow);  // through the door's narrow band
  // The door cells are traversable but not roomy (no goal in a doorway).
  ASSERT_TRUE(planner.map().cellOf(common::Point2(4.05, 2.95), &col, &row));
  EXPECT_NE(planner.traversable()(row, col), 0);
  EXPECT_EQ(planner.roomy()(row, col), 0);

  // With the inflation at robot_radius (min_clearance = robot_radius) the same door is closed, and so is a
  // 0.4 m one (0.2 m from the jambs) with min_clearance 0.25.
  options.min_clearance = options.robot_radius;
  GridPlanner strict(options);
  strict.setMap(roomWithDoor(0.6));
  ASSERT_TRUE(strict.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isinf(strict.costTo(common::Point2(6.0, 3.0))));
  options.min_clearance = 0.25;
  GridPlanner narrow_door(options);
  narrow_door.setMap(roomWithDoor(0.4));
  ASSERT_TRUE(narrow_door.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isinf(narrow_door.costTo(common::Point2(6.0, 3.0))));
}

TEST(GridPlanner, NarrowBandOnlyWhereThereIsNoRoomyWay) {
  // Around the end of the wall (1.9 m of room above it) the path keeps robot_radius although cutting the corner
  // through the narrow band would be shorter: narrow cells cost narrow_cost_factor times more.
  GridPlannerOptions options;
  options.cost_weight = 0.0;
  options.smoothing_window = 0.0;
  GridPlanner planner(options);
  planner.setMap(room(true));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 1.0)));
  int col = 0, row = 0;
  ASSERT_TRUE(planner.map().cellOf(common::Point2(6.0, 1.0), &col, &row));
  for (const common::Point2& point : planner.pathTo(col, row)) {
    int c = 0, r = 0;
    ASSERT_TRUE(planner.map().cellOf(point, &c, &r));
    EXPECT_NE(planner.roomy()(r, c), 0);
  }
  // Without the extra cost the shortest way cuts through the band.
  options.narrow_cost_factor = 1.0;
  GridPlanner cutting(options);
  cutting.setMap(room(true));
  ASSERT_TRUE(cutting.computeCostsFrom(common::Point2(2.0, 1.0)));
  bool narrow = false;
  for (const common::Point2& point : cutting.pathTo(col, row)) {
    int c = 0, r = 0;
    ASSERT_TRUE(cutting.map().cellOf(point, &c, &r));
    narrow |= cutting.roomy()(r, c) == 0;
  }
  EXPECT_TRUE(narrow);
}

TEST(GridPlanner, BlockedPointsCloseADoorUntilUnblocked) {
  GridPlanner planner;
  planner.setMap(roomWithDoor(1.0));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  ASSERT_TRUE(std::isfinite(planner.costTo(common::Point2(6.0, 3.0))));
  // Points across the door's middle, blocking 0.15 m around each: the room behind is cut off, at once and in the
  // next map.
  planner.setBlockedPoints({common::Point2(4.05, 2.85), common::Point2(4.05, 3.05), common::Point2(4.05, 3.25)}, 0.15);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isinf(planner.costTo(common::Point2(6.0, 3.0))));
  int col = 0, row = 0;
  ASSERT_TRUE(planner.map().cellOf(common::Point2(4.05, 3.05), &col, &row));
  EXPECT_EQ(planner.traversable()(row, col), 0);
  planner.setMap(roomWithDoor(1.0));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isinf(planner.costTo(common::Point2(6.0, 3.0))));
  // Elsewhere in the room nothing changed.
  EXPECT_TRUE(std::isfinite(planner.costTo(common::Point2(2.0, 5.0))));
  planner.setBlockedPoints({}, 0.0);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isfinite(planner.costTo(common::Point2(6.0, 3.0))));
}

TEST(GridPlanner, TheRobotsTrailStaysPassableWhereTheMapDrawsTheWayNarrower) {
  // A 0.4 m door (its centre 0.2 m from the jambs, under min_clearance 0.30): closed to the planner. The robot came
  // through it (its trail from (5.5, 4.5) to (2.6, 1.6), at 45 degrees through the door's middle): the trail's free
  // cells are traversable, so the far side is reachable again, by the trail alone (no other cell of the door opens).
  // A diagonal step of the search needs both cells beside it, so the trail is drawn 4-connected.
  GridPlanner planner;
  planner.setMap(roomWithDoor(0.4));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isinf(planner.costTo(common::Point2(6.0, 3.0))));
  std::vector<common::Point2> trail;
  for (double x = 5.5; x >= 2.6 - 1e-9; x -= 0.05) trail.emplace_back(x, 3.05 + (x - 4.05));
  planner.setTrail(trail);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isfinite(planner.costTo(common::Point2(6.0, 3.0))));
  int col = 0, row = 0;
  ASSERT_TRUE(planner.map().cellOf(common::Point2(4.05, 3.05), &col, &row));
  EXPECT_NE(planner.traversable()(row, col), 0);
  EXPECT_LE(cv::countNonZero(planner.traversable().col(col)), 2);  // the trail's cells of the door's 4
  EXPECT_EQ(planner.roomy()(row, col), 0);  // no goal in the door
  // Kept for the next map; blocked points still close it; a jump of the pose (a step over a metre) draws nothing.
  planner.setMap(roomWithDoor(0.4));
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isfinite(planner.costTo(common::Point2(6.0, 3.0))));
  planner.setBlockedPoints({common::Point2(4.05, 3.05)}, 0.15);
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isinf(planner.costTo(common::Point2(6.0, 3.0))));
  planner.setBlockedPoints({}, 0.0);
  planner.setTrail({common::Point2(5.5, 4.5), common::Point2(3.5, 2.5), common::Point2(2.6, 1.6)});
  ASSERT_TRUE(planner.computeCostsFrom(common::Point2(2.0, 3.0)));
  EXPECT_TRUE(std::isinf(planner.costTo(common::Point2(6.0, 3.0))));
}

TEST(GridPlanner, EmptyMapPlansNothing) {
  GridPlanner planner;
  planner.setMap(common::OccupancyGrid());
  EXPECT_FALSE(planner.computeCostsFrom(common::Point2(0.0, 0.0)));
  EXPECT_TRUE(std::isinf(planner.costTo(0, 0)));
  EXPECT_TRUE(planner.pathTo(0, 0).empty());
}

TEST(GridPlanner, RejectsBadOptions) {
  GridPlannerOptions options;
  options.robot_radius = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(GridPlanner{options}, common::InputError);
  options = GridPlannerOptions();
  options.cost_radius = 0.1;  // below robot_radius
  EXPECT_THROW(GridPlanner{options}, common::InputError);
  options = GridPlannerOptions();
  options.min_clearance = 0.5;  // above robot_radius
  EXPECT_THROW(GridPlanner{options}, common::InputError);
  options = GridPlannerOptions();
  options.narrow_cost_factor = 0.5;
  EXPECT_THROW(GridPlanner{options}, common::InputError);
}

}  // namespace
}  // namespace hidden_rooms::exploration
