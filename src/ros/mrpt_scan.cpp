#include "ros/mrpt_scan.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <mrpt/poses/CPose3D.h>
#include <mrpt/ros1bridge/laser_scan.h>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms {

mrpt::obs::CObservation2DRangeScan toMrptScan(const sensor_msgs::LaserScan& message, const common::Pose2& sensor_pose) {
  const size_t n = message.ranges.size();
  if (n < 2) throw common::InputError("scan", "has " + std::to_string(n) + " beams; at least 2 are needed");
  if (!std::isfinite(message.angle_min) || !std::isfinite(message.angle_increment) || message.angle_increment == 0.0f)
    throw common::InputError("scan", "angle_min and angle_increment must be finite, the increment non-zero");
  if (!std::isfinite(message.range_max) || !(message.range_max > 0.0f))
    throw common::InputError("scan", "range_max must be positive and finite");
  if (!std::isfinite(sensor_pose.x) || !std::isfinite(sensor_pose.y) || !std::isfinite(sensor_pose.yaw))
    throw common::InputError("scan", "the pose of frame " + message.header.frame_id + " in base_link is not finite");

  // What fromROS expects: beams counter-clockwise from angle_min = -angle_max (it maps MRPT's beams from
  // -aperture/2 on and wraps indices otherwise). The scan's middle direction goes into the sensor pose.
  sensor_msgs::LaserScan symmetric = message;
  const bool clockwise = message.angle_increment < 0.0f;
  if (clockwise) std::reverse(symmetric.ranges.begin(), symmetric.ranges.end());
  const double increment = std::abs(static_cast<double>(message.angle_increment));
  const double half_aperture = 0.5 * increment * static_cast<double>(n - 1);
  const double middle = static_cast<double>(message.angle_min) +
                        0.5 * static_cast<double>(message.angle_increment) * static_cast<double>(n - 1);
  symmetric.angle_min = static_cast<float>(-half_aperture);
  symmetric.angle_max = static_cast<float>(half_aperture);
  symmetric.angle_increment = static_cast<float>(increment);

  mrpt::obs::CObservation2DRangeScan scan;
  const mrpt::poses::CPose3D sensor(sensor_pose.x, sensor_pose.y, 0.0, sensor_pose.yaw + middle, 0.0, 0.0);
  if (!mrpt::ros1bridge::fromROS(symmetric, sensor, scan) || scan.getScanSize() != n)
    throw common::InputError("scan", "mrpt::ros1bridge could not convert it");
  // fromROS picks MRPT beam i from the message beam at the truncated product of two rounded floating-point
  // factors, which for some increments is the neighbour (5 beams 0.01 rad apart come out shifted by one). So
  // each beam is set again from the message by index, with fromROS's validity rule (strictly between range_min
  // and 0.99 range_max; NaN compares false). Invalid beams keep a finite range (range_max) for MRPT.
  for (size_t i = 0; i < n; ++i) {
    const float range = symmetric.ranges[i];
    const bool valid = isValidRange(message, range);
    scan.setScanRange(i, valid ? range : message.range_max);
    scan.setScanRangeValidity(i, valid);
  }
  return scan;
}

bool isValidRange(const sensor_msgs::LaserScan& message, float range) {
  return std::isfinite(range) && range > message.range_min && range < 0.99f * message.range_max;
}

size_t countValidRanges(const sensor_msgs::LaserScan& message) {
  return static_cast<size_t>(std::count_if(message.ranges.begin(), message.ranges.end(),
                                           [&](float range) { return isValidRange(message, range); }));
}

}  // namespace hidden_rooms
