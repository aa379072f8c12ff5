#include "hidden_rooms/mapping/scan_matched_odometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/mapping/pose_graph.h"

namespace hidden_rooms::mapping {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxPoints = 360;
constexpr size_t kMaxKeyframes = 20000;  // keyframes kept for map_radius (a 4 km path at 0.2 m)
constexpr double kWindowSigmas = 3.0;  // the search window: the prediction's std. dev. times this, each way
constexpr double kMaxWindow = 0.5;     // metres and ...
constexpr double kMaxWindowAngle = 10.0 * kPi / 180.0;  // ... radians of the window at most

// The scan's valid returns in the robot frame (the laser's mount applied).
std::vector<common::Point2> robotFramePoints(const mrpt::obs::CObservation2DRangeScan& scan, double max_range) {
  std::vector<common::Point2> points;
  const size_t n = scan.getScanSize();
  const double increment = n > 1 ? scan.aperture / static_cast<double>(n - 1) : 0.0;
  const mrpt::poses::CPose3D& sensor = scan.sensorPose;
  for (size_t i = 0; i < n; ++i) {
    if (!scan.getScanRangeValidity(i)) continue;
    const double range = scan.getScanRange(i);
    if (!(range > 0.0) || range >= std::min<double>(scan.maxRange, max_range)) continue;
    const double angle = -0.5 * scan.aperture + increment * static_cast<double>(scan.rightToLeft ? i : n - 1 - i);
    double x = 0.0, y = 0.0, z = 0.0;
    sensor.composePoint(range * std::cos(angle), range * std::sin(angle), 0.0, x, y, z);
    points.emplace_back(x, y);
  }
  if (points.size() > static_cast<size_t>(kMaxPoints)) {
    std::vector<common::Point2> thinned;
    for (int k = 0; k < kMaxPoints; ++k) thinned.push_back(points[k * points.size() / kMaxPoints]);
    points.swap(thinned);
  }
  return points;
}

common::Point2 transformed(const common::Pose2& pose, const common::Point2& p) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  return {pose.x + c * p.x() - s * p.y(), pose.y + s * p.x() + c * p.y()};
}

}  // namespace

ScanMatchingOptions readScanMatchingOptions(const mrpt::config::CConfigFileBase& ini, const std::string& file) {
  ScanMatchingOptions options;
  const std::string section = "ScanMatching";
  if (!ini.sectionExists(section)) return options;
  options.enabled = ini.read_bool(section, "enabled", options.enabled);
  options.keyframe_distance = ini.read_double(section, "keyframe_distance", options.keyframe_distance);
  options.keyframe_angle_deg = ini.read_double(section, "keyframe_angle_deg", options.keyframe_angle_deg);
  options.local_map_scans = ini.read_int(section, "local_map_scans", options.local_map_scans);
  options.resolution = ini.read_double(section, "resolution", options.resolution);
  options.angle_step_deg = ini.read_double(section, "angle_step_deg", options.angle_step_deg);
  options.point_sigma = ini.read_double(section, "point_sigma", options.point_sigma);
  options.min_goodness = ini.read_double(section, "min_goodness", options.min_goodness);
  options.max_range = ini.read_double(section, "max_range", options.max_range);
  options.map_radius = ini.read_double(section, "map_radius", options.map_radius);
  options.loop_min_travel = ini.read_double(section, "loop_min_travel", options.loop_min_travel);
  options.loop_search_radius = ini.read_double(section, "loop_search_radius", options.loop_search_radius);
  options.loop_search_angle_deg = ini.read_double(section, "loop_search_angle_deg", options.loop_search_angle_deg);
  options.loop_min_goodness = ini.read_double(section, "loop_min_goodness", options.loop_min_goodness);
  options.loop_check_distance = ini.read_double(section, "loop_check_distance", options.loop_check_distance);
  for (double value : {options.max_range, options.keyframe_distance, options.keyframe_angle_deg, options.resolution,
                       options.angle_step_deg, options.point_sigma})
    if (!std::isfinite(value) || value <= 0.0)
      throw common::InputError(file, "[ScanMatching] distances, angles, resolution and sigma must be positive");
  if (options.local_map_scans < 1) throw common::InputError(file, "[ScanMatching] local_map_scans must be at least 1");
  if (!(options.min_goodness >= 0.0 && options.min_goodness <= 1.0) ||
      !(options.loop_min_goodness >= 0.0 && options.loop_min_goodness <= 1.0))
    throw common::InputError(file, "[ScanMatching] min_goodness and loop_min_goodness must be in [0, 1]");
  if (!(options.map_radius >= 0.0) || !(options.loop_min_travel >= 0.0) || !std::isfinite(options.loop_min_travel))
    throw common::InputError(file, "[ScanMatching] map_radius and loop_min_travel must be zero or positive");
  if (options.loop_min_travel > 0.0)
    for (double value : {options.loop_search_radius, options.loop_search_angle_deg, options.loop_check_distance})
      if (!std::isfinite(value) || value <= 0.0)
        throw common::InputError(file, "[ScanMatching] loop_search_radius, loop_search_angle_deg and "
                                       "loop_check_distance must be positive");
  return options;
}

struct ScanMatchedOdometry::Keyframe {
  std::vector<common::Point2> points;  // robot frame
  common::Pose2 pose;
  double travelled = 0.0;  // metres of corrected path from the first keyframe
  size_t id = 0;           // its node in the pose graph (with loop closure)
};

// The log-likelihood of a point at each cell: log(exp(-d^2 / (2 sigma^2)) + floor), d the distance to the
// nearest map point.
struct ScanLikelihoodField {
  double resolution = 0.0;
  common::Point2 origin;  // metres: the corner of cell (0, 0)
  cv::Mat1f log_likelihood;
  float outside = 0.0f;   // the value off the map (the floor's)
  cv::Mat1b near;         // non-zero where a point is within 2 sigma of the map
};

namespace {

ScanLikelihoodField likelihoodField(const std::vector<common::Point2>& world, double resolution, double sigma) {
  constexpr double kMargin = 1.0;  // metres around the points
  constexpr double kFloor = 0.01;  // likelihood of a point far from the map (clutter, people, new walls)
  ScanLikelihoodField field;
  field.resolution = resolution;
  field.outside = static_cast<float>(std::log(kFloor));
  if (world.empty()) return field;
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x, max_x = -min_x, max_y = -min_x;
  for (const common::Point2& p : world) {
    min_x = std::min(min_x, p.x()), max_x = std::max(max_x, p.x());
    min_y = std::min(min_y, p.y()), max_y = std::max(max_y, p.y());
  }
  const double r = resolution;
  field.origin = common::Point2(min_x - kMargin, min_y - kMargin);
  const int cols = static_cast<int>(std::ceil((max_x - min_x + 2 * kMargin) / r)) + 1;
  const int rows = static_cast<int>(std::ceil((max_y - min_y + 2 * kMargin) / r)) + 1;
  cv::Mat1b free_of_points(rows, cols, uchar(255));
  for (const common::Point2& p : world) {
    const int col = static_cast<int>((p.x() - field.origin.x()) / r);
    const int row = static_cast<int>((p.y() - field.origin.y()) / r);
    if (col >= 0 && row >= 0 && col < cols && row < rows) free_of_points(row, col) = 0;
  }
  cv::Mat1f distance;
  cv::distanceTransform(free_of_points, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  const double sigma_cells = sigma / r;
  // Per distance (a tenth of a cell apart) up to where the floor dominates: the log-likelihood.
  constexpr int kSteps = 10;
  const int table_size = static_cast<int>(std::ceil(5.0 * sigma_cells * kSteps)) + 1;
  std::vector<float> table(table_size);
  for (int k = 0; k < table_size; ++k) {
    const double d = static_cast<double>(k) / kSteps;
    table[k] = static_cast<float>(std::log(std::exp(-0.5 * d * d / (sigma_cells * sigma_cells)) + kFloor));
  }
  field.log_likelihood.create(rows, cols);
  field.near = distance <= 2.0 * sigma_cells;
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const int k = static_cast<int>(distance(row, col) * kSteps);
      field.log_likelihood(row, col) = k < table_size ? table[k] : field.outside;
    }
  return field;
}

// The Gaussian prior of a search: the prediction's std. dev. in position and heading.
struct SearchPrior {
  double sigma_xy, sigma_phi;
};

struct Match {
  common::Pose2 best;             // the window's most likely pose
  common::Pose2 mean;             // the posterior's mean over the window
  Eigen::Matrix3d covariance;     // and its covariance (x, y, yaw; world frame)
  int near = 0;                   // points within 2 sigma of the map at the best pose
};

// The correlative search (Olson 2009): the scan's log-likelihood at every pose of the window around `centre`
// (half_xy cells of the field each way, half_phi steps of angle_step), plus the prior's when given.
Match searchWindow(const ScanLikelihoodField& field, const std::vector<common::Point2>& points,
                   const common::Pose2& centre, int half_xy, int half_phi, double angle_step,
                   const SearchPrior* prior) {
  const double r = field.resolution;
  const int side = 2 * half_xy + 1;
  double best = -std::numeric_limits<double>::infinity();
  int best_index = 0, best_near = 0;
  std::vector<double> scores((2 * half_phi + 1) * side * side);
  std::vector<cv::Point> cells(points.size());
  for (int a = -half_phi; a <= half_phi; ++a) {
    const common::Pose2 turned{centre.x, centre.y, centre.yaw + a * angle_step};
    for (size_t i = 0; i < points.size(); ++i) {
      const common::Point2 p = transformed(turned, points[i]);
      cells[i] = cv::Point(static_cast<int>(std::floor((p.x() - field.origin.x()) / r)),
                           static_cast<int>(std::floor((p.y() - field.origin.y()) / r)));
    }
    for (int dy = -half_xy; dy <= half_xy; ++dy)
      for (int dx = -half_xy; dx <= half_xy; ++dx) {
        double score = 0.0;
        int near = 0;
        for (const cv::Point& cell : cells) {
          const int col = cell.x + dx, row = cell.y + dy;
          if (col < 0 || row < 0 || col >= field.log_likelihood.cols || row >= field.log_likelihood.rows) {
            score += field.outside;
          } else {
            score += field.log_likelihood(row, col);
            near += field.near(row, col) != 0;
          }
        }
        if (prior != nullptr) {
          const double ex = dx * r / prior->sigma_xy, ey = dy * r / prior->sigma_xy,
                       ephi = a * angle_step / prior->sigma_phi;
          score -= 0.5 * (ex * ex + ey * ey + ephi * ephi);
        }
        const int index = ((a + half_phi) * side + (dy + half_xy)) * side + (dx + half_xy);
        scores[index] = score;
        if (score > best) best = score, best_index = index, best_near = near;
      }
  }
  // The posterior's mean and covariance over the window.
  double weight_sum = 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (int a = -half_phi; a <= half_phi; ++a)
    for (int dy = -half_xy; dy <= half_xy; ++dy)
      for (int dx = -half_xy; dx <= half_xy; ++dx) {
        const double w = std::exp(scores[((a + half_phi) * side + (dy + half_xy)) * side + (dx + half_xy)] - best);
        const Eigen::Vector3d offset(dx * r, dy * r, a * angle_step);
        weight_sum += w;
        mean += w * offset;
        second += w * offset * offset.transpose();
      }
  mean /= weight_sum;
  Match match;
  match.covariance = second / weight_sum - mean * mean.transpose();
  match.mean = {centre.x + mean.x(), centre.y + mean.y(), common::wrapAngle(centre.yaw + mean.z())};
  const int a = best_index / (side * side) - half_phi, dy = (best_index / side) % side - half_xy,
            dx = best_index % side - half_xy;
  match.best = {centre.x + dx * r, centre.y + dy * r, common::wrapAngle(centre.yaw + a * angle_step)};
  match.near = best_near;
  return match;
}

// The least uncertainty of a match: a cell of the search and an angle step (x, y, yaw).
Eigen::Matrix3d searchCellCovariance(const ScanMatchingOptions& options) {
  const Eigen::Vector3d cell(options.resolution, options.resolution, options.angle_step_deg * kPi / 180.0);
  return cell.cwiseAbs2().asDiagonal();
}

// The covariance of `covariance` (world frame x, y, yaw) in the frame of a node at heading `yaw`.
Eigen::Matrix3d inFrame(const Eigen::Matrix3d& covariance, double yaw) {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  rotation.topLeftCorner<2, 2>() << std::cos(yaw), std::sin(yaw), -std::sin(yaw), std::cos(yaw);
  return rotation * covariance * rotation.transpose();
}

}  // namespace

ScanMatchedOdometry::ScanMatchedOdometry(const ScanMatchingOptions& options, const MotionNoise& noise)
    : options_(options), noise_(noise) {
  if (options_.loop_min_travel > 0.0) graph_ = std::make_unique<PoseGraph>();
}

ScanMatchedOdometry::~ScanMatchedOdometry() = default;

void ScanMatchedOdometry::rebuildLocalMap() {
  std::vector<common::Point2> world;
  // The last local_map_scans keyframes, and with map_radius every older one that near the newest.
  const size_t recent_from = keyframes_.size() > static_cast<size_t>(options_.local_map_scans)
                                 ? keyframes_.size() - options_.local_map_scans
                                 : 0;
  const common::Pose2& newest = keyframes_.back()->pose;
  for (size_t k = 0; k < keyframes_.size(); ++k) {
    const auto& keyframe = keyframes_[k];
    if (k < recent_from &&
        std::hypot(keyframe->pose.x - newest.x, keyframe->pose.y - newest.y) > options_.map_radius)
      continue;
    for (const common::Point2& p : keyframe->points) world.push_back(transformed(keyframe->pose, p));
  }
  local_map_ = std::make_unique<ScanLikelihoodField>(likelihoodField(world, options_.resolution, options_.point_sigma));
}

void ScanMatchedOdometry::addKeyframe(const common::Pose2& pose, const std::vector<common::Point2>& points,
                                      const Eigen::Matrix3d& covariance) {
  if (!keyframes_.empty()) {
    const common::Pose2& previous = keyframes_.back()->pose;
    travelled_ += std::hypot(pose.x - previous.x, pose.y - previous.y);
  }
  auto keyframe = std::make_shared<Keyframe>(Keyframe{points, pose, travelled_, 0});
  if (graph_) {  // the node, and the edge from the keyframe before as the scan matched
    keyframe->id = graph_->addNode(pose);
    if (!keyframes_.empty()) {
      const Keyframe& previous = *keyframes_.back();
      graph_->addEdge(previous.id, keyframe->id, common::composePoses(common::invertPose(previous.pose), pose),
                      inFrame(covariance, previous.pose.yaw));
    }
  }
  keyframes_.push_back(keyframe);
  const size_t keep =
      options_.map_radius > 0.0 || graph_ ? kMaxKeyframes : static_cast<size_t>(options_.local_map_scans);
  while (keyframes_.size() > keep) keyframes_.pop_front();
  last_keyframe_ = pose;
  if (graph_ && travelled_ - last_loop_check_ >= options_.loop_check_distance) {
    last_loop_check_ = travelled_;
    if (closeLoop()) return;  // rebuilt the local map
  }
  rebuildLocalMap();
}

// The newest keyframe searched for in the map of the places the path left loop_min_travel or more before, near
// its pose; a good match becomes an edge and the graph is optimized. Returns true when the keyframes moved.
bool ScanMatchedOdometry::closeLoop() {
  const Keyframe& newest = *keyframes_.back();
  if (newest.points.empty()) return false;
  // The nearest of the keyframes the path left loop_min_travel or more before, and the map of its place: the
  // keyframes within half that much path of it, a stretch of path as consistent as the local map is.
  const Keyframe* nearest = nullptr;
  double nearest_distance = std::numeric_limits<double>::infinity();
  for (const auto& keyframe : keyframes_) {
    if (newest.travelled - keyframe->travelled < options_.loop_min_travel) break;  // in path order
    const double distance = std::hypot(keyframe->pose.x - newest.pose.x, keyframe->pose.y - newest.pose.y);
    if (distance < nearest_distance) nearest_distance = distance, nearest = keyframe.get();
  }
  if (nearest == nullptr || nearest_distance > options_.loop_search_radius + 0.5 * options_.max_range) {
    pending_loop_.reset();
    return false;
  }
  std::vector<common::Point2> world;
  for (const auto& keyframe : keyframes_)
    if (std::abs(keyframe->travelled - nearest->travelled) <= 0.5 * options_.loop_min_travel &&
        newest.travelled - keyframe->travelled >= options_.loop_min_travel)
      for (const common::Point2& p : keyframe->points) world.push_back(transformed(keyframe->pose, p));

  // Coarse to fine: a wide window on a field four times coarser (no prior: the drift since the place was left is
  // unknown), then the fine field around the coarse best.
  constexpr int kCoarse = 4;
  const double r = options_.resolution, coarse_r = kCoarse * r;
  const double angle_step = options_.angle_step_deg * kPi / 180.0, coarse_step = kCoarse * angle_step;
  const ScanLikelihoodField coarse = likelihoodField(world, coarse_r, std::max(options_.point_sigma, coarse_r));
  const int half_xy = static_cast<int>(std::ceil(options_.loop_search_radius / coarse_r));
  const int half_phi = static_cast<int>(std::ceil(options_.loop_search_angle_deg * kPi / 180.0 / coarse_step));
  const Match wide = searchWindow(coarse, newest.points, newest.pose, half_xy, half_phi, coarse_step, nullptr);
  const ScanLikelihoodField fine = likelihoodField(world, r, options_.point_sigma);
  const Match match = searchWindow(fine, newest.points, wide.best, kCoarse, kCoarse, angle_step, nullptr);
  if (match.near < options_.loop_min_goodness * static_cast<double>(newest.points.size())) {
    pending_loop_.reset();
    return false;
  }

  // The edge: where the newest keyframe is in the old place's frame, as uncertain as the wide search left it
  // (along a corridor the scan fits at many places) and never less than a cell and an angle step.
  const Eigen::Matrix3d covariance = wide.covariance + searchCellCovariance(options_);
  LoopCandidate candidate{nearest->id, newest.id, common::composePoses(common::invertPose(nearest->pose), match.mean),
                          inFrame(covariance, nearest->pose.yaw),
                          common::composePoses(match.mean, common::invertPose(newest.pose)), newest.travelled};
  // A loop is believed when the check before saw it the same way (its correction of the path within two cells
  // and two angle steps of the coarse search): a single match can pick the wrong one of two similar places.
  const bool confirmed =
      pending_loop_ && newest.travelled - pending_loop_->travelled <= 2.0 * options_.loop_check_distance + 1e-9 &&
      std::hypot(candidate.correction.x - pending_loop_->correction.x,
                 candidate.correction.y - pending_loop_->correction.y) <= 2.0 * coarse_r &&
      std::abs(common::wrapAngle(candidate.correction.yaw - pending_loop_->correction.yaw)) <= 2.0 * coarse_step;
  if (!confirmed) {
    pending_loop_ = candidate;
    return false;
  }
  for (const LoopCandidate& loop : {*pending_loop_, candidate})
    graph_->addEdge(loop.from, loop.to, loop.relative, loop.covariance);
  pending_loop_.reset();
  ++loop_closures_;
  const common::Pose2 before = newest.pose;
  graph_->optimize();
  for (const auto& keyframe : keyframes_) keyframe->pose = graph_->pose(keyframe->id);
  // The current pose moves with the newest keyframe.
  const common::Pose2 moved = common::composePoses(keyframes_.back()->pose, common::invertPose(before));
  last_corrected_ = common::composePoses(moved, last_corrected_);
  last_keyframe_ = keyframes_.back()->pose;
  rebuildLocalMap();
  return true;
}

KeyframeAnchor ScanMatchedOdometry::anchor(const common::Pose2& pose) const {
  if (!graph_ || keyframes_.empty()) return {KeyframeAnchor::kNone, pose};  // keyframes never move
  const Keyframe& newest = *keyframes_.back();
  return {newest.id, common::composePoses(common::invertPose(newest.pose), pose)};
}

common::Pose2 ScanMatchedOdometry::resolve(const KeyframeAnchor& anchor) const {
  if (anchor.keyframe == KeyframeAnchor::kNone) return anchor.offset;
  return common::composePoses(graph_->pose(anchor.keyframe), anchor.offset);
}

common::Pose2 ScanMatchedOdometry::correct(const common::Pose2& odometry,
                                           const mrpt::obs::CObservation2DRangeScan& scan) {
  const std::vector<common::Point2> points = robotFramePoints(scan, options_.max_range);
  const Eigen::Matrix3d floor = searchCellCovariance(options_);
  if (!started_) {
    started_ = true;
    last_odometry_ = last_corrected_ = odometry;
    addKeyframe(odometry, points, floor);
    return odometry;
  }
  // The odometry's prediction and its std. dev. (the motion model of the increment, isotropic in x and y).
  const common::Pose2 increment = common::composePoses(common::invertPose(last_odometry_), odometry);
  last_odometry_ = odometry;
  const common::Pose2 predicted = common::composePoses(last_corrected_, increment);
  const double distance = std::hypot(increment.x, increment.y), turn = std::abs(increment.yaw);
  const SearchPrior prior{
      std::max(noise_.min_xy + noise_.a1 * distance + noise_.a2 * turn, 0.5 * options_.resolution),
      std::max(noise_.min_phi + noise_.a3 * distance + noise_.a4 * turn, 0.5 * options_.angle_step_deg * kPi / 180.0)};

  // The corrected pose and its covariance (the edge from the last keyframe if it becomes one): the match's
  // posterior, else the prediction's.
  common::Pose2 corrected = predicted;
  const Eigen::Vector3d prior_sigmas(prior.sigma_xy, prior.sigma_xy, prior.sigma_phi);
  Eigen::Matrix3d covariance = prior_sigmas.cwiseAbs2().asDiagonal();
  const ScanLikelihoodField& map = *local_map_;
  if (!map.log_likelihood.empty() && !points.empty()) {
    const double r = options_.resolution;
    const int half_xy =
        std::max(1, static_cast<int>(std::ceil(std::min(kWindowSigmas * prior.sigma_xy, kMaxWindow) / r)));
    const double angle_step = options_.angle_step_deg * kPi / 180.0;
    const int half_phi =
        std::max(1, static_cast<int>(std::ceil(std::min(kWindowSigmas * prior.sigma_phi, kMaxWindowAngle) /
                                               angle_step)));
    const Match match = searchWindow(map, points, predicted, half_xy, half_phi, angle_step, &prior);
    if (match.near >= options_.min_goodness * static_cast<double>(points.size())) {
      corrected = match.mean;
      covariance = match.covariance;
    }
  }
  last_corrected_ = corrected;
  const common::Pose2 since = common::composePoses(common::invertPose(last_keyframe_), corrected);
  if (std::hypot(since.x, since.y) >= options_.keyframe_distance ||
      std::abs(since.yaw) >= options_.keyframe_angle_deg * kPi / 180.0)
    addKeyframe(corrected, points, covariance + floor);
  return last_corrected_;  // moved with the keyframes when a loop closed
}

}  // namespace hidden_rooms::mapping
