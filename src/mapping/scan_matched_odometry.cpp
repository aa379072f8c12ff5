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

namespace hidden_rooms::mapping {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxPoints = 360;
constexpr size_t kMaxKeyframes = 20000;  // keyframes kept for map_radius (a 4 km path at 0.2 m)        // scan points matched (evenly thinned beyond)
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
  for (double value : {options.max_range, options.keyframe_distance, options.keyframe_angle_deg, options.resolution,
                       options.angle_step_deg, options.point_sigma})
    if (!std::isfinite(value) || value <= 0.0)
      throw common::InputError(file, "[ScanMatching] distances, angles, resolution and sigma must be positive");
  if (options.local_map_scans < 1) throw common::InputError(file, "[ScanMatching] local_map_scans must be at least 1");
  if (!(options.min_goodness >= 0.0 && options.min_goodness <= 1.0))
    throw common::InputError(file, "[ScanMatching] min_goodness must be in [0, 1]");
  return options;
}

struct ScanMatchedOdometry::Keyframe {
  std::vector<common::Point2> points;  // robot frame
  common::Pose2 pose;
};

// The log-likelihood of a point at each cell: log(exp(-d^2 / (2 sigma^2)) + floor), d the distance to the
// nearest keyframe point.
struct ScanMatchedOdometry::LocalMap {
  common::Point2 origin;  // metres: the corner of cell (0, 0)
  cv::Mat1f log_likelihood;
  float outside = 0.0f;   // the value off the map (the floor's)
  cv::Mat1b near;         // non-zero where a point is within 2 sigma of the map
};

ScanMatchedOdometry::ScanMatchedOdometry(const ScanMatchingOptions& options, const MotionNoise& noise)
    : options_(options), noise_(noise) {}

ScanMatchedOdometry::~ScanMatchedOdometry() = default;

void ScanMatchedOdometry::rebuildLocalMap() {
  constexpr double kMargin = 1.0;      // metres around the keyframes' points
  constexpr double kFloor = 0.01;      // likelihood of a point far from the map (clutter, people, new walls)
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x, max_x = -min_x, max_y = -min_x;
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
    for (const common::Point2& p : keyframe->points) {
      world.push_back(transformed(keyframe->pose, p));
      min_x = std::min(min_x, world.back().x()), max_x = std::max(max_x, world.back().x());
      min_y = std::min(min_y, world.back().y()), max_y = std::max(max_y, world.back().y());
    }
  }
  local_map_ = std::make_unique<LocalMap>();
  if (world.empty()) return;
  const double r = options_.resolution;
  local_map_->origin = common::Point2(min_x - kMargin, min_y - kMargin);
  const int cols = static_cast<int>(std::ceil((max_x - min_x + 2 * kMargin) / r)) + 1;
  const int rows = static_cast<int>(std::ceil((max_y - min_y + 2 * kMargin) / r)) + 1;
  cv::Mat1b free_of_points(rows, cols, uchar(255));
  for (const common::Point2& p : world) {
    const int col = static_cast<int>((p.x() - local_map_->origin.x()) / r);
    const int row = static_cast<int>((p.y() - local_map_->origin.y()) / r);
    if (col >= 0 && row >= 0 && col < cols && row < rows) free_of_points(row, col) = 0;
  }
  cv::Mat1f distance;
  cv::distanceTransform(free_of_points, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  const double sigma_cells = options_.point_sigma / r;
  // Per distance (a tenth of a cell apart) up to where the floor dominates: the log-likelihood.
  constexpr int kSteps = 10;
  const int table_size = static_cast<int>(std::ceil(5.0 * sigma_cells * kSteps)) + 1;
  std::vector<float> table(table_size);
  for (int k = 0; k < table_size; ++k) {
    const double d = static_cast<double>(k) / kSteps;
    table[k] = static_cast<float>(std::log(std::exp(-0.5 * d * d / (sigma_cells * sigma_cells)) + kFloor));
  }
  local_map_->outside = static_cast<float>(std::log(kFloor));
  local_map_->log_likelihood.create(rows, cols);
  local_map_->near = distance <= 2.0 * sigma_cells;
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const int k = static_cast<int>(distance(row, col) * kSteps);
      local_map_->log_likelihood(row, col) = k < table_size ? table[k] : local_map_->outside;
    }
}

common::Pose2 ScanMatchedOdometry::correct(const common::Pose2& odometry,
                                           const mrpt::obs::CObservation2DRangeScan& scan) {
  const std::vector<common::Point2> points = robotFramePoints(scan, options_.max_range);
  auto addKeyframe = [&](const common::Pose2& pose) {
    keyframes_.push_back(std::make_shared<Keyframe>(Keyframe{points, pose}));
    const size_t keep = options_.map_radius > 0.0 ? kMaxKeyframes : static_cast<size_t>(options_.local_map_scans);
    while (keyframes_.size() > keep) keyframes_.pop_front();
    last_keyframe_ = pose;
    rebuildLocalMap();
  };
  if (!started_) {
    started_ = true;
    last_odometry_ = last_corrected_ = odometry;
    addKeyframe(odometry);
    return odometry;
  }
  // The odometry's prediction and its std. dev. (the motion model of the increment, isotropic in x and y).
  const common::Pose2 increment = common::composePoses(common::invertPose(last_odometry_), odometry);
  last_odometry_ = odometry;
  const common::Pose2 predicted = common::composePoses(last_corrected_, increment);
  const double distance = std::hypot(increment.x, increment.y), turn = std::abs(increment.yaw);
  const double sigma_xy = std::max(noise_.min_xy + noise_.a1 * distance + noise_.a2 * turn, 0.5 * options_.resolution);
  const double sigma_phi =
      std::max(noise_.min_phi + noise_.a3 * distance + noise_.a4 * turn, 0.5 * options_.angle_step_deg * kPi / 180.0);

  common::Pose2 corrected = predicted;
  const LocalMap& map = *local_map_;
  if (!map.log_likelihood.empty() && !points.empty()) {
    const double r = options_.resolution;
    const int half_xy = std::max(1, static_cast<int>(std::ceil(std::min(kWindowSigmas * sigma_xy, kMaxWindow) / r)));
    const double angle_step = options_.angle_step_deg * kPi / 180.0;
    const int half_phi =
        std::max(1, static_cast<int>(std::ceil(std::min(kWindowSigmas * sigma_phi, kMaxWindowAngle) / angle_step)));
    const int side = 2 * half_xy + 1;
    // Per heading: the log-likelihood of the scan at every shift (cells) of the window, and the count of points
    // near the map at the best shift.
    double best = -std::numeric_limits<double>::infinity();
    int best_near = 0;
    std::vector<double> scores((2 * half_phi + 1) * side * side);
    std::vector<cv::Point> cells(points.size());
    for (int a = -half_phi; a <= half_phi; ++a) {
      const common::Pose2 turned{predicted.x, predicted.y, predicted.yaw + a * angle_step};
      for (size_t i = 0; i < points.size(); ++i) {
        const common::Point2 p = transformed(turned, points[i]);
        cells[i] = cv::Point(static_cast<int>(std::floor((p.x() - map.origin.x()) / r)),
                             static_cast<int>(std::floor((p.y() - map.origin.y()) / r)));
      }
      for (int dy = -half_xy; dy <= half_xy; ++dy)
        for (int dx = -half_xy; dx <= half_xy; ++dx) {
          double score = 0.0;
          int near = 0;
          for (const cv::Point& cell : cells) {
            const int col = cell.x + dx, row = cell.y + dy;
            if (col < 0 || row < 0 || col >= map.log_likelihood.cols || row >= map.log_likelihood.rows) {
              score += map.outside;
            } else {
              score += map.log_likelihood(row, col);
              near += map.near(row, col) != 0;
            }
          }
          // The prediction's Gaussian prior.
          const double ex = dx * r / sigma_xy, ey = dy * r / sigma_xy, ephi = a * angle_step / sigma_phi;
          score -= 0.5 * (ex * ex + ey * ey + ephi * ephi);
          scores[((a + half_phi) * side + (dy + half_xy)) * side + (dx + half_xy)] = score;
          if (score > best) best = score, best_near = near;
        }
    }
    if (best_near >= options_.min_goodness * static_cast<double>(points.size())) {
      // The posterior's mean over the window.
      double weight_sum = 0.0, mx = 0.0, my = 0.0, mphi = 0.0;
      for (int a = -half_phi; a <= half_phi; ++a)
        for (int dy = -half_xy; dy <= half_xy; ++dy)
          for (int dx = -half_xy; dx <= half_xy; ++dx) {
            const double w = std::exp(scores[((a + half_phi) * side + (dy + half_xy)) * side + (dx + half_xy)] - best);
            weight_sum += w;
            mx += w * dx * r;
            my += w * dy * r;
            mphi += w * a * angle_step;
          }
      corrected = {predicted.x + mx / weight_sum, predicted.y + my / weight_sum,
                   common::wrapAngle(predicted.yaw + mphi / weight_sum)};
    }
  }
  last_corrected_ = corrected;
  const common::Pose2 since = common::composePoses(common::invertPose(last_keyframe_), corrected);
  if (std::hypot(since.x, since.y) >= options_.keyframe_distance ||
      std::abs(since.yaw) >= options_.keyframe_angle_deg * kPi / 180.0)
    addKeyframe(corrected);
  return corrected;
}

}  // namespace hidden_rooms::mapping
