#include "hidden_rooms/range_scan.h"

#include <cmath>

namespace hidden_rooms {

double wrapAngle(double angle) { return std::atan2(std::sin(angle), std::cos(angle)); }

Pose2 composePoses(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.yaw), s = std::sin(a.yaw);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrapAngle(a.yaw + b.yaw)};
}

Pose2 invertPose(const Pose2& pose) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  return {-c * pose.x - s * pose.y, s * pose.x - c * pose.y, wrapAngle(-pose.yaw)};
}

Point2 transformPoint(const Pose2& pose, const Point2& point) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  return {pose.x + c * point.x() - s * point.y(), pose.y + s * point.x() + c * point.y()};
}

}  // namespace hidden_rooms
