#include "hidden_rooms/evaluation/map_quality.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/geometry.h"

namespace hidden_rooms::evaluation {

namespace {

constexpr int8_t kFreeMax = 19;      // map_saver's free threshold (percent)
constexpr int8_t kOccupiedMin = 65;  // map_saver's occupied threshold

bool isFree(int8_t value) { return value >= 0 && value <= kFreeMax; }
bool isOccupied(int8_t value) { return value >= kOccupiedMin; }

}  // namespace

void markObservedCells(const common::OccupancyGrid& truth, const common::Pose2& laser_pose,
                       const common::RangeScan& scan, cv::Mat1b* observed) {
  if (observed->empty() || observed->rows != truth.height() || observed->cols != truth.width())
    *observed = cv::Mat1b::zeros(truth.height(), truth.width());
  const double step = 0.5 * truth.resolution;
  for (size_t k = 0; k < scan.ranges.size(); ++k) {
    const float range = scan.ranges[k];
    if (!std::isfinite(range) || range <= scan.range_min) continue;
    const double length = std::min<double>(range, scan.range_max);
    const double angle = laser_pose.yaw + scan.angle_min + static_cast<double>(k) * scan.angle_increment;
    const double dx = std::cos(angle), dy = std::sin(angle);
    for (double t = 0.0; t < length; t += step) {
      int col = 0, row = 0;
      if (!truth.cellOf(common::Point2(laser_pose.x + t * dx, laser_pose.y + t * dy), &col, &row)) break;
      (*observed)(row, col) = 255;
    }
  }
}

MapQuality evaluateMap(const common::OccupancyGrid& map, const common::Pose2& world_from_map,
                       const common::OccupancyGrid& truth, const cv::Mat1b& observed) {
  MapQuality quality;
  const bool restrict = !observed.empty();
  const common::Pose2 map_from_world = common::invertPose(world_from_map);
  long long union_cells = 0;
  for (int row = 0; row < truth.height(); ++row) {
    for (int col = 0; col < truth.width(); ++col) {
      const bool truly_free = isFree(truth.cells(row, col)) && (!restrict || observed(row, col) != 0);
      int map_col = 0, map_row = 0;
      const bool mapped_free =
          !map.empty() &&
          map.cellOf(common::transformPoint(map_from_world, truth.cellCentre(col, row)), &map_col, &map_row) &&
          isFree(map.cells(map_row, map_col));
      quality.true_free_cells += truly_free;
      quality.map_free_cells += mapped_free;
      quality.intersection_cells += truly_free && mapped_free;
      union_cells += truly_free || mapped_free;
    }
  }

  // Distance of every truth cell to the nearest truth wall cell, in cells.
  cv::Mat1b not_wall(truth.height(), truth.width());
  for (int row = 0; row < truth.height(); ++row)
    for (int col = 0; col < truth.width(); ++col) not_wall(row, col) = isOccupied(truth.cells(row, col)) ? 0 : 255;
  cv::Mat1f distance;
  cv::distanceTransform(not_wall, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);

  std::vector<float> wall_distances;
  for (int row = 0; row < map.height(); ++row) {
    for (int col = 0; col < map.width(); ++col) {
      const int8_t value = map.cells(row, col);
      if (!isFree(value) && !isOccupied(value)) continue;
      int truth_col = 0, truth_row = 0;
      const bool inside =
          truth.cellOf(common::transformPoint(world_from_map, map.cellCentre(col, row)), &truth_col, &truth_row);
      if (isFree(value) && !inside) {  // free space mapped outside the world's grid: wrong by definition
        ++quality.map_free_cells;
        ++union_cells;
      }
      if (isOccupied(value))
        wall_distances.push_back(inside ? distance(truth_row, truth_col) : 1e6f);
    }
  }
  quality.free_iou = union_cells > 0 ? static_cast<double>(quality.intersection_cells) / union_cells : 0.0;
  quality.occupied_cells = static_cast<long long>(wall_distances.size());
  if (!wall_distances.empty()) {
    long long within = 0;
    double sum = 0.0;
    for (float d : wall_distances) {
      within += d <= 2.0f;
      sum += std::min(d, 1e3f);
    }
    quality.walls_within_2_cells = static_cast<double>(within) / wall_distances.size();
    quality.wall_distance_mean = sum / wall_distances.size();
    std::vector<float> sorted = wall_distances;
    const size_t p95 = std::min(sorted.size() - 1, static_cast<size_t>(0.95 * sorted.size()));
    std::nth_element(sorted.begin(), sorted.begin() + p95, sorted.end());
    quality.wall_distance_p95 = std::min(sorted[p95], 1e3f);
  }
  return quality;
}

cv::Mat3b drawMapComparison(const common::OccupancyGrid& map, const common::Pose2& world_from_map,
                            const common::OccupancyGrid& truth, const cv::Mat1b& observed) {
  const common::Pose2 map_from_world = common::invertPose(world_from_map);
  cv::Mat3b picture(truth.height(), truth.width(), cv::Vec3b(160, 160, 160));
  for (int row = 0; row < truth.height(); ++row) {
    for (int col = 0; col < truth.width(); ++col) {
      const int8_t true_value = truth.cells(row, col);
      const bool truly_free = isFree(true_value) && (observed.empty() || observed(row, col) != 0);
      int map_col = 0, map_row = 0;
      const int8_t mapped =
          !map.empty() &&
                  map.cellOf(common::transformPoint(map_from_world, truth.cellCentre(col, row)), &map_col, &map_row)
              ? map.cells(map_row, map_col)
              : common::OccupancyGrid::kUnknown;
      cv::Vec3b& pixel = picture(row, col);
      if (truly_free && isFree(mapped)) pixel = {255, 255, 255};
      else if (truly_free && isOccupied(mapped)) pixel = {255, 0, 255};
      else if (truly_free) pixel = mapped < 0 ? cv::Vec3b(0, 165, 255) : cv::Vec3b(0, 0, 255);
      else if (isFree(mapped)) pixel = {255, 0, 0};
      else if (isOccupied(true_value)) pixel = {0, 0, 0};
    }
  }
  return picture;
}

TrajectoryError trajectoryError(const std::vector<common::Pose2>& estimate, const std::vector<common::Pose2>& truth,
                                const common::Pose2& world_from_map) {
  TrajectoryError error;
  const size_t n = std::min(estimate.size(), truth.size());
  double position_sum = 0.0, yaw_sum = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const common::Pose2 placed = common::composePoses(world_from_map, estimate[i]);
    const double d = std::hypot(placed.x - truth[i].x, placed.y - truth[i].y);
    const double yaw = std::atan2(std::sin(placed.yaw - truth[i].yaw), std::cos(placed.yaw - truth[i].yaw));
    position_sum += d * d;
    yaw_sum += yaw * yaw;
    error.position_max = std::max(error.position_max, d);
  }
  error.poses = static_cast<int>(n);
  if (n > 0) {
    error.position_rmse = std::sqrt(position_sum / n);
    error.yaw_rmse = std::sqrt(yaw_sum / n);
  }
  // Relations between consecutive poses (Kummerle et al. 2009): the estimated motion against the true one.
  double translation_sum = 0.0, rotation_sum = 0.0, distance = 0.0;
  for (size_t i = 1; i < n; ++i) {
    const common::Pose2 moved = common::composePoses(common::invertPose(estimate[i - 1]), estimate[i]);
    const common::Pose2 truly = common::composePoses(common::invertPose(truth[i - 1]), truth[i]);
    translation_sum += std::hypot(moved.x - truly.x, moved.y - truly.y);
    rotation_sum += std::abs(common::wrapAngle(moved.yaw - truly.yaw));
    distance += std::hypot(truly.x, truly.y);
  }
  if (n > 1) {
    error.relations = static_cast<int>(n - 1);
    error.relative_translation_mean = translation_sum / (n - 1);
    error.relative_rotation_mean = rotation_sum / (n - 1);
    error.relative_translation_per_metre = distance > 0.0 ? translation_sum / distance : 0.0;
  }
  return error;
}

}  // namespace hidden_rooms::evaluation
