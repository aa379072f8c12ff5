// Map-quality metrics: free-space IoU after a rigid transform, wall distance, trajectory error.
#include <cmath>

#include <gtest/gtest.h>

#include "hidden_rooms/evaluation/map_quality.h"

namespace hidden_rooms::evaluation {
namespace {

// A 4 m x 3 m room (free) with 1-cell walls, in a grid of 0.05 m with its origin at `origin`.
common::OccupancyGrid room(const common::Point2& origin) {
  common::OccupancyGrid grid;
  grid.resolution = 0.05;
  grid.origin = origin;
  grid.cells = cv::Mat_<int8_t>(60, 80, common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(1, 1, 78, 58)).setTo(common::OccupancyGrid::kFree);
  return grid;
}

TEST(MapQuality, IdenticalMapsScorePerfectly) {
  const common::OccupancyGrid truth = room(common::Point2(0.0, 0.0));
  const MapQuality quality = evaluateMap(truth, common::Pose2{}, truth, cv::Mat1b());
  EXPECT_DOUBLE_EQ(quality.free_iou, 1.0);
  EXPECT_EQ(quality.true_free_cells, 78 * 58);
  EXPECT_DOUBLE_EQ(quality.walls_within_2_cells, 1.0);
  EXPECT_DOUBLE_EQ(quality.wall_distance_mean, 0.0);
}

TEST(MapQuality, AlignsByTheRigidTransform) {
  const common::OccupancyGrid truth = room(common::Point2(0.0, 0.0));
  // The same room mapped in a frame rotated by 90 degrees and shifted: map point (x, y) is world (3 - y, x - 1).
  // The map samples the truth through that transform.
  const common::Pose2 world_from_map{3.0, -1.0, M_PI / 2};
  common::OccupancyGrid map;
  map.resolution = 0.05;
  map.origin = common::Point2(0.0, -2.0);
  map.cells = cv::Mat_<int8_t>(100, 100, common::OccupancyGrid::kUnknown);
  for (int row = 0; row < map.height(); ++row)
    for (int col = 0; col < map.width(); ++col) {
      const common::Point2 p = map.cellCentre(col, row);
      const double c = std::cos(world_from_map.yaw), s = std::sin(world_from_map.yaw);
      const common::Point2 w(world_from_map.x + c * p.x() - s * p.y(), world_from_map.y + s * p.x() + c * p.y());
      int tc = 0, tr = 0;
      if (truth.cellOf(w, &tc, &tr)) map.cells(row, col) = truth.cells(tr, tc);
    }
  const MapQuality aligned = evaluateMap(map, world_from_map, truth, cv::Mat1b());
  EXPECT_GT(aligned.free_iou, 0.97);
  EXPECT_GT(aligned.walls_within_2_cells, 0.99);
  const MapQuality misaligned = evaluateMap(map, common::Pose2{3.3, -0.7, M_PI / 2}, truth, cv::Mat1b());
  EXPECT_LT(misaligned.free_iou, 0.9);
  EXPECT_LT(misaligned.walls_within_2_cells, 0.5);
}

TEST(MapQuality, ScoresOnlyObservedTrueCellsAndCountsExtraFreeCells) {
  const common::OccupancyGrid truth = room(common::Point2(0.0, 0.0));
  cv::Mat1b observed = cv::Mat1b::zeros(truth.height(), truth.width());
  observed(cv::Rect(0, 0, 40, 60)).setTo(255);  // the left half was seen
  common::OccupancyGrid map = truth;
  map.cells(cv::Rect(40, 0, 40, 60)).setTo(common::OccupancyGrid::kUnknown);
  EXPECT_DOUBLE_EQ(evaluateMap(map, common::Pose2{}, truth, observed).free_iou, 1.0);
  map.cells(cv::Rect(40, 1, 10, 58)).setTo(common::OccupancyGrid::kFree);  // free beyond what was seen
  const MapQuality quality = evaluateMap(map, common::Pose2{}, truth, observed);
  EXPECT_NEAR(quality.free_iou, 39.0 * 58 / (49.0 * 58), 1e-9);
}

TEST(MapQuality, MarksCellsAlongTheBeams) {
  const common::OccupancyGrid truth = room(common::Point2(0.0, 0.0));
  common::RangeScan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 0.1;
  scan.range_min = 0.01;
  scan.range_max = 30.0;
  scan.ranges = {1.0f};
  cv::Mat1b observed;
  markObservedCells(truth, common::Pose2{1.0, 1.5, 0.0}, scan, &observed);
  EXPECT_EQ(observed.rows, truth.height());
  EXPECT_EQ(cv::countNonZero(observed), 20);  // 1 m along x from the middle of a cell: 20 cells
  int col = 0, row = 0;
  ASSERT_TRUE(truth.cellOf(common::Point2(1.5, 1.5), &col, &row));
  EXPECT_EQ(observed(row, col), 255);
}

TEST(MapQuality, TrajectoryErrorAfterTheTransform) {
  const std::vector<common::Pose2> truth{{1.0, 1.0, 0.0}, {2.0, 1.0, 0.1}};
  const common::Pose2 world_from_map{1.0, 1.0, 0.0};
  const std::vector<common::Pose2> estimate{{0.0, 0.0, 0.0}, {1.0, 0.3, 0.1}};
  const TrajectoryError error = trajectoryError(estimate, truth, world_from_map);
  EXPECT_EQ(error.poses, 2);
  EXPECT_NEAR(error.position_rmse, std::sqrt(0.09 / 2), 1e-12);
  EXPECT_NEAR(error.position_max, 0.3, 1e-12);
  EXPECT_NEAR(error.yaw_rmse, 0.0, 1e-12);
  const common::Pose2 p{1.0, 2.0, 0.7};
  const common::Pose2 identity = common::composePoses(p, common::invertPose(p));
  EXPECT_NEAR(identity.x, 0.0, 1e-12);
  EXPECT_NEAR(identity.y, 0.0, 1e-12);
  EXPECT_NEAR(identity.yaw, 0.0, 1e-12);
}

TEST(MapQuality, DrawsTheComparison) {
  const common::OccupancyGrid truth = room(common::Point2(0.0, 0.0));
  common::OccupancyGrid map = truth;
  map.cells = truth.cells.clone();  // (cv::Mat copies share their cells)
  map.cells(10, 10) = common::OccupancyGrid::kUnknown;  // missed, never observed
  map.cells(10, 11) = 40;                        // missed, uncertain
  map.cells(10, 12) = common::OccupancyGrid::kOccupied;  // missed, a wall in the map
  map.cells(0, 5) = common::OccupancyGrid::kFree;        // free where the truth has a wall
  const cv::Mat3b picture = drawMapComparison(map, common::Pose2{}, truth, cv::Mat1b());
  ASSERT_EQ(picture.rows, truth.height());
  ASSERT_EQ(picture.cols, truth.width());
  EXPECT_EQ(picture(20, 20), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(picture(10, 10), cv::Vec3b(0, 165, 255));
  EXPECT_EQ(picture(10, 11), cv::Vec3b(0, 0, 255));
  EXPECT_EQ(picture(10, 12), cv::Vec3b(255, 0, 255));
  EXPECT_EQ(picture(0, 5), cv::Vec3b(255, 0, 0));
  EXPECT_EQ(picture(0, 6), cv::Vec3b(0, 0, 0));
  // Outside the observed cells a true free cell is neither hit nor miss.
  cv::Mat1b observed = cv::Mat1b::zeros(truth.height(), truth.width());
  observed(cv::Rect(1, 1, 5, 5)).setTo(255);
  const cv::Mat3b restricted = drawMapComparison(map, common::Pose2{}, truth, observed);
  EXPECT_EQ(restricted(2, 2), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(restricted(10, 11), cv::Vec3b(160, 160, 160));
  EXPECT_EQ(restricted(20, 20), cv::Vec3b(255, 0, 0));  // map free, truth free but not observed
}

}  // namespace
}  // namespace hidden_rooms::evaluation
