#include "hidden_rooms/exploration/exploration_policy.h"

namespace hidden_rooms::exploration {

const common::OptionTable<ExplorationPolicyOptions>& explorationPolicyOptionTable() {
  using O = ExplorationPolicyOptions;
  static const common::OptionTable<O> table{
      {"replan_interval", &O::replan_interval, "seconds between replans without a new map; 0 = on new maps only",
       common::atLeast(0)},
      {"goal_hysteresis", &O::goal_hysteresis, "path cost (metres) by which another goal must be cheaper",
       common::atLeast(0)},
      {"blacklist_radius", &O::blacklist_radius, "metres around a reached or failed goal where no goal is chosen",
       common::atLeast(0)},
      {"done_confirmations", &O::done_confirmations, "new maps in a row without a reachable frontier before done",
       common::atLeast(1)},
      {"search_angular_velocity", &O::search_angular_velocity, "rad/s turned in place while there is no goal"},
      {"obstacle_memory", &O::obstacle_memory, "seconds the laser points of past scans are kept", common::atLeast(0)},
      {"trail_length", &O::trail_length,
       "metres of the robot's latest path the planner may use however narrow once nothing else is left; 0 = never",
       common::atLeast(0)},
  };
  return table;
}

namespace {

// Half ROS time's resolution: time differences closer than this to a threshold reach it.
constexpr double kTimeEpsilon = 0.5e-9;
// Metres between the points of the robot's trail (a map cell or so).
constexpr double kTrailSpacing = 0.05;

ExplorationEvent event(ExplorationEventType type, const common::Point2& position = common::Point2::Zero(),
                       size_t count = 0) {
  ExplorationEvent result;
  result.type = type;
  result.position = position;
  result.count = count;
  return result;
}

}  // namespace

ExplorationPolicy::ExplorationPolicy(const ExplorationPolicyOptions& options)
    : options_(options),
      planner_(options.planner),
      follower_(options.follower),
      passages_(options.passages),
      obstacle_memory_(options.obstacle_memory),
      seen_walls_(options.frontiers.seen_wall_range, options.frontiers.seen_wall_margin) {
  blacklist_.radius = options.blacklist_radius;
}

ExplorationPolicy::~ExplorationPolicy() {
  if (background_plan_.valid()) background_plan_.wait();
}

void ExplorationPolicy::setMap(const common::OccupancyGrid& map) {
  next_map_ = map;
  pending_map_ = PendingMap::kUsable;
}

void ExplorationPolicy::setUnusableMap(const std::string& reason) {
  next_map_ = common::OccupancyGrid();
  unusable_reason_ = reason;
  pending_map_ = PendingMap::kUnusable;
}

void ExplorationPolicy::addScan(const std::vector<common::Point2>& points, const common::Pose2& pose, double time) {
  obstacle_memory_.add(points, pose, time);
  seen_walls_.addScan(points, pose, time);
}

void ExplorationPolicy::hold(double time) { follower_.hold(time); }

ExplorationStep ExplorationPolicy::update(const common::Pose2& pose, double time) {
  ExplorationStep step;
  recordTrail(common::Point2(pose.x, pose.y));
  // The follower sees the latest scan and the remembered ones (placed with the robot's current pose).
  const std::vector<common::Point2> obstacles = obstacle_memory_.points(pose);

  // Replan on a new map, every replan_interval, and when the follower has nothing to do; recovery manoeuvres
  // run to their end first.
  const FollowerState state = follower_.state();
  const bool recovering = state == FollowerState::kBackingOff || state == FollowerState::kRecoveryRotating;
  const bool replan_due =
      options_.replan_interval > 0.0 && time - last_plan_ >= options_.replan_interval - kTimeEpsilon;
  if (background_plan_.valid() &&
      background_plan_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    choose(background_plan_.get(), pose, time, &step);
    goal_ended_ = false;
  }
  if (!recovering && (pending_map_ != PendingMap::kNone || replan_due)) plan(pose, time, &step);

  if (goal_) {
    const FollowerStep followed = follower_.update(pose, obstacles, time);
    if (followed.state != FollowerState::kGoalReached && followed.state != FollowerState::kFailed) {
      step.command = followed.command;
      return step;
    }
    finishGoal(pose, followed.state, &step);
    plan(pose, time, &step);
    if (goal_) {
      step.command = follower_.update(pose, obstacles, time).command;
      return step;
    }
    goal_ended_ = background_plan_.valid();
  }
  if (goal_ended_) return step;  // stand still until the plan for the next goal is in
  // No goal: turn in place to look around until a frontier shows up or done is confirmed.
  if (!done_) step.command.angular = options_.search_angular_velocity;
  return step;
}

void ExplorationPolicy::recordTrail(const common::Point2& position) {
  if (options_.trail_length <= 0.0) return;
  if (!trail_.empty()) {
    const double step = (position - trail_.back()).norm();
    if (step < kTrailSpacing) return;
    trail_metres_ += step;
  }
  trail_.push_back(position);
  size_t drop = 0;
  while (trail_.size() - drop > 2 && trail_metres_ > options_.trail_length) {
    trail_metres_ -= (trail_[drop + 1] - trail_[drop]).norm();
    ++drop;
  }
  trail_.erase(trail_.begin(), trail_.begin() + static_cast<std::ptrdiff_t>(drop));
}

void ExplorationPolicy::finishGoal(const common::Pose2& pose, FollowerState outcome, ExplorationStep* step) {
  // A reached goal whose frontier is still there next time cannot be seen from there: no goal near it again.
  // A failed one gets one more try when nothing else is left; one failed because the robot could not move at
  // all (no recovery moved it), a try each time nothing else is left.
  const bool failed = outcome == FollowerState::kFailed;
  const bool robot_stuck =
      failed && follower_.recoveries() > 0 && follower_.recoveriesWithoutMotion() == follower_.recoveries();
  const bool released_later = blacklist_.add(goal_->position, !failed      ? GoalOutcome::kReached
                                                              : robot_stuck ? GoalOutcome::kRobotStuck
                                                                            : GoalOutcome::kFailed);
  ExplorationEvent ended = event(!failed      ? ExplorationEventType::kGoalReached
                                 : robot_stuck ? ExplorationEventType::kGoalFailedStuck
                                               : ExplorationEventType::kGoalFailed,
                                 goal_->position);
  ended.recoveries = follower_.recoveries();
  ended.retry_later = failed && !robot_stuck && released_later;
  step->events.push_back(ended);

  const size_t blocked_before = passages_.blockedPoints().size();
  const common::Point2 robot(pose.x, pose.y);
  if (failed && !robot_stuck && passages_.addFailure(robot, follower_.path())) {
    planner_.setBlockedPoints(passages_.blockedPoints(), options_.passages.radius);
    step->events.push_back(event(passages_.blockedPoints().size() > blocked_before
                                     ? ExplorationEventType::kPassageBlocked
                                     : ExplorationEventType::kPassageOpened,
                                 robot));
  }
  goal_.reset();
  trail_open_ = false;
}

ExplorationPolicy::CostMap ExplorationPolicy::computeCostMap(const ExplorationPolicyOptions& options,
                                                             const Blacklist& blacklist,
                                                             const std::vector<common::Point2>& blocked_points,
                                                             const std::vector<common::Point2>& trail,
                                                             const common::OccupancyGrid& map,
                                                             const cv::Mat1b& seen_walls,
                                                             const common::Point2& robot, bool new_map) {
  CostMap result{GridPlanner(options.planner), FrontierMap(), false, new_map};
  result.planner.setBlockedPoints(blocked_points, options.passages.radius);
  result.planner.setTrail(trail);
  result.planner.setMap(map);
  result.frontiers = findFrontiers(result.planner.map(), options.frontiers, seen_walls);
  const cv::Mat1b targets = goalCandidates(result.frontiers, result.planner, blacklist, options.frontiers, robot,
                                           options.planner.start_escape_radius);
  result.start_reachable = result.planner.computeCostsFrom(robot, targets, options.goal_hysteresis);
  return result;
}

void ExplorationPolicy::plan(const common::Pose2& pose, double time, ExplorationStep* step) {
  if (background_plan_.valid()) return;  // one at a time
  last_plan_ = time;
  const PendingMap pending = pending_map_;
  pending_map_ = PendingMap::kNone;
  if (pending == PendingMap::kUnusable) {
    ExplorationEvent unusable = event(ExplorationEventType::kMapUnusable);
    unusable.message = unusable_reason_;
    step->events.push_back(unusable);
    return;
  }
  const bool new_map = pending == PendingMap::kUsable;
  const common::OccupancyGrid map = new_map ? next_map_ : planner_.map();
  if (new_map) {
    next_map_ = common::OccupancyGrid();
    seen_walls_.setGrid(map);
    map_time_ = time;
  }
  // Walls the laser saw long enough before this map that the map would show them.
  const cv::Mat1b seen_walls = seen_walls_.seenBy(map_time_ - options_.frontiers.seen_wall_delay);
  const common::Point2 robot(pose.x, pose.y);
  if (!options_.background_planning) {
    choose(computeCostMap(options_, blacklist_, passages_.blockedPoints(), openTrail(), map, seen_walls, robot,
                          new_map),
           pose, time, step);
    return;
  }
  background_plan_ = std::async(std::launch::async, &ExplorationPolicy::computeCostMap, options_, blacklist_,
                                passages_.blockedPoints(), openTrail(), map, seen_walls, robot, new_map);
}

void ExplorationPolicy::choose(CostMap cost_map, const common::Pose2& pose, double time, ExplorationStep* step) {
  planner_ = std::move(cost_map.planner);
  frontiers_ = std::move(cost_map.frontiers);
  const bool new_map = cost_map.new_map;
  const common::Point2 robot(pose.x, pose.y);
  step->planned = true;
  if (!cost_map.start_reachable) {
    step->events.push_back(event(ExplorationEventType::kStartBlocked, robot));
    return;
  }
  const std::optional<common::Point2> previous = goal_ && follower_.state() == FollowerState::kFollowing
                                                     ? std::optional<common::Point2>(goal_->position)
                                                     : std::nullopt;
  // The nearest goal with the current blacklist and costs (tried again after each release below).
  const auto nearest = [&] {
    return nearestFrontierGoal(frontiers_, planner_, blacklist_, options_.frontiers, previous,
                               options_.goal_hysteresis);
  };
  std::optional<FrontierGoal> goal = nearest();
  if (!goal && planner_.searchWasBounded()) {
    // The bound was set by a candidate blacklisted since the plan started (in the background): costs everywhere.
    planner_.computeCostsFrom(robot);
    goal = nearest();
  }
  if (!goal && !blacklist_.stuck_points.empty()) {
    // Not done while the only goals left failed because the robot could not move: try them again (their
    // recoveries are what may free the robot).
    step->events.push_back(event(ExplorationEventType::kStuckReleased, robot, blacklist_.releaseStuck()));
    goal = nearest();
  }
  if (!goal) {
    const size_t unblocked = passages_.releaseOnce();
    if (unblocked > 0) {
      // A passage may have been blocked by failures with another cause: before done, each is tried once more.
      step->events.push_back(event(ExplorationEventType::kPassagesReleased, robot, unblocked));
      planner_.setBlockedPoints({}, 0.0);
      if (planner_.computeCostsFrom(robot)) goal = nearest();
    }
  }
  if (!goal && !blacklist_.failed_points.empty()) {
    step->events.push_back(event(ExplorationEventType::kFailedReleased, robot, blacklist_.releaseFailed()));
    goal = nearest();
  }
  if (!goal && !trail_open_ && trail_.size() > 1 && !frontiers_.frontiers.empty()) {
    // No frontier can be reached: the way the robot came in is a way out, however narrow the map now draws it.
    trail_open_ = true;
    ExplorationEvent opened = event(ExplorationEventType::kTrailOpened, robot);
    opened.path_length = trail_metres_;
    step->events.push_back(opened);
    planner_.setTrail(trail_);
    if (planner_.computeCostsFrom(robot)) goal = nearest();
  }
  if (!goal) {
    // No frontier can be reached: look past those the laser can see from where the robot can go.
    if (planner_.searchWasBounded()) planner_.computeCostsFrom(robot);
    goal = nearestLookGoal(frontiers_, planner_, blacklist_, options_.frontiers, previous, options_.goal_hysteresis);
  }
  if (!goal) {
    goal_.reset();
    follower_.stop();
    // Only plans on new maps count towards done (the map must have had the chance to change).
    if (new_map) ++plans_without_goal_;
    if (plans_without_goal_ >= options_.done_confirmations && !done_) {
      done_ = true;
      ExplorationEvent finished = event(ExplorationEventType::kDone, robot);
      finished.blacklisted = blacklist_.points.size();
      step->events.push_back(finished);
    }
    if (!done_) {
      ExplorationEvent none = event(ExplorationEventType::kNoGoal, robot, frontiers_.frontiers.size());
      none.blacklisted = blacklist_.points.size();
      step->events.push_back(none);
    }
    return;
  }
  plans_without_goal_ = 0;
  if (done_) {
    done_ = false;
    step->events.push_back(event(ExplorationEventType::kResumed, robot));
  }
  const std::vector<common::Point2> path = planner_.pathTo(goal->cell.x, goal->cell.y);
  const bool same_goal = goal_ && (goal_->position - goal->position).norm() < 1e-6;
  if (same_goal && follower_.state() == FollowerState::kFollowing) {
    follower_.updatePath(path);
  } else {
    follower_.setPath(path, time);
    ExplorationEvent chosen = event(ExplorationEventType::kGoalChosen, goal->position);
    chosen.cost = goal->cost;
    chosen.path_length = pathLength(path);
    chosen.look = goal->look;
    step->events.push_back(chosen);
  }
  goal_ = goal;
}

}  // namespace hidden_rooms::exploration
