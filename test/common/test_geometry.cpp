#include <gtest/gtest.h>

#include <cmath>

#include "hidden_rooms/common/geometry.h"

namespace hidden_rooms::common {
namespace {

TEST(Geometry, AreaOfPolygons) {
  const Polygon square{{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  EXPECT_DOUBLE_EQ(signedArea(square), 4.0);
  const Polygon clockwise(square.rbegin(), square.rend());
  EXPECT_DOUBLE_EQ(signedArea(clockwise), -4.0);
  EXPECT_DOUBLE_EQ(area(clockwise), 4.0);
  const Polygon l_shape{{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}};
  EXPECT_DOUBLE_EQ(area(l_shape), 5.0);
}

TEST(Geometry, RemovesRepeatedAndClosingVertices) {
  const Polygon raw{{0, 0}, {0, 0}, {1, 0}, {1, 1}, {1, 1}, {0, 0}};
  EXPECT_EQ(withoutRepeatedVertices(raw).size(), 3u);
}

TEST(Geometry, CrossingOutlinesAreFoundTouchingOnesAreNot) {
  std::string problem;
  const Polygon bow_tie{{0, 0}, {2, 2}, {2, 0}, {0, 2}};
  EXPECT_TRUE(hasCrossing(bow_tie, 0.1, &problem));
  EXPECT_NE(problem.find("crosses"), std::string::npos);
  const Polygon square{{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  EXPECT_FALSE(hasCrossing(square, 0.1));
  // A spur touching its own edge, as real floor plans have.
  const Polygon touching{{0, 0}, {4, 0}, {4, 2}, {2, 2}, {2, 0}, {0, 0.0001}};
  EXPECT_FALSE(hasCrossing(withoutRepeatedVertices(touching), 0.1));
  // A crossing near a corner is drawing slop within the tolerance, a real crossing beyond it.
  const Polygon corner_slop{{0, 0}, {4, 0}, {4, 4}, {-0.1, 4}, {0, 4.1}};  // last edge crosses at (0, 4)
  EXPECT_FALSE(hasCrossing(corner_slop, 0.25));
  EXPECT_TRUE(hasCrossing(corner_slop, 0.01));
}

TEST(Geometry, DistanceToSegment) {
  EXPECT_DOUBLE_EQ(distanceToSegment({1, 1}, {0, 0}, {2, 0}), 1.0);
  EXPECT_DOUBLE_EQ(distanceToSegment({3, 0}, {0, 0}, {2, 0}), 1.0);
  EXPECT_DOUBLE_EQ(distanceToSegment({5, 5}, {1, 1}, {1, 1}), std::sqrt(32.0));
  EXPECT_DOUBLE_EQ(projectionParameter({1, 5}, {0, 0}, {2, 0}), 0.5);
}

}  // namespace
}  // namespace hidden_rooms::common
