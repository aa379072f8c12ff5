#include "hidden_rooms/mapping/pose_graph.h"

#include <stdexcept>
#include <string>

#include <mrpt/graphs/CNetworkOfPoses.h>
#include <mrpt/graphslam/levmarq.h>
#include <mrpt/poses/CPosePDFGaussianInf.h>

namespace hidden_rooms::mapping {

struct PoseGraph::Impl {
  mrpt::graphs::CNetworkOfPoses2DInf graph;
  size_t nodes = 0;
};

PoseGraph::PoseGraph() : impl_(std::make_unique<Impl>()) { impl_->graph.root = 0; }

PoseGraph::~PoseGraph() = default;

size_t PoseGraph::addNode(const common::Pose2& pose) {
  const size_t id = impl_->nodes++;
  impl_->graph.nodes[id] = mrpt::poses::CPose2D(pose.x, pose.y, pose.yaw);
  return id;
}

void PoseGraph::addEdge(size_t from, size_t to, const common::Pose2& relative, const Eigen::Matrix3d& covariance) {
  if (from >= impl_->nodes || to >= impl_->nodes || from == to)
    throw std::invalid_argument("PoseGraph::addEdge: bad nodes " + std::to_string(from) + " -> " + std::to_string(to));
  mrpt::poses::CPosePDFGaussianInf edge;
  edge.mean = mrpt::poses::CPose2D(relative.x, relative.y, relative.yaw);
  const Eigen::Matrix3d information = covariance.inverse();
  if (!information.allFinite()) throw std::invalid_argument("PoseGraph::addEdge: singular covariance");
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) edge.cov_inv(r, c) = 0.5 * (information(r, c) + information(c, r));
  impl_->graph.insertEdge(from, to, edge);
}

size_t PoseGraph::optimize() {
  if (impl_->nodes < 2) return 0;
  mrpt::graphslam::TResultInfoSpaLevMarq info;
  mrpt::containers::yaml parameters = mrpt::containers::yaml::Map();
  parameters["max_iterations"] = 50;
  mrpt::graphslam::optimize_graph_spa_levmarq(impl_->graph, info, nullptr, parameters);
  return info.num_iters;
}

size_t PoseGraph::size() const { return impl_->nodes; }

size_t PoseGraph::edges() const { return impl_->graph.edgeCount(); }

common::Pose2 PoseGraph::pose(size_t node) const {
  const mrpt::poses::CPose2D& p = impl_->graph.nodes.at(node);
  return {p.x(), p.y(), p.phi()};
}

}  // namespace hidden_rooms::mapping
