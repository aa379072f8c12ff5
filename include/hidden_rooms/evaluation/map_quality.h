#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/range_scan.h"

namespace hidden_rooms::evaluation {

// Cells of `truth`'s grid that a laser saw: every cell a beam crosses from `laser_pose` (world frame) up to its
// return (or up to range_max for beams without one) is set to 255 in `observed` (CV_8U, truth's size; allocated
// and zeroed when empty). Used to score a map only where the robot could have mapped.
void markObservedCells(const common::OccupancyGrid& truth, const common::Pose2& laser_pose,
                       const common::RangeScan& scan, cv::Mat1b* observed);

struct MapQuality {
  // Free-space IoU: cells free in the map (<= 19 after the rigid transform, nearest cell) against cells free in
  // the truth and observed; map-free cells falling outside the truth's grid count in the union.
  double free_iou = 0.0;
  long long true_free_cells = 0;
  long long map_free_cells = 0;
  long long intersection_cells = 0;
  // Occupied map cells (>= 65), each at its distance (in truth cells) to the nearest truth wall cell.
  long long occupied_cells = 0;
  double walls_within_2_cells = 0.0;  // fraction of occupied map cells within 2 cells of a true wall
  double wall_distance_mean = 0.0;    // cells
  double wall_distance_p95 = 0.0;     // cells
};

// Scores `map` against the rendered ground truth `truth`, with `world_from_map` placing the map frame in the
// truth's (world) frame. `observed` (truth's size, non-zero = seen) restricts the true free cells; empty = all.
MapQuality evaluateMap(const common::OccupancyGrid& map, const common::Pose2& world_from_map,
                       const common::OccupancyGrid& truth, const cv::Mat1b& observed);

// The comparison of evaluateMap as a picture on truth's grid (BGR): true walls black, true free cells that were
// observed and mapped free white; observed true free cells the map misses: orange where it is unknown, red where
// it is uncertain (between free and occupied), magenta where it has a wall; map-free cells where the truth is not observed-free blue, other cells grey.
cv::Mat3b drawMapComparison(const common::OccupancyGrid& map, const common::Pose2& world_from_map,
                            const common::OccupancyGrid& truth, const cv::Mat1b& observed);

struct TrajectoryError {
  int poses = 0;
  double position_rmse = 0.0;  // metres, absolute (after world_from_map)
  double yaw_rmse = 0.0;       // radians
  double position_max = 0.0;   // metres
  int relations = 0;                            // consecutive pose pairs
  double relative_translation_mean = 0.0;       // metres per relation: |estimated motion - true motion|
  double relative_rotation_mean = 0.0;          // radians per relation
  double relative_translation_per_metre = 0.0;  // summed translation errors / distance travelled
};

// Error of `estimate` (map frame) against `truth` (world frame, same length and times): absolute after placing the
// estimate with `world_from_map`, and relative between consecutive poses (independent of world_from_map).
TrajectoryError trajectoryError(const std::vector<common::Pose2>& estimate, const std::vector<common::Pose2>& truth,
                                const common::Pose2& world_from_map);

}  // namespace hidden_rooms::evaluation
