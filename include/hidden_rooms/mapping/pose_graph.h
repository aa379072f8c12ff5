#pragma once

#include <cstddef>
#include <memory>

#include <Eigen/Core>

#include "hidden_rooms/common/geometry.h"

namespace hidden_rooms::mapping {

// A graph of 2D poses (nodes) and measured relative poses between them (edges, each with its covariance in the
// frame of its first node: x, y, yaw), optimized by MRPT's sparse pose adjustment (Konolige et al. 2010,
// mrpt::graphslam::optimize_graph_spa_levmarq). The first node is held fixed.
class PoseGraph {
 public:
  PoseGraph();
  ~PoseGraph();
  PoseGraph(const PoseGraph&) = delete;
  PoseGraph& operator=(const PoseGraph&) = delete;

  // A node at `pose` (its initial estimate); returns its id: 0, 1, 2, ... in order of addition.
  size_t addNode(const common::Pose2& pose);
  // `relative`: the pose of node `to` in the frame of node `from`. Both must exist; the covariance must be
  // symmetric positive definite.
  void addEdge(size_t from, size_t to, const common::Pose2& relative, const Eigen::Matrix3d& covariance);
  // Moves every node but the first to the poses that fit the edges best (least squares weighted by the
  // edges' information). Returns the number of iterations run.
  size_t optimize();

  size_t size() const;
  size_t edges() const;
  common::Pose2 pose(size_t node) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hidden_rooms::mapping
