#pragma once

#include <vector>

#include "hidden_rooms/laser_caster.h"

namespace hidden_rooms {

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

// Pose composition and inverse in the plane (a then b: b expressed in a's frame).
Pose2 composePoses(const Pose2& a, const Pose2& b);
Pose2 invertPose(const Pose2& pose);
// A point given in `pose`'s frame, in the frame `pose` is expressed in.
Point2 transformPoint(const Pose2& pose, const Point2& point);
// Angle wrapped into [-pi, pi].
double wrapAngle(double angle);

}  // namespace hidden_rooms
