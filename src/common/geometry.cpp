#include "hidden_rooms/common/geometry.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace hidden_rooms::common {

namespace {

double cross(const Point2& a, const Point2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Orientation of the triple (a, b, c): +1 counter-clockwise, -1 clockwise, 0 collinear.
int orientation(const Point2& a, const Point2& b, const Point2& c) {
  const double value = cross(b - a, c - a);
  const double scale = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), 1e-30});
  if (std::abs(value) <= 1e-12 * scale) return 0;
  return value > 0 ? 1 : -1;
}

}  // namespace

double signedArea(const Polygon& polygon) {
  double twice_area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i)
    twice_area += cross(polygon[i], polygon[(i + 1) % polygon.size()]);
  return 0.5 * twice_area;
}

double area(const Polygon& polygon) { return std::abs(signedArea(polygon)); }

Polygon withoutRepeatedVertices(const Polygon& polygon, double tolerance) {
  Polygon result;
  for (const Point2& vertex : polygon)
    if (result.empty() || (vertex - result.back()).norm() > tolerance) result.push_back(vertex);
  while (result.size() > 1 && (result.front() - result.back()).norm() <= tolerance) result.pop_back();
  return result;
}

bool hasCrossing(const Polygon& polygon, double vertex_tolerance, std::string* problem) {
  const size_t n = polygon.size();
  for (size_t i = 0; i < n; ++i) {
    const Point2& a = polygon[i];
    const Point2& b = polygon[(i + 1) % n];
    for (size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // adjacent through the closing vertex
      const Point2& c = polygon[j];
      const Point2& d = polygon[(j + 1) % n];
      if (orientation(a, b, c) * orientation(a, b, d) < 0 && orientation(c, d, a) * orientation(c, d, b) < 0) {
        const double t = cross(c - a, d - c) / cross(b - a, d - c);
        const Point2 crossing = a + t * (b - a);
        const double to_vertex = std::min({(crossing - a).norm(), (crossing - b).norm(), (crossing - c).norm(),
                                           (crossing - d).norm()});
        if (to_vertex <= vertex_tolerance) continue;
        if (problem != nullptr) {
          std::ostringstream text;
          text << "edge " << i << " (" << a.transpose() << " -> " << b.transpose() << ") crosses edge " << j << " ("
               << c.transpose() << " -> " << d.transpose() << ")";
          *problem = text.str();
        }
        return true;
      }
    }
  }
  return false;
}

double distanceToSegment(const Point2& p, const Point2& a, const Point2& b) {
  const double t = std::clamp(projectionParameter(p, a, b), 0.0, 1.0);
  return (p - (a + t * (b - a))).norm();
}

double projectionParameter(const Point2& p, const Point2& a, const Point2& b) {
  const double length_squared = (b - a).squaredNorm();
  if (length_squared <= 0.0) return 0.0;
  return (p - a).dot(b - a) / length_squared;
}

double wrapAngle(double angle) { return std::atan2(std::sin(angle), std::cos(angle)); }

double angleModuloPi(double angle) {
  angle = std::fmod(angle, M_PI);
  if (angle < 0) angle += M_PI;
  if (angle >= M_PI) angle -= M_PI;
  return angle;
}

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

}  // namespace hidden_rooms::common
