#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace hidden_rooms {

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

}  // namespace hidden_rooms
