#include "hidden_rooms/exploration/path_follower.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::exploration {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// `point` (map frame) in the frame of a robot at `pose`.
common::Point2 toRobotFrame(const common::Pose2& pose, const common::Point2& point) {
  return common::transformPoint(common::invertPose(pose), point);
}

}  // namespace

const common::OptionTable<PathFollowerOptions>& pathFollowerOptionTable() {
  using O = PathFollowerOptions;
  const common::ParameterRange positive = common::above(0), non_negative = common::atLeast(0);
  static const common::OptionTable<O> table{
      {"max_linear_velocity", &O::max_linear_velocity, "m/s", positive},
      {"max_angular_velocity", &O::max_angular_velocity, "rad/s", positive},
      {"lookahead", &O::lookahead, "metres: pure pursuit distance along the path", positive},
      {"goal_tolerance", &O::goal_tolerance, "metres: the goal is reached within this", positive},
      {"rotate_in_place_angle", &O::rotate_in_place_angle,
       "rad: a larger heading error to the pursued point turns in place", positive},
      {"heading_gain", &O::heading_gain, "rad/s per rad of heading error when turning in place", positive},
      {"footprint_length", &O::footprint_length, "metres: the robot box for the laser lane", positive},
      {"footprint_width", &O::footprint_width, "metres: the robot box for the laser lane", positive},
      {"side_margin", &O::side_margin, "metres of lane beside, ahead of and behind the footprint", non_negative},
      {"stop_distance", &O::stop_distance, "metres: no forward motion with less free space ahead", non_negative},
      {"deceleration", &O::deceleration, "m/s^2: the laser speed cap sqrt(2 deceleration free)", positive},
      {"creep_velocity", &O::creep_velocity, "m/s: moving away from near points while turning in place",
       non_negative},
      {"arc_horizon", &O::arc_horizon, "seconds of the commanded arc checked against the laser; 0 = no check",
       non_negative},
      {"doorway_distance", &O::doorway_distance, "metres: points this close on both sides make a doorway",
       non_negative},
      {"doorway_angular_velocity", &O::doorway_angular_velocity, "rad/s: the turn rate cap in a doorway",
       non_negative},
      {"gap_slack", &O::gap_slack, "metres: in a gap with less to spare beside the lane, aim at its middle; 0 = off",
       non_negative},
      {"stall_timeout", &O::stall_timeout, "seconds without stall_distance or stall_angle start a recovery",
       positive},
      {"stall_distance", &O::stall_distance, "metres", non_negative},
      {"stall_angle", &O::stall_angle, "rad", non_negative},
      {"backoff_time", &O::backoff_time, "recovery: seconds backing off", non_negative},
      {"backoff_velocity", &O::backoff_velocity, "recovery: m/s backing off", non_negative},
      {"recovery_rotate_time", &O::recovery_rotate_time, "recovery: seconds turning towards the freer side",
       non_negative},
      {"progress_timeout", &O::progress_timeout,
       "seconds in which the remaining path must shrink by progress_distance, else the goal fails", positive},
      {"progress_distance", &O::progress_distance, "metres", non_negative},
      {"max_recoveries", &O::max_recoveries, "recoveries per goal before it fails", non_negative},
  };
  return table;
}

void validate(const PathFollowerOptions& options) { common::validateOptions(pathFollowerOptionTable(), options); }

const char* toString(FollowerState state) {
  switch (state) {
    case FollowerState::kIdle: return "idle";
    case FollowerState::kFollowing: return "following";
    case FollowerState::kBackingOff: return "backing off";
    case FollowerState::kRecoveryRotating: return "rotating (recovery)";
    case FollowerState::kGoalReached: return "goal reached";
    case FollowerState::kFailed: return "failed";
  }
  return "unknown";
}

std::vector<common::Point2> obstaclePoints(const common::RangeScan& scan, int* skipped) {
  std::vector<common::Point2> points;
  points.reserve(scan.ranges.size());
  int invalid = 0;
  const double c = std::cos(scan.sensor_pose.yaw), s = std::sin(scan.sensor_pose.yaw);
  for (size_t k = 0; k < scan.ranges.size(); ++k) {
    const double range = scan.ranges[k];
    if (!std::isfinite(range) || !scan.valid(k)) {
      ++invalid;
      continue;
    }
    const double angle = scan.angle_min + static_cast<double>(k) * scan.angle_increment;
    const double x = range * std::cos(angle), y = range * std::sin(angle);
    points.emplace_back(scan.sensor_pose.x + c * x - s * y, scan.sensor_pose.y + s * x + c * y);
  }
  if (skipped != nullptr) *skipped = invalid;
  return points;
}

void ObstacleMemory::add(const std::vector<common::Point2>& points, const common::Pose2& pose, double time) {
  scans_.erase(std::remove_if(scans_.begin(), scans_.end(),
                              [&](const Scan& scan) { return scan.time < time - duration_ || scan.time > time; }),
               scans_.end());
  Scan scan;
  scan.time = time;
  scan.points.reserve(points.size());
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  for (const common::Point2& point : points)
    if (point.allFinite()) scan.points.emplace_back(pose.x + c * point.x() - s * point.y(), pose.y + s * point.x() + c * point.y());
  scans_.push_back(std::move(scan));
}

std::vector<common::Point2> ObstacleMemory::points(const common::Pose2& pose) const {
  std::vector<common::Point2> result;
  for (const Scan& scan : scans_)
    for (const common::Point2& point : scan.points) result.push_back(toRobotFrame(pose, point));
  return result;
}

namespace {

// The margin kept beside the footprint when moving: side_margin, or 70% of the present gap (the distance from the
// footprint to the nearest point) when something is already closer. The robot may go on through a passage as tight
// as where it stands, but not into a tighter one; with the full margin it could not move at all in a tight door.
double movingMargin(const std::vector<common::Point2>& obstacles, const PathFollowerOptions& options) {
  constexpr double kShareOfPresentGap = 0.7;
  const double half_length = 0.5 * options.footprint_length, half_width = 0.5 * options.footprint_width;
  double gap = kInfinity;
  for (const common::Point2& point : obstacles)
    if (point.allFinite())
      gap = std::min(gap, std::hypot(std::max(0.0, std::abs(point.x()) - half_length),
                                     std::max(0.0, std::abs(point.y()) - half_width)));
  return std::min(options.side_margin, kShareOfPresentGap * gap);
}

// Free distance beyond the footprint's front (`direction` +1) or rear (-1) within its lane (the footprint's width
// plus `margin` each side). Points beside the footprint in the lane's side margins do not count (driving straight
// does not bring them closer); points inside the footprint's half on that side give 0.
double laneClearance(const std::vector<common::Point2>& obstacles, const PathFollowerOptions& options,
                     double direction, double margin) {
  const double half_length = 0.5 * options.footprint_length, half_width = 0.5 * options.footprint_width;
  const double half_lane = half_width + margin;
  double clearance = kInfinity;
  for (const common::Point2& point : obstacles) {
    const double along = direction * point.x();
    if (!point.allFinite() || std::abs(point.y()) > half_lane || along < 0.0 || (along == 0.0 && direction < 0))
      continue;
    if (along > half_length)
      clearance = std::min(clearance, along - half_length);
    else if (std::abs(point.y()) <= half_width)
      clearance = 0.0;
  }
  return clearance;
}

}  // namespace

double frontClearance(const std::vector<common::Point2>& obstacles, const PathFollowerOptions& options) {
  return laneClearance(obstacles, options, 1.0, movingMargin(obstacles, options));
}

double rearClearance(const std::vector<common::Point2>& obstacles, const PathFollowerOptions& options) {
  return laneClearance(obstacles, options, -1.0, movingMargin(obstacles, options));
}

PathFollower::PathFollower(const PathFollowerOptions& options) : options_(options) { validate(options_); }

void PathFollower::setPath(const std::vector<common::Point2>& path, double time) {
  path_ = path;
  closest_index_ = 0;
  recoveries_ = 0;
  recoveries_without_motion_ = 0;
  held_ = false;
  anchor_set_ = false;
  progress_time_ = time;
  best_remaining_ = kInfinity;
  state_ = path_.empty() ? FollowerState::kIdle : FollowerState::kFollowing;
}

void PathFollower::updatePath(const std::vector<common::Point2>& path) {
  if (path.empty()) return;
  path_ = path;
  closest_index_ = 0;
}

void PathFollower::stop() {
  path_.clear();
  state_ = FollowerState::kIdle;
}

void PathFollower::hold(double time) {
  if (held_) return;
  held_ = true;
  held_since_ = time;
}

bool PathFollower::withinStall(const common::Pose2& pose, const common::Pose2& since) const {
  return std::hypot(pose.x - since.x, pose.y - since.y) <= options_.stall_distance &&
         std::abs(common::wrapAngle(pose.yaw - since.yaw)) <= options_.stall_angle;
}

double PathFollower::remainingLength(const common::Pose2& pose) {
  // The closest path point, searched from the last one on (the robot does not go back along its path); a
  // window keeps a path that passes near itself from being skipped.
  const common::Point2 position(pose.x, pose.y);
  double best = kInfinity;
  size_t best_index = closest_index_;
  double along = 0.0;
  for (size_t i = closest_index_; i < path_.size(); ++i) {
    if (i > closest_index_) along += (path_[i] - path_[i - 1]).norm();
    if (along > 2.0 * options_.lookahead + 1.0) break;
    const double d = (path_[i] - position).norm();
    if (d < best) {
      best = d;
      best_index = i;
    }
  }
  closest_index_ = best_index;
  double remaining = best;
  for (size_t i = closest_index_ + 1; i < path_.size(); ++i) remaining += (path_[i] - path_[i - 1]).norm();
  return remaining;
}

FollowerStep PathFollower::update(const common::Pose2& pose, const std::vector<common::Point2>& obstacles,
                                  double time) {
  if (held_) {  // the held time does not count: timers move on by it, the stall watch starts afresh
    const double pause = std::max(0.0, time - held_since_);
    progress_time_ += pause;
    recovery_until_ += pause;
    anchor_set_ = false;
    held_ = false;
  }
  FollowerStep step;
  step.front_clearance = frontClearance(obstacles, options_);
  if (state_ == FollowerState::kIdle || state_ == FollowerState::kGoalReached || state_ == FollowerState::kFailed ||
      path_.empty()) {
    step.state = state_;
    return step;
  }

  // Goal and progress.
  const common::Point2 position(pose.x, pose.y);
  if ((path_.back() - position).norm() <= options_.goal_tolerance) {
    state_ = step.state = FollowerState::kGoalReached;
    return step;
  }
  const double remaining = remainingLength(pose);
  if (remaining <= best_remaining_ - options_.progress_distance || !std::isfinite(best_remaining_)) {
    best_remaining_ = remaining;
    progress_time_ = time;
  }
  if (time - progress_time_ > options_.progress_timeout) {
    state_ = step.state = FollowerState::kFailed;
    return step;
  }

  // Recovery in progress.
  if (state_ == FollowerState::kBackingOff) {
    if (time < recovery_until_ && rearClearance(obstacles, options_) > options_.stop_distance) {
      step.command.linear = -options_.backoff_velocity;
      step.state = state_;
      return step;
    }
    state_ = FollowerState::kRecoveryRotating;
    recovery_until_ = time + options_.recovery_rotate_time;
  }
  if (state_ == FollowerState::kRecoveryRotating) {
    if (time < recovery_until_) {
      step.command.angular = recovery_turn_sign_ * options_.max_angular_velocity;
      step.state = state_;
      return step;
    }
    state_ = FollowerState::kFollowing;
    anchor_set_ = false;
    last_recovery_moved_ = !withinStall(pose, recovery_start_pose_);
    if (!last_recovery_moved_) ++recoveries_without_motion_;
  }

  // Stall watch: no motion for stall_timeout while following starts a recovery (or fails after too many).
  if (!anchor_set_ || !withinStall(pose, anchor_pose_)) {
    anchor_pose_ = pose;
    anchor_time_ = time;
    anchor_set_ = true;
  } else if (time - anchor_time_ > options_.stall_timeout) {
    if (recoveries_ >= options_.max_recoveries) {
      state_ = step.state = FollowerState::kFailed;
      return step;
    }
    ++recoveries_;
    if (!last_recovery_moved_ && withinStall(pose, recovery_start_pose_)) {
      recovery_turn_sign_ = -recovery_turn_sign_;  // that turn was blocked: the other way
    } else {
      // Turn towards the side with more room: the mean lateral position of nearby points tells the crowded side.
      double lateral = 0.0;
      for (const common::Point2& point : obstacles)
        if (point.allFinite() && point.norm() < 1.5) lateral += point.y();
      recovery_turn_sign_ = lateral > 0.0 ? -1.0 : 1.0;
    }
    recovery_start_pose_ = pose;
    state_ = FollowerState::kBackingOff;
    recovery_until_ = time + options_.backoff_time;
    anchor_set_ = false;
    step.state = state_;
    if (rearClearance(obstacles, options_) > options_.stop_distance)
      step.command.linear = -options_.backoff_velocity;
    return step;
  }
  return follow(pose, obstacles, step.front_clearance);
}

bool PathFollower::arcHitsObstacle(const std::vector<common::Point2>& obstacles, double linear, double angular,
                                   double max_distance) const {
  if (options_.arc_horizon <= 0.0 || linear <= 0.0) return false;
  const double horizon = std::min(options_.arc_horizon, max_distance / linear);
  const double half_length = 0.5 * options_.footprint_length, half_width = 0.5 * options_.footprint_width;
  const double reach = linear * horizon + std::hypot(half_length, half_width) + options_.side_margin;
  const auto inside = [&](const common::Point2& point, double margin) {
    return std::abs(point.x()) <= half_length + margin && std::abs(point.y()) <= half_width + margin;
  };
  std::vector<common::Point2> near;
  for (const common::Point2& point : obstacles)
    if (point.allFinite() && point.norm() <= reach) near.push_back(point);
  const double margin = movingMargin(near, options_);
  constexpr double kStep = 0.1;  // seconds between checked poses
  for (double t = std::min(kStep, horizon); t <= horizon + 1e-9; t += kStep) {
    // Unicycle pose after t seconds from the origin.
    const double yaw = angular * t;
    const double x = std::abs(angular) > 1e-6 ? linear / angular * std::sin(yaw) : linear * t;
    const double y = std::abs(angular) > 1e-6 ? linear / angular * (1.0 - std::cos(yaw)) : 0.0;
    const double c = std::cos(yaw), s = std::sin(yaw);
    for (const common::Point2& point : near) {
      const double dx = point.x() - x, dy = point.y() - y;
      if (inside(common::Point2(c * dx + s * dy, -s * dx + c * dy), margin)) return true;
    }
  }
  return false;
}

bool PathFollower::inDoorway(const std::vector<common::Point2>& obstacles) const {
  const double half_length = 0.5 * options_.footprint_length, half_width = 0.5 * options_.footprint_width;
  bool left = false, right = false;
  for (const common::Point2& point : obstacles) {
    if (!point.allFinite() || std::abs(point.x()) > half_length) continue;
    if (point.y() > half_width && point.y() <= half_width + options_.doorway_distance) left = true;
    if (point.y() < -half_width && point.y() >= -half_width - options_.doorway_distance) right = true;
  }
  return left && right;
}

common::Point2 PathFollower::centredInGap(const std::vector<common::Point2>& obstacles,
                                          const common::Point2& local) const {
  const double distance = local.norm();
  if (options_.gap_slack <= 0.0 || distance < 1e-6) return local;
  const common::Point2 along = local / distance, across(-along.y(), along.x());
  const double half_length = 0.5 * options_.footprint_length;
  const double widest = options_.footprint_width + 2.0 * (options_.side_margin + options_.gap_slack);
  // The nearest points on either side of the way, from beside the footprint to past the pursued point.
  double left = kInfinity, right = kInfinity;
  for (const common::Point2& point : obstacles) {
    if (!point.allFinite()) continue;
    const double a = point.dot(along), c = point.dot(across);
    if (a < -half_length || a > distance + half_length || std::abs(c) > widest) continue;
    if (c >= 0.0) left = std::min(left, c);
    else right = std::min(right, -c);
  }
  const double width = left + right;
  // No gap, one the robot cannot pass, or one with room to spare.
  if (!(width >= options_.footprint_width && width <= widest)) return local;
  return local + across * (0.5 * (left - right));
}

common::VelocityCommand PathFollower::turnInPlace(double angular, const std::vector<common::Point2>& obstacles,
                                                  double front_clearance) const {
  const double half_length = 0.5 * options_.footprint_length, half_width = 0.5 * options_.footprint_width;
  const double swept_radius = std::hypot(half_length, half_width) + options_.side_margin;
  bool front = false, rear = false;
  for (const common::Point2& point : obstacles) {
    if (!point.allFinite() || point.norm() >= swept_radius) continue;
    if (std::abs(point.x()) <= half_length && std::abs(point.y()) <= half_width) continue;  // inside: not the turn's fault
    (point.x() >= 0.0 ? front : rear) = true;
  }
  const bool ahead_free = front_clearance > options_.stop_distance;
  common::VelocityCommand command;
  command.angular = angular;
  if (front && !rear) {
    if (rearClearance(obstacles, options_) > options_.stop_distance) command.linear = -options_.creep_velocity;
  } else if (rear && !front) {
    if (ahead_free) command.linear = options_.creep_velocity;
  } else if (front && rear && ahead_free) {
    // Hemmed in on both halves (in a doorway): leave straight ahead before turning.
    command.linear = options_.creep_velocity;
    command.angular = 0.0;
  }
  return command;
}

FollowerStep PathFollower::follow(const common::Pose2& pose, const std::vector<common::Point2>& obstacles,
                                  double clearance) {
  FollowerStep step;
  step.state = state_;
  step.front_clearance = clearance;
  // Pursued point: the first path point at least `lookahead` from the robot after the closest one, else the end.
  const common::Point2 position(pose.x, pose.y);
  common::Point2 target = path_.back();
  for (size_t i = closest_index_; i < path_.size(); ++i)
    if ((path_[i] - position).norm() >= options_.lookahead) {
      target = path_[i];
      break;
    }
  const common::Point2 local = centredInGap(obstacles, toRobotFrame(pose, target));
  const double heading_error = std::atan2(local.y(), local.x());
  if (std::abs(heading_error) > options_.rotate_in_place_angle) {
    step.command = turnInPlace(std::clamp(options_.heading_gain * heading_error, -options_.max_angular_velocity,
                                          options_.max_angular_velocity),
                               obstacles, clearance);
    return step;
  }
  // Speed: the maximum, less when the heading is off, capped by the free space ahead and the distance to the end.
  const double free_ahead = std::max(0.0, clearance - options_.stop_distance);
  const double to_goal = (path_.back() - position).norm();
  double linear = options_.max_linear_velocity * (1.0 - 0.5 * std::abs(heading_error) / options_.rotate_in_place_angle);
  linear = std::min({linear, std::sqrt(2.0 * options_.deceleration * free_ahead),
                     std::sqrt(2.0 * options_.deceleration * to_goal) + 0.05});
  const double squared_distance = std::max(local.squaredNorm(), 1e-6);
  const double curvature = 2.0 * local.y() / squared_distance;
  double angular = linear * curvature;
  if (std::abs(angular) > options_.max_angular_velocity) {
    angular = std::copysign(options_.max_angular_velocity, angular);
    linear = std::abs(angular / curvature);
  }
  // Steering around what the laser sees: when the pure-pursuit arc would touch something (checked no further
  // than the path's end), the nearest turn rate whose arc is clear (at this speed, else at half of it). When none
  // is, the command stays: the speed cap above stops the robot in front of what lies ahead.
  const double check_distance = remainingLength(pose) + 0.1;
  if (linear > 1e-3 && arcHitsObstacle(obstacles, linear, angular, check_distance)) {
    bool found = false;
    for (const double speed : {linear, 0.5 * linear}) {
      for (int k = 1; k <= 8 && !found; ++k)
        for (const double sign : {1.0, -1.0}) {
          const double candidate = std::clamp(angular + sign * k * 0.125 * options_.max_angular_velocity,
                                              -options_.max_angular_velocity, options_.max_angular_velocity);
          if (!arcHitsObstacle(obstacles, speed, candidate, check_distance)) {
            linear = speed;
            angular = candidate;
            found = true;
            break;
          }
        }
      if (found) break;
    }
  }
  // In a doorway (something beside both sides within doorway_distance), turn slowly: the rear would swing into
  // the frame, where the laser does not look.
  if (inDoorway(obstacles)) angular = std::clamp(angular, -options_.doorway_angular_velocity, options_.doorway_angular_velocity);
  if (linear <= 1e-3) {
    // Blocked ahead. When only the lane's side margins hold what stops it (a wall's end beside its way, the
    // footprint's own width clear), creep straight on: the robot passes the wall's end at the side distance it
    // has now, and then turns round it (creep_velocity 0: never). Otherwise turn towards the path (the stall watch
    // starts a recovery if nothing changes).
    if (options_.creep_velocity > 0.0 && laneClearance(obstacles, options_, 1.0, 0.0) > options_.stop_distance) {
      step.command.linear = options_.creep_velocity;
      step.command.angular = 0.0;
      return step;
    }
    angular = std::clamp(options_.heading_gain * heading_error, -options_.max_angular_velocity,
                         options_.max_angular_velocity);
    linear = 0.0;
  }
  step.command.linear = linear;
  step.command.angular = angular;
  return step;
}

}  // namespace hidden_rooms::exploration
