#pragma once

#include <vector>

#include "hidden_rooms/common/geometry.h"

namespace hidden_rooms::common {

// The beams of a 2D laser in its own frame: beam k points at angle_min + k * angle_increment.
struct LaserGeometry {
  int beams = 1081;
  double angle_min = -2.356194490192345;       // -135 degrees
  double angle_increment = 0.004363323129985824;  // 270 degrees / 1080
  double max_range = 30.0;                     // metres; beams that hit nothing return exactly this
};

// One planar laser scan, independent of any middleware: beam k points at angle_min + k * angle_increment in the
// laser frame (counter-clockwise for a positive increment).
struct RangeScan {
  double angle_min = 0.0;
  double angle_increment = 0.0;
  double range_min = 0.0;  // metres; returns at or below it are invalid
  double range_max = 0.0;  // metres; returns at or beyond it mean "nothing hit"
  std::vector<float> ranges;
  Pose2 sensor_pose;       // base_link -> laser frame

  // A beam's return counts as a hit: finite and strictly between range_min and range_max.
  bool valid(size_t k) const { return ranges[k] > range_min && ranges[k] < range_max; }
};

}  // namespace hidden_rooms::common
