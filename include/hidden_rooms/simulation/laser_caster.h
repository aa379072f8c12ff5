#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/range_scan.h"

class b2World;
class b2Body;

namespace hidden_rooms::simulation {

// Casts every beam of a laser at `laser_pose` (world frame) and writes the distance to the first solid thing
// (metres, noise-free) or max_range when there is none within it.
class LaserCaster {
 public:
  virtual ~LaserCaster() = default;
  virtual void cast(const common::Pose2& laser_pose, const common::LaserGeometry& laser,
                    std::vector<float>* ranges) const = 0;
};

// Exact ray casts against the static fixtures of a Box2D world (b2World::RayCast, closest hit); fixtures of
// `ignored` (the robot) and disabled bodies (open doors) are not seen.
class Box2dLaserCaster : public LaserCaster {
 public:
  Box2dLaserCaster(const b2World* world, const b2Body* ignored) : world_(world), ignored_(ignored) {}
  void cast(const common::Pose2& laser_pose, const common::LaserGeometry& laser,
            std::vector<float>* ranges) const override;

 private:
  const b2World* world_;
  const b2Body* ignored_;
};

// Ray casts through an occupancy grid with the exact voxel traversal of Amanatides and Woo (every cell a beam
// crosses is visited, so beams never slip between diagonal walls as Bresenham's lines do): the range is the
// distance to the border of the first occupied cell. Outside the grid nothing is solid.
class GridLaserCaster : public LaserCaster {
 public:
  // `occupied`: non-zero on solid cells, image order (row 0 at the top) as OccupancyGrid stores cells.
  GridLaserCaster(const cv::Mat1b& occupied, double resolution, const common::Point2& origin);
  void cast(const common::Pose2& laser_pose, const common::LaserGeometry& laser,
            std::vector<float>* ranges) const override;
  // One ray from `start` along the unit vector `direction`.
  double castRay(const common::Point2& start, const common::Point2& direction, double max_range) const;

 private:
  std::vector<uint8_t> cells_;  // row-major, row 0 at the bottom (y up)
  int width_ = 0;
  int height_ = 0;
  double resolution_ = 0.05;
  common::Point2 origin_ = common::Point2::Zero();
};

}  // namespace hidden_rooms::simulation
