#include "hidden_rooms/exploration/grid_planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <string>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::exploration {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kMaxTrailStep = 1.0;  // metres: longer steps of a trail are jumps of the pose, not driven

}  // namespace

const common::OptionTable<GridPlannerOptions>& gridPlannerOptionTable() {
  using O = GridPlannerOptions;
  static const common::OptionTable<O> table{
      {"free_threshold", &O::free_threshold, "map values 0..this are free", common::between(0, 100)},
      {"occupied_threshold", &O::occupied_threshold, "map values >= this are obstacles", common::between(0, 100)},
      {"robot_radius", &O::robot_radius, "metres: the clearance goals always keep and paths keep where they can",
       common::atLeast(0)},
      {"min_clearance", &O::min_clearance, "metres: obstacle inflation, the hard limit for the robot's centre",
       common::atLeast(0)},
      {"narrow_cost_factor", &O::narrow_cost_factor, "cost factor of cells closer than robot_radius to an obstacle",
       common::atLeast(1)},
      {"cost_radius", &O::cost_radius, "metres: cells this close to an obstacle cost extra", common::atLeast(0)},
      {"cost_weight", &O::cost_weight, "extra cost at robot_radius, falling linearly to cost_radius",
       common::atLeast(0)},
      {"start_escape_radius", &O::start_escape_radius,
       "metres: a robot in the inflation plans from the nearest traversable cell within this", common::atLeast(0)},
      {"smoothing_window", &O::smoothing_window, "metres: half-width of the path's moving average; 0 = none",
       common::atLeast(0)},
  };
  return table;
}

void validate(const GridPlannerOptions& options) {
  common::validateOptions(gridPlannerOptionTable(), options);
  const auto require = [](bool ok, const std::string& what) {
    if (!ok) throw common::InputError("explorer options", what);
  };
  require(options.free_threshold < options.occupied_threshold, "need free_threshold < occupied_threshold");
  require(options.min_clearance <= options.robot_radius, "need min_clearance <= robot_radius");
  require(options.cost_radius >= options.robot_radius, "cost_radius must be >= robot_radius");
}

GridPlanner::GridPlanner(const GridPlannerOptions& options) : options_(options) { validate(options_); }

void GridPlanner::setMap(const common::OccupancyGrid& map) {
  map_ = map;
  start_cell_ = {-1, -1};
  const int rows = map.height(), cols = map.width();
  traversable_ = cv::Mat1b::zeros(rows, cols);
  roomy_ = cv::Mat1b::zeros(rows, cols);
  obstacle_distance_ = cv::Mat1f(rows, cols, std::numeric_limits<float>::max());
  step_factor_ = cv::Mat1f(rows, cols, 1.0f);
  cost_ = cv::Mat1d(rows, cols, kInfinity);
  parent_ = cv::Mat1i(rows, cols, -1);
  if (map.empty()) return;

  cv::Mat1b not_obstacle(rows, cols);
  bool any_obstacle = false;
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const bool obstacle = map.cells(row, col) >= options_.occupied_threshold;
      not_obstacle(row, col) = obstacle ? 0 : 255;
      any_obstacle |= obstacle;
    }
  if (any_obstacle) {
    cv::distanceTransform(not_obstacle, obstacle_distance_, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    obstacle_distance_ *= static_cast<float>(map.resolution);
  }
  const double band = options_.cost_radius - options_.robot_radius;
  const auto free = [&](const cv::Point& cell) {
    const int value = map.cells(cell);
    return value >= 0 && value <= options_.free_threshold;
  };
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const double distance = obstacle_distance_(row, col);
      const bool is_free = free({col, row});
      if (is_free && distance >= options_.min_clearance) traversable_(row, col) = 255;
      if (is_free && distance >= options_.robot_radius) roomy_(row, col) = 255;
      const double closeness = band > 0.0 ? std::clamp((options_.cost_radius - distance) / band, 0.0, 1.0)
                                          : (distance < options_.cost_radius ? 1.0 : 0.0);
      const double narrow = distance < options_.robot_radius ? options_.narrow_cost_factor : 1.0;
      step_factor_(row, col) = static_cast<float>(narrow * (1.0 + options_.cost_weight * closeness));
    }
  for (size_t i = 1; i < trail_.size(); ++i) {
    int col_a = 0, row_a = 0, col_b = 0, row_b = 0;
    if ((trail_[i] - trail_[i - 1]).norm() > kMaxTrailStep || !map.cellOf(trail_[i - 1], &col_a, &row_a) ||
        !map.cellOf(trail_[i], &col_b, &row_b))
      continue;
    cv::LineIterator cell(traversable_, {col_a, row_a}, {col_b, row_b}, 4);  // the search cuts no corners
    for (int k = 0; k < cell.count; ++k, ++cell)
      if (free(cell.pos())) traversable_(cell.pos()) = 255;
  }
  const int blocked_cells = static_cast<int>(std::lround(blocked_radius_ / map.resolution));
  for (const common::Point2& point : blocked_points_) {
    int col = 0, row = 0;
    if (!map.cellOf(point, &col, &row)) continue;
    cv::circle(traversable_, {col, row}, blocked_cells, 0, cv::FILLED);
    cv::circle(roomy_, {col, row}, blocked_cells, 0, cv::FILLED);
  }
}

void GridPlanner::setTrail(const std::vector<common::Point2>& trail) {
  trail_ = trail;
  const common::OccupancyGrid map = map_;
  setMap(map);
}

void GridPlanner::setBlockedPoints(const std::vector<common::Point2>& points, double radius) {
  blocked_points_ = points;
  blocked_radius_ = radius;
  const common::OccupancyGrid map = map_;
  setMap(map);
}

bool GridPlanner::computeCostsFrom(const common::Point2& start, const cv::Mat1b& targets, double margin) {
  cost_.setTo(kInfinity);
  parent_.setTo(-1);
  start_cell_ = {-1, -1};
  search_bounded_ = false;
  int start_col = 0, start_row = 0;
  if (map_.empty() || !map_.cellOf(start, &start_col, &start_row)) return false;
  if (traversable_(start_row, start_col) == 0) {
    // Escape: the nearest traversable cell within start_escape_radius (map noise or a tight spot put the robot
    // into the inflation).
    const int reach = static_cast<int>(std::ceil(options_.start_escape_radius / map_.resolution));
    double best = kInfinity;
    cv::Point best_cell(-1, -1);
    for (int row = std::max(0, start_row - reach); row <= std::min(map_.height() - 1, start_row + reach); ++row)
      for (int col = std::max(0, start_col - reach); col <= std::min(map_.width() - 1, start_col + reach); ++col) {
        const double d = std::hypot(col - start_col, row - start_row);
        if (traversable_(row, col) != 0 && d <= reach && d < best) {
          best = d;
          best_cell = {col, row};
        }
      }
    if (best_cell.x < 0) return false;
    start_col = best_cell.x;
    start_row = best_cell.y;
  }
  start_cell_ = {start_col, start_row};

  const int cols = map_.width(), rows = map_.height();
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  cost_(start_row, start_col) = 0.0;
  open.push({0.0, start_row * cols + start_col});
  const double resolution = map_.resolution;
  static constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  static constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  const bool bounded = !targets.empty() && targets.size() == cost_.size();
  double bound = kInfinity;  // the cheapest target reached plus margin
  while (!open.empty()) {
    const auto [cost, index] = open.top();
    open.pop();
    const int row = index / cols, col = index % cols;
    if (cost > cost_(row, col)) continue;
    if (cost > bound) {  // every cell left costs more: forget what was queued beyond the bound
      for (; !open.empty(); open.pop()) {
        const int queued = open.top().second;
        cost_(queued / cols, queued % cols) = kInfinity;
        parent_(queued / cols, queued % cols) = -1;
      }
      cost_(row, col) = kInfinity;
      parent_(row, col) = -1;
      search_bounded_ = true;
      break;
    }
    if (bounded && targets(row, col) != 0 && cost + margin < bound) bound = cost + margin;
    for (int k = 0; k < 8; ++k) {
      const int next_col = col + kDx[k], next_row = row + kDy[k];
      if (next_col < 0 || next_row < 0 || next_col >= cols || next_row >= rows) continue;
      if (traversable_(next_row, next_col) == 0) continue;
      const bool diagonal = k >= 4;
      // No corner cutting: a diagonal step needs both cells it passes between.
      if (diagonal && (traversable_(row, next_col) == 0 || traversable_(next_row, col) == 0)) continue;
      const double length = (diagonal ? M_SQRT2 : 1.0) * resolution;
      const double next_cost =
          cost + length * 0.5 * (step_factor_(row, col) + step_factor_(next_row, next_col));
      if (next_cost < cost_(next_row, next_col)) {
        cost_(next_row, next_col) = next_cost;
        parent_(next_row, next_col) = index;
        open.push({next_cost, next_row * cols + next_col});
      }
    }
  }
  return true;
}

double GridPlanner::costTo(int col, int row) const {
  if (cost_.empty() || col < 0 || row < 0 || col >= cost_.cols || row >= cost_.rows) return kInfinity;
  return cost_(row, col);
}

double GridPlanner::costTo(const common::Point2& point) const {
  int col = 0, row = 0;
  if (map_.empty() || !map_.cellOf(point, &col, &row)) return kInfinity;
  return costTo(col, row);
}

std::vector<common::Point2> GridPlanner::pathTo(int col, int row) const {
  if (!std::isfinite(costTo(col, row))) return {};
  std::vector<cv::Point> cells;
  const int cols = map_.width();
  for (int index = row * cols + col; index >= 0; index = parent_(index / cols, index % cols))
    cells.emplace_back(index % cols, index / cols);
  std::reverse(cells.begin(), cells.end());

  std::vector<common::Point2> path;
  path.reserve(cells.size());
  for (const cv::Point& cell : cells) path.push_back(map_.cellCentre(cell.x, cell.y));
  const int half_window = static_cast<int>(std::lround(options_.smoothing_window / map_.resolution));
  if (half_window <= 0 || path.size() < 3) return path;
  std::vector<common::Point2> smoothed = path;
  const int n = static_cast<int>(path.size());
  for (int i = 1; i + 1 < n; ++i) {
    const int window = std::min({half_window, i, n - 1 - i});  // symmetric, so the ends stay put
    common::Point2 sum = common::Point2::Zero();
    for (int j = i - window; j <= i + window; ++j) sum += path[j];
    const common::Point2 average = sum / (2 * window + 1);
    int average_col = 0, average_row = 0;
    if (map_.cellOf(average, &average_col, &average_row) && traversable_(average_row, average_col) != 0)
      smoothed[i] = average;
  }
  return smoothed;
}

double pathLength(const std::vector<common::Point2>& path) {
  double length = 0.0;
  for (size_t i = 1; i < path.size(); ++i) length += (path[i] - path[i - 1]).norm();
  return length;
}

}  // namespace hidden_rooms::exploration
