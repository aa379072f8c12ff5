#include "hidden_rooms/exploration/frontier.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::exploration {

namespace {

// 255 where the frontiers count a cell as unknown: -1, and uncertain cells (seen too rarely to be free or occupied).
cv::Mat1b unknownCells(const common::OccupancyGrid& map, const FrontierOptions& options) {
  return (map.cells < 0) | ((map.cells > options.free_threshold) & (map.cells < options.occupied_threshold));
}

// The goal a search keeps (nearestFrontierGoal, nearestLookGoal): `previous` while `claims` (per cell: the frontier
// it serves, 0 none) still has it, it is not blacklisted and it costs at most `hysteresis` more than `best`; else
// `best`.
FrontierGoal keptGoal(const FrontierGoal& best, const common::Point2& previous, const cv::Mat1i& claims,
                      const GridPlanner& planner, const Blacklist& blacklist, double hysteresis) {
  const common::OccupancyGrid& map = planner.map();
  int col = 0, row = 0;
  if (!map.cellOf(previous, &col, &row) || claims(row, col) == 0 || blacklist.contains(previous)) return best;
  const double cost = planner.costTo(col, row);
  if (!std::isfinite(cost) || cost > best.cost + hysteresis) return best;
  return FrontierGoal{claims(row, col), {col, row}, map.cellCentre(col, row), cost, best.look};
}

}  // namespace

FrontierMap findFrontiers(const common::OccupancyGrid& map, const FrontierOptions& options,
                          const cv::Mat1b& seen_walls) {
  FrontierMap result;
  if (map.empty()) return result;
  const int rows = map.height(), cols = map.width();
  result.labels = cv::Mat1i::zeros(rows, cols);

  // Unknown areas big enough to be worth exploring (4-connected, as the frontier test below looks at them).
  const cv::Mat1b unknown = unknownCells(map, options);
  cv::Mat1i unknown_labels, unknown_stats;
  cv::Mat centroids;
  cv::connectedComponentsWithStats(unknown, unknown_labels, unknown_stats, centroids, 4, CV_32S);
  const auto significant_unknown = [&](int col, int row) {
    if (col < 0 || row < 0 || col >= cols || row >= rows) return true;  // beyond the grid nothing is known
    const int label = unknown_labels(row, col);
    return label > 0 && unknown_stats(label, cv::CC_STAT_AREA) >= options.min_unknown_cells;
  };

  cv::Mat1b frontier_cells = cv::Mat1b::zeros(rows, cols);
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const int value = map.cells(row, col);
      if (value < 0 || value > options.free_threshold || (!seen_walls.empty() && seen_walls(row, col))) continue;
      if (significant_unknown(col + 1, row) || significant_unknown(col - 1, row) ||
          significant_unknown(col, row + 1) || significant_unknown(col, row - 1))
        frontier_cells(row, col) = 255;
    }

  cv::Mat1i groups, stats;
  const int group_count = cv::connectedComponentsWithStats(frontier_cells, groups, stats, centroids, 8, CV_32S);
  std::vector<int> kept;
  for (int label = 1; label < group_count; ++label)
    if (stats(label, cv::CC_STAT_AREA) >= options.min_frontier_cells) kept.push_back(label);
  std::stable_sort(kept.begin(), kept.end(), [&](int a, int b) {
    return stats(a, cv::CC_STAT_AREA) > stats(b, cv::CC_STAT_AREA);
  });
  std::vector<int> new_label(group_count, 0);
  for (size_t i = 0; i < kept.size(); ++i) new_label[kept[i]] = static_cast<int>(i) + 1;

  result.frontiers.resize(kept.size());
  for (size_t i = 0; i < kept.size(); ++i) result.frontiers[i].label = static_cast<int>(i) + 1;
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const int label = new_label[groups(row, col)];
      if (label == 0) continue;
      result.labels(row, col) = label;
      Frontier& frontier = result.frontiers[label - 1];
      frontier.cells.emplace_back(col, row);
      frontier.centroid += map.cellCentre(col, row);
    }
  for (Frontier& frontier : result.frontiers) frontier.centroid /= static_cast<double>(frontier.cells.size());
  return result;
}

void SeenWalls::setGrid(const common::OccupancyGrid& map) {
  const bool same_grid = !first_time_.empty() && map.resolution == grid_.resolution &&
                         map.origin == grid_.origin && map.cells.size() == grid_.cells.size();
  if (!same_grid) {
    cv::Mat1d moved(map.height(), map.width(), std::numeric_limits<double>::infinity());
    if (!first_time_.empty() && map.resolution == grid_.resolution) {
      for (int row = 0; row < map.height(); ++row)
        for (int col = 0; col < map.width(); ++col) {
          int old_col = 0, old_row = 0;
          if (grid_.cellOf(map.cellCentre(col, row), &old_col, &old_row))
            moved(row, col) = first_time_(old_row, old_col);
        }
    }
    first_time_ = moved;
  }
  grid_ = map;
}

void SeenWalls::addScan(const std::vector<common::Point2>& points, const common::Pose2& pose, double time) {
  if (first_time_.empty() || range_ <= 0.0) return;
  const common::Point2 origin(pose.x, pose.y);
  const double step = 0.5 * grid_.resolution;
  for (const common::Point2& point : points) {
    const common::Point2 ray = common::transformPoint(pose, point) - origin;
    const double length = ray.norm();
    if (!(length > 0.0 && length <= range_)) continue;
    const common::Point2 direction = ray / length;
    for (double along = length; along <= length + margin_; along += step) {
      int col = 0, row = 0;
      if (!grid_.cellOf(origin + along * direction, &col, &row)) continue;
      double& first = first_time_(row, col);
      first = std::min(first, time);
    }
  }
}

cv::Mat1b SeenWalls::seenBy(double time) const {
  if (first_time_.empty()) return cv::Mat1b();
  return first_time_ <= time;
}

bool Blacklist::contains(const common::Point2& point) const {
  return std::any_of(points.begin(), points.end(),
                     [&](const common::Point2& listed) { return (listed - point).norm() <= radius; });
}

bool Blacklist::add(const common::Point2& point, GoalOutcome outcome) {
  points.push_back(point);
  if (outcome == GoalOutcome::kRobotStuck) {
    stuck_points.push_back(point);
    return true;
  }
  const auto near = [&](const common::Point2& place) { return (place - point).norm() <= radius; };
  if (outcome != GoalOutcome::kFailed || std::any_of(retried_points.begin(), retried_points.end(), near)) return false;
  failed_points.push_back(point);
  return true;
}

namespace {

// Removes every occurrence of each of `released` from `points`; returns how many `released` there were.
size_t removePoints(std::vector<common::Point2>* released, std::vector<common::Point2>* points) {
  for (const common::Point2& place : *released)
    points->erase(std::remove(points->begin(), points->end(), place), points->end());
  const size_t count = released->size();
  released->clear();
  return count;
}

}  // namespace

size_t Blacklist::releaseStuck() { return removePoints(&stuck_points, &points); }

size_t Blacklist::releaseFailed() {
  retried_points.insert(retried_points.end(), failed_points.begin(), failed_points.end());
  return removePoints(&failed_points, &points);
}

const common::OptionTable<FrontierOptions>& frontierOptionTable() {
  using O = FrontierOptions;
  static const common::OptionTable<O> table{
      {"min_frontier_cells", &O::min_frontier_cells, "smaller frontiers are dropped", common::atLeast(1)},
      {"min_unknown_cells", &O::min_unknown_cells, "smaller unknown areas (4-connected) make no frontier",
       common::atLeast(1)},
      {"goal_reach", &O::goal_reach, "metres: a goal lies within this of a frontier cell", common::atLeast(0)},
      {"min_goal_distance", &O::min_goal_distance, "metres: and at least this far from the robot",
       common::atLeast(0)},
      {"look_range", &O::look_range,
       "metres: with no frontier reachable, a goal may look past a frontier cell from this far; 0 = off",
       common::atLeast(0)},
      {"seen_wall_range", &O::seen_wall_range,
       "metres: a free cell at (or seen_wall_margin behind) the end of a beam at most this long, next to "
       "unknown space in a map seen_wall_delay later, is in a wall, no frontier; 0 = off",
       common::atLeast(0)},
      {"seen_wall_margin", &O::seen_wall_margin, "metres behind the beam's end", common::atLeast(0)},
      {"seen_wall_delay", &O::seen_wall_delay, "seconds between the scan and the map that judges it",
       common::atLeast(0)},
  };
  return table;
}

const common::OptionTable<BlockedPassagesOptions>& blockedPassagesOptionTable() {
  using O = BlockedPassagesOptions;
  static const common::OptionTable<O> table{
      {"blocked_passage_failures", &O::failures,
       "goals failed from one place in one direction that block the path ahead; 0 = off", common::atLeast(0)},
      {"blocked_passage_length", &O::length, "metres of the failed path ahead of the robot that are blocked",
       common::atLeast(0)},
      {"blocked_passage_radius", &O::radius, "metres blocked around each point of that stretch",
       common::atLeast(0)},
  };
  return table;
}

void validate(const BlockedPassagesOptions& options) {
  const auto require = [](bool ok, const std::string& what) {
    if (!ok) throw common::InputError("explorer options", what);
  };
  common::validateOptions(blockedPassagesOptionTable(), options);  // failures, length, radius
  for (const double value : {options.same_place, options.same_direction, options.skip})
    require(std::isfinite(value) && value >= 0.0, "blocked passage distances and angles must be >= 0");
  require(options.skip < options.length, "the blocked stretch must start (skip) before it ends (length)");
}

BlockedPassages::BlockedPassages(const BlockedPassagesOptions& options) : options_(options) { validate(options_); }

bool BlockedPassages::addFailure(const common::Point2& robot, const std::vector<common::Point2>& path) {
  if (options_.failures <= 0 || path.empty()) return false;
  const auto here = [&](const common::Point2& place) { return (place - robot).norm() <= options_.same_place; };
  if (std::any_of(wedged_.begin(), wedged_.end(), here)) return false;
  // The stretch: path points between skip and length metres along the path from the point nearest the robot.
  size_t nearest = 0;
  for (size_t i = 1; i < path.size(); ++i)
    if ((path[i] - robot).norm() < (path[nearest] - robot).norm()) nearest = i;
  Failure failure{robot, common::Point2::Zero(), {}, false};
  double along = 0.0;
  for (size_t i = nearest + 1; i < path.size() && along <= options_.length; ++i) {
    along += (path[i] - path[i - 1]).norm();
    if (along >= options_.skip && along <= options_.length) failure.stretch.push_back(path[i]);
  }
  if (failure.stretch.empty() || (failure.stretch.back() - robot).norm() < 1e-9) return false;
  failure.direction = (failure.stretch.back() - robot).normalized();

  const size_t blocked_before = blocked_.size();
  const auto from_here = [&](const Failure& other) { return here(other.robot); };
  const double agreement = std::cos(options_.same_direction);
  const bool wedged = std::any_of(failures_.begin(), failures_.end(), [&](const Failure& other) {
    return from_here(other) && other.direction.dot(failure.direction) < agreement;
  });
  if (wedged) {
    wedged_.push_back(robot);
    failures_.erase(std::remove_if(failures_.begin(), failures_.end(), from_here), failures_.end());
  } else {
    failures_.push_back(failure);
    if (std::count_if(failures_.begin(), failures_.end(), from_here) >= options_.failures)
      for (Failure& other : failures_)
        if (from_here(other)) other.blocking = true;
  }
  collectBlocked();
  return blocked_.size() != blocked_before;
}

void BlockedPassages::collectBlocked() {
  blocked_.clear();
  for (const Failure& failure : failures_)
    if (failure.blocking) blocked_.insert(blocked_.end(), failure.stretch.begin(), failure.stretch.end());
}

size_t BlockedPassages::releaseOnce() {
  if (released_ || blocked_.empty()) return 0;
  released_ = true;
  const size_t released = blocked_.size();
  failures_.clear();
  blocked_.clear();
  return released;
}

std::optional<FrontierGoal> nearestFrontierGoal(const FrontierMap& frontiers, const GridPlanner& planner,
                                                const Blacklist& blacklist, const FrontierOptions& options,
                                                const std::optional<common::Point2>& previous, double hysteresis) {
  const common::OccupancyGrid& map = planner.map();
  if (map.empty() || frontiers.frontiers.empty() || planner.startCell().x < 0) return std::nullopt;
  const int reach = static_cast<int>(std::floor(options.goal_reach / map.resolution));
  const cv::Mat1b& roomy = planner.roomy();  // goals keep robot_radius from obstacles

  const common::Point2 robot = map.cellCentre(planner.startCell().x, planner.startCell().y);
  const auto acceptable = [&](const common::Point2& position) {
    return (position - robot).norm() >= options.min_goal_distance && !blacklist.contains(position);
  };
  // Per cell, the frontier that claims it (the first one found within reach); cells are visited once.
  cv::Mat1i claimed = cv::Mat1i::zeros(map.height(), map.width());
  std::optional<FrontierGoal> best;
  for (const Frontier& frontier : frontiers.frontiers) {
    for (const cv::Point& cell : frontier.cells) {
      for (int row = std::max(0, cell.y - reach); row <= std::min(map.height() - 1, cell.y + reach); ++row)
        for (int col = std::max(0, cell.x - reach); col <= std::min(map.width() - 1, cell.x + reach); ++col) {
          if (claimed(row, col) != 0 || roomy(row, col) == 0) continue;
          if ((col - cell.x) * (col - cell.x) + (row - cell.y) * (row - cell.y) > reach * reach) continue;
          claimed(row, col) = frontier.label;
          const double cost = planner.costTo(col, row);
          if (!std::isfinite(cost) || (best && cost >= best->cost)) continue;
          const common::Point2 position = map.cellCentre(col, row);
          if (!acceptable(position)) continue;
          best = FrontierGoal{frontier.label, {col, row}, position, cost};
        }
    }
  }
  if (!best || !previous) return best;
  return keptGoal(*best, *previous, claimed, planner, blacklist, hysteresis);
}

std::optional<FrontierGoal> nearestLookGoal(const FrontierMap& frontiers, const GridPlanner& planner,
                                            const Blacklist& blacklist, const FrontierOptions& options,
                                            const std::optional<common::Point2>& previous, double hysteresis) {
  const common::OccupancyGrid& map = planner.map();
  if (options.look_range <= 0.0 || map.empty() || frontiers.frontiers.empty() || planner.startCell().x < 0)
    return std::nullopt;
  const auto inside = [&](int col, int row) { return col >= 0 && row >= 0 && col < map.width() && row < map.height(); };
  const auto free = [&](int col, int row) {
    const int value = map.cells(row, col);
    return value >= 0 && value <= options.free_threshold;
  };
  const cv::Mat1b unknown = unknownCells(map, options);  // beyond the grid counts as unknown too
  const common::Point2 robot = map.cellCentre(planner.startCell().x, planner.startCell().y);
  const cv::Mat1b& roomy = planner.roomy();
  // Rays every 5 degrees from each frontier cell, in half-cell steps.
  constexpr int kDirections = 72;
  std::array<common::Point2, kDirections> directions;
  for (int k = 0; k < kDirections; ++k)
    directions[k] = common::Point2(std::cos(2.0 * CV_PI * k / kDirections), std::sin(2.0 * CV_PI * k / kDirections));
  const double steps = 2.0 * options.look_range / map.resolution;
  cv::Mat1i looking = cv::Mat1i::zeros(map.height(), map.width());  // per cell: a frontier it looks past
  std::optional<FrontierGoal> best;
  for (const Frontier& frontier : frontiers.frontiers)
    for (const cv::Point& cell : frontier.cells)
      for (const common::Point2& direction : directions) {
        const double dx = direction.x(), dy = direction.y();
        const int behind_col = cvRound(cell.x - dx), behind_row = cvRound(cell.y - dy);
        if (inside(behind_col, behind_row) && unknown(behind_row, behind_col) == 0) continue;  // nothing beyond
        for (int step = 1; step <= steps; ++step) {
          const int col = cvRound(cell.x + 0.5 * step * dx), row = cvRound(cell.y + 0.5 * step * dy);
          if (!inside(col, row) || !free(col, row)) break;
          if (roomy(row, col) == 0 || looking(row, col) != 0) continue;
          looking(row, col) = frontier.label;
          const double cost = planner.costTo(col, row);
          if (!std::isfinite(cost) || (best && cost >= best->cost)) continue;
          const common::Point2 position = map.cellCentre(col, row);
          if ((position - robot).norm() < options.min_goal_distance || blacklist.contains(position)) continue;
          best = FrontierGoal{frontier.label, {col, row}, position, cost, true};
        }
      }
  if (!best || !previous) return best;
  return keptGoal(*best, *previous, looking, planner, blacklist, hysteresis);
}

cv::Mat1b goalCandidates(const FrontierMap& frontiers, const GridPlanner& planner, const Blacklist& blacklist,
                         const FrontierOptions& options, const common::Point2& robot, double extra_distance) {
  const common::OccupancyGrid& map = planner.map();
  cv::Mat1b candidates = cv::Mat1b::zeros(map.height(), map.width());
  if (map.empty()) return candidates;
  for (const Frontier& frontier : frontiers.frontiers)
    for (const cv::Point& cell : frontier.cells) candidates(cell) = 255;
  // Within goal_reach of a frontier cell, as nearestFrontierGoal measures it (whole cells, centre to centre).
  const int reach = static_cast<int>(std::floor(options.goal_reach / map.resolution));
  cv::Mat1b disc = cv::Mat1b::zeros(2 * reach + 1, 2 * reach + 1);
  for (int row = 0; row <= 2 * reach; ++row)
    for (int col = 0; col <= 2 * reach; ++col)
      disc(row, col) = (col - reach) * (col - reach) + (row - reach) * (row - reach) <= reach * reach ? 1 : 0;
  cv::dilate(candidates, candidates, disc, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  candidates &= planner.roomy();
  const double min_distance = options.min_goal_distance + extra_distance;
  for (int row = 0; row < candidates.rows; ++row)
    for (int col = 0; col < candidates.cols; ++col) {
      if (candidates(row, col) == 0) continue;
      const common::Point2 position = map.cellCentre(col, row);
      if ((position - robot).norm() < min_distance || blacklist.contains(position)) candidates(row, col) = 0;
    }
  return candidates;
}

}  // namespace hidden_rooms::exploration
