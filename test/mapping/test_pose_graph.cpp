// PoseGraph (MRPT's sparse pose adjustment): a loop of odometry edges that drifted, closed by one edge back to the
// start, comes out close to the true poses; bad edges are refused.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "hidden_rooms/mapping/pose_graph.h"

namespace hidden_rooms::mapping {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The corners of a 10 m square, walked counter-clockwise, 1 m apart (40 poses), heading along the side.
std::vector<common::Pose2> squareLoop() {
  std::vector<common::Pose2> poses;
  for (int side = 0; side < 4; ++side)
    for (int step = 0; step < 10; ++step) {
      const double yaw = side * kPi / 2.0;
      const common::Pose2 corner = side == 0   ? common::Pose2{0, 0, 0}
                                   : side == 1 ? common::Pose2{10, 0, 0}
                                   : side == 2 ? common::Pose2{10, 10, 0}
                                               : common::Pose2{0, 10, 0};
      poses.push_back({corner.x + step * std::cos(yaw), corner.y + step * std::sin(yaw), yaw});
    }
  return poses;
}

double worstError(const PoseGraph& graph, const std::vector<common::Pose2>& truth) {
  double worst = 0.0;
  for (size_t i = 0; i < truth.size(); ++i)
    worst = std::max(worst, std::hypot(graph.pose(i).x - truth[i].x, graph.pose(i).y - truth[i].y));
  return worst;
}

TEST(PoseGraph, ALoopEdgeTakesOutTheDriftOfTheOdometryEdges) {
  const std::vector<common::Pose2> truth = squareLoop();
  const Eigen::Matrix3d odometry_covariance = Eigen::Vector3d(0.05 * 0.05, 0.05 * 0.05, 0.01 * 0.01).asDiagonal();
  PoseGraph graph;
  // Each measured step turns 1 degree too far and is 3 % too long; the initial estimates chain them.
  common::Pose2 estimate = truth[0];
  graph.addNode(estimate);
  for (size_t i = 1; i < truth.size(); ++i) {
    common::Pose2 step = common::composePoses(common::invertPose(truth[i - 1]), truth[i]);
    step.x *= 1.03;
    step.y *= 1.03;
    step.yaw += kPi / 180.0;
    estimate = common::composePoses(estimate, step);
    graph.addNode(estimate);
    graph.addEdge(i - 1, i, step, odometry_covariance);
  }
  const double drifted = worstError(graph, truth);
  // The loop: the last pose seen from the first one as it truly is, more certain than a step.
  graph.addEdge(0, truth.size() - 1, common::composePoses(common::invertPose(truth[0]), truth.back()),
                Eigen::Vector3d(0.01 * 0.01, 0.01 * 0.01, 0.002 * 0.002).asDiagonal());
  EXPECT_EQ(graph.size(), truth.size());
  EXPECT_EQ(graph.edges(), truth.size());
  EXPECT_GT(graph.optimize(), 0u);
  const double closed = worstError(graph, truth);
  std::printf("worst position error: %.2f m drifted, %.2f m with the loop closed\n", drifted, closed);
  EXPECT_GT(drifted, 3.0);
  EXPECT_LT(closed, 0.5);
  // The first node stays where it was.
  EXPECT_DOUBLE_EQ(graph.pose(0).x, truth[0].x);
  EXPECT_DOUBLE_EQ(graph.pose(0).y, truth[0].y);
}

TEST(PoseGraph, RefusesEdgesBetweenMissingNodesAndSingularCovariances) {
  PoseGraph graph;
  graph.addNode({0, 0, 0});
  graph.addNode({1, 0, 0});
  const Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  EXPECT_THROW(graph.addEdge(0, 2, {1, 0, 0}, covariance), std::invalid_argument);
  EXPECT_THROW(graph.addEdge(1, 1, {0, 0, 0}, covariance), std::invalid_argument);
  EXPECT_THROW(graph.addEdge(0, 1, {1, 0, 0}, Eigen::Matrix3d::Zero()), std::invalid_argument);
  EXPECT_EQ(graph.edges(), 0u);
  EXPECT_EQ(PoseGraph().optimize(), 0u);  // nothing to move
}

}  // namespace
}  // namespace hidden_rooms::mapping
