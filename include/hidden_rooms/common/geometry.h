#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace hidden_rooms::common {

using Point2 = Eigen::Vector2d;
// A simple polygon as its vertex list, without repeating the first vertex at the end.
using Polygon = std::vector<Point2>;

// Shoelace area: positive for counter-clockwise vertex order (x right, y up).
double signedArea(const Polygon& polygon);
double area(const Polygon& polygon);

// Removes consecutive vertices closer than `tolerance` and a closing vertex equal to the first one.
Polygon withoutRepeatedVertices(const Polygon& polygon, double tolerance = 1e-9);

// True when two non-adjacent edges properly cross (each passes through the interior of the other). Touching
// (a vertex on another edge, collinear overlaps, spurs) is not crossing: real floor-plan outlines often touch
// themselves but a crossing outline has no well-defined inside. Crossings within `vertex_tolerance` of an end
// of either edge are drawing slop at a corner and do not count. On true, `problem` (if given) names the pair.
bool hasCrossing(const Polygon& polygon, double vertex_tolerance, std::string* problem = nullptr);

// Euclidean distance from `p` to the closed segment [a, b].
double distanceToSegment(const Point2& p, const Point2& a, const Point2& b);

// Position of the projection of `p` on the line through a and b, as a fraction of |b - a| from a.
double projectionParameter(const Point2& p, const Point2& a, const Point2& b);

// A planar pose: position (metres) and heading (radians, counter-clockwise from x).
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
};

// Pose composition and inverse in the plane (a then b: b expressed in a's frame).
Pose2 composePoses(const Pose2& a, const Pose2& b);
Pose2 invertPose(const Pose2& pose);
// A point given in `pose`'s frame, in the frame `pose` is expressed in.
Point2 transformPoint(const Pose2& pose, const Point2& point);
// Angle wrapped into [-pi, pi].
double wrapAngle(double angle);
// The direction of a line: the angle folded into [0, pi).
double angleModuloPi(double angle);

}  // namespace hidden_rooms::common
