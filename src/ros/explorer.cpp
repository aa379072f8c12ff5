#include "hidden_rooms/ros/explorer.h"

#include <cmath>

#include <geometry_msgs/Twist.h>
#include <std_msgs/Bool.h>
#include <visualization_msgs/MarkerArray.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/range_scan.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/ros/markers.h"

namespace hidden_rooms {

ExplorerOptions readExplorerOptions(const ros::NodeHandle& nh) {
  ExplorerOptions options;
  GridPlannerOptions& planner = options.planner;
  nh.param("free_threshold", planner.free_threshold, planner.free_threshold);
  nh.param("occupied_threshold", planner.occupied_threshold, planner.occupied_threshold);
  nh.param("robot_radius", planner.robot_radius, planner.robot_radius);
  nh.param("min_clearance", planner.min_clearance, planner.min_clearance);
  nh.param("narrow_cost_factor", planner.narrow_cost_factor, planner.narrow_cost_factor);
  nh.param("cost_radius", planner.cost_radius, planner.cost_radius);
  nh.param("cost_weight", planner.cost_weight, planner.cost_weight);
  nh.param("start_escape_radius", planner.start_escape_radius, planner.start_escape_radius);
  nh.param("smoothing_window", planner.smoothing_window, planner.smoothing_window);
  validate(planner);

  FrontierOptions& frontiers = options.frontiers;
  frontiers.free_threshold = planner.free_threshold;
  frontiers.occupied_threshold = planner.occupied_threshold;
  nh.param("min_frontier_cells", frontiers.min_frontier_cells, frontiers.min_frontier_cells);
  nh.param("min_unknown_cells", frontiers.min_unknown_cells, frontiers.min_unknown_cells);
  nh.param("goal_reach", frontiers.goal_reach, frontiers.goal_reach);
  nh.param("min_goal_distance", frontiers.min_goal_distance, frontiers.min_goal_distance);
  if (frontiers.min_frontier_cells < 1) throw InputError("~min_frontier_cells", "must be at least 1");
  if (frontiers.min_unknown_cells < 1) throw InputError("~min_unknown_cells", "must be at least 1");
  if (!std::isfinite(frontiers.goal_reach) || frontiers.goal_reach < 0.0)
    throw InputError("~goal_reach", "must be zero or positive");
  if (!std::isfinite(frontiers.min_goal_distance) || frontiers.min_goal_distance < 0.0)
    throw InputError("~min_goal_distance", "must be zero or positive");

  PathFollowerOptions& follower = options.follower;
  nh.param("max_linear_velocity", follower.max_linear_velocity, follower.max_linear_velocity);
  nh.param("max_angular_velocity", follower.max_angular_velocity, follower.max_angular_velocity);
  nh.param("lookahead", follower.lookahead, follower.lookahead);
  nh.param("goal_tolerance", follower.goal_tolerance, follower.goal_tolerance);
  nh.param("rotate_in_place_angle", follower.rotate_in_place_angle, follower.rotate_in_place_angle);
  nh.param("heading_gain", follower.heading_gain, follower.heading_gain);
  nh.param("footprint_length", follower.footprint_length, follower.footprint_length);
  nh.param("footprint_width", follower.footprint_width, follower.footprint_width);
  nh.param("side_margin", follower.side_margin, follower.side_margin);
  nh.param("stop_distance", follower.stop_distance, follower.stop_distance);
  nh.param("deceleration", follower.deceleration, follower.deceleration);
  nh.param("creep_velocity", follower.creep_velocity, follower.creep_velocity);
  nh.param("arc_horizon", follower.arc_horizon, follower.arc_horizon);
  nh.param("doorway_distance", follower.doorway_distance, follower.doorway_distance);
  nh.param("doorway_angular_velocity", follower.doorway_angular_velocity, follower.doorway_angular_velocity);
  nh.param("stall_timeout", follower.stall_timeout, follower.stall_timeout);
  nh.param("stall_distance", follower.stall_distance, follower.stall_distance);
  nh.param("stall_angle", follower.stall_angle, follower.stall_angle);
  nh.param("backoff_time", follower.backoff_time, follower.backoff_time);
  nh.param("backoff_velocity", follower.backoff_velocity, follower.backoff_velocity);
  nh.param("recovery_rotate_time", follower.recovery_rotate_time, follower.recovery_rotate_time);
  nh.param("progress_timeout", follower.progress_timeout, follower.progress_timeout);
  nh.param("progress_distance", follower.progress_distance, follower.progress_distance);
  nh.param("max_recoveries", follower.max_recoveries, follower.max_recoveries);
  validate(follower);

  BlockedPassagesOptions& passages = options.passages;
  nh.param("blocked_passage_failures", passages.failures, passages.failures);
  nh.param("blocked_passage_length", passages.length, passages.length);
  nh.param("blocked_passage_radius", passages.radius, passages.radius);
  validate(passages);

  nh.param("map_frame", options.map_frame, options.map_frame);
  nh.param("base_frame", options.base_frame, options.base_frame);
  nh.param("control_rate", options.control_rate, options.control_rate);
  nh.param("replan_interval", options.replan_interval, options.replan_interval);
  nh.param("goal_hysteresis", options.goal_hysteresis, options.goal_hysteresis);
  nh.param("blacklist_radius", options.blacklist_radius, options.blacklist_radius);
  nh.param("done_confirmations", options.done_confirmations, options.done_confirmations);
  nh.param("search_angular_velocity", options.search_angular_velocity, options.search_angular_velocity);
  nh.param("scan_timeout", options.scan_timeout, options.scan_timeout);
  nh.param("pose_timeout", options.pose_timeout, options.pose_timeout);
  nh.param("map_timeout", options.map_timeout, options.map_timeout);
  nh.param("obstacle_memory", options.obstacle_memory, options.obstacle_memory);
  if (options.map_frame.empty() || options.base_frame.empty())
    throw InputError("~map_frame, ~base_frame", "must not be empty");
  if (!std::isfinite(options.control_rate) || options.control_rate <= 0.0)
    throw InputError("~control_rate", "must be positive");
  for (const auto& [name, value] : {std::pair<const char*, double>{"replan_interval", options.replan_interval},
                                    {"goal_hysteresis", options.goal_hysteresis},
                                    {"blacklist_radius", options.blacklist_radius},
                                    {"map_timeout", options.map_timeout},
                                    {"obstacle_memory", options.obstacle_memory}})
    if (!std::isfinite(value) || value < 0.0) throw InputError(std::string("~") + name, "must be zero or positive");
  for (const auto& [name, value] : {std::pair<const char*, double>{"scan_timeout", options.scan_timeout},
                                    {"pose_timeout", options.pose_timeout}})
    if (!std::isfinite(value) || value <= 0.0) throw InputError(std::string("~") + name, "must be positive");
  if (!std::isfinite(options.search_angular_velocity)) throw InputError("~search_angular_velocity", "must be finite");
  if (options.done_confirmations < 1) throw InputError("~done_confirmations", "must be at least 1");
  return options;
}

Explorer::Explorer(ros::NodeHandle nh, const ExplorerOptions& options)
    : options_(options),
      planner_(options.planner),
      follower_(options.follower),
      passages_(options.passages),
      tf_buffer_(ros::Duration(10.0)),
      tf_listener_(tf_buffer_),
      obstacle_memory_(options.obstacle_memory) {
  blacklist_.radius = options.blacklist_radius;
  map_subscriber_ = nh.subscribe("map", 1, &Explorer::onMap, this);
  scan_subscriber_ = nh.subscribe("base_scan", 1, &Explorer::onScan, this);
  command_publisher_ = nh.advertise<geometry_msgs::Twist>("cmd_vel", 1);
  done_publisher_ = nh.advertise<std_msgs::Bool>("exploration_done", 1, true);
  markers_publisher_ = nh.advertise<visualization_msgs::MarkerArray>("exploration_markers", 1, true);
  std_msgs::Bool not_done;
  done_publisher_.publish(not_done);
  timer_ = nh.createTimer(ros::Duration(1.0 / options.control_rate), &Explorer::onTimer, this);
}

void Explorer::onMap(const nav_msgs::OccupancyGrid::ConstPtr& map) {
  if (map->info.width == 0 || map->info.height == 0) {
    ROS_WARN_THROTTLE(5.0, "explorer: empty map received; ignored");
    return;
  }
  latest_map_ = map;
  map_received_ = ros::Time::now();
  map_changed_ = true;
}

void Explorer::onScan(const sensor_msgs::LaserScan::ConstPtr& scan) {
  Pose2 sensor;
  try {
    sensor = fromRos(tf_buffer_.lookupTransform(options_.base_frame, scan->header.frame_id, ros::Time(0)).transform);
  } catch (const tf2::TransformException& error) {
    ROS_WARN_THROTTLE(5.0, "explorer: no transform %s -> %s (%s); scan ignored", options_.base_frame.c_str(),
                      scan->header.frame_id.c_str(), error.what());
    return;
  }
  try {
    int skipped = 0;
    scan_points_ = obstaclePoints(fromRos(*scan, sensor), &skipped);
    scan_remembered_ = false;
    int non_finite = 0;
    for (float range : scan->ranges) non_finite += !std::isfinite(range);
    if (non_finite > 0)
      ROS_WARN_THROTTLE(10.0, "explorer: %d of %zu ranges of a scan are not finite; skipped", non_finite,
                        scan->ranges.size());
    latest_scan_ = scan;
  } catch (const InputError& error) {
    ROS_WARN_THROTTLE(5.0, "explorer: bad scan: %s", error.what());
  }
}

bool Explorer::robotPose(Pose2* pose) {
  try {
    const geometry_msgs::TransformStamped transform =
        tf_buffer_.lookupTransform(options_.map_frame, options_.base_frame, ros::Time(0));
    if ((ros::Time::now() - transform.header.stamp).toSec() > options_.pose_timeout) {
      ROS_WARN_THROTTLE(5.0, "explorer: %s -> %s is %.1f s old; stopped", options_.map_frame.c_str(),
                        options_.base_frame.c_str(), (ros::Time::now() - transform.header.stamp).toSec());
      return false;
    }
    *pose = fromRos(transform.transform);
    return true;
  } catch (const tf2::TransformException& error) {
    ROS_WARN_THROTTLE(5.0, "explorer: waiting for %s -> %s: %s", options_.map_frame.c_str(), options_.base_frame.c_str(),
                      error.what());
    return false;
  }
}

void Explorer::holdRobot(const ros::Time& now) {
  follower_.hold(now.toSec());
  publishCommand(VelocityCommand());
}

void Explorer::onTimer(const ros::TimerEvent&) {
  const ros::Time now = ros::Time::now();
  if (!latest_map_) {
    ROS_INFO_THROTTLE(10.0, "explorer: waiting for a map on %s", map_subscriber_.getTopic().c_str());
    return;
  }
  Pose2 pose;
  if (!robotPose(&pose)) {
    holdRobot(now);
    return;
  }
  if (last_pose_) distance_driven_ += std::hypot(pose.x - last_pose_->x, pose.y - last_pose_->y);
  last_pose_ = pose;
  if (!latest_scan_ || (now - latest_scan_->header.stamp).toSec() > options_.scan_timeout) {
    ROS_WARN_THROTTLE(5.0, "explorer: no recent scan on %s; stopped", scan_subscriber_.getTopic().c_str());
    holdRobot(now);
    return;
  }
  // The map stopped coming (the mapper died or hangs): stop until it comes again; the goal and the follower's
  // state are kept (a map arrived at ROS time 0, before the clock, counts from the first tick).
  if (map_received_.isZero()) map_received_ = now;
  const double map_age = (now - map_received_).toSec();
  if (options_.map_timeout > 0.0 && map_age > options_.map_timeout) {
    if (!done_)
      ROS_WARN_THROTTLE(5.0, "explorer: no new map on %s for %.1f s (mapper down?); stopped until one comes",
                        map_subscriber_.getTopic().c_str(), map_age);
    map_stale_ = true;
    holdRobot(now);
    return;
  }
  if (map_stale_) {
    ROS_INFO("explorer: maps on %s again; exploring on", map_subscriber_.getTopic().c_str());
    map_stale_ = false;
  }

  // The follower sees the latest scan and the remembered ones (placed with the robot's current pose).
  if (!scan_remembered_) {
    obstacle_memory_.add(scan_points_, pose, now.toSec());
    scan_remembered_ = true;
  }
  const std::vector<Point2> obstacles = obstacle_memory_.points(pose);

  // Replan on a new map, every replan_interval, and when the follower has nothing to do; recovery manoeuvres
  // run to their end first.
  const FollowerState state = follower_.state();
  const bool recovering = state == FollowerState::kBackingOff || state == FollowerState::kRecoveryRotating;
  const bool replan_due = options_.replan_interval > 0.0 && (now - last_plan_).toSec() >= options_.replan_interval;
  if (!recovering && (map_changed_ || replan_due)) plan(pose, now);

  if (goal_) {
    const FollowerStep step = follower_.update(pose, obstacles, now.toSec());
    if (step.state != FollowerState::kGoalReached && step.state != FollowerState::kFailed) {
      publishCommand(step.command);
      return;
    }
    // A reached goal whose frontier is still there next time cannot be seen from there: no goal near it again.
    // A failed one gets one more try when nothing else is left; one failed because the robot could not move at
    // all (no recovery moved it), a try each time nothing else is left.
    const bool robot_stuck = step.state == FollowerState::kFailed && follower_.recoveries() > 0 &&
                             follower_.recoveriesWithoutMotion() == follower_.recoveries();
    const bool released_later =
        blacklist_.add(goal_->position, step.state == FollowerState::kGoalReached ? GoalOutcome::kReached
                                        : robot_stuck                            ? GoalOutcome::kRobotStuck
                                                                                 : GoalOutcome::kFailed);
    if (robot_stuck)
      ROS_WARN("explorer: goal (%.2f, %.2f) failed: the robot did not move in %d recoveries (stuck?); "
               "blacklisted until no other goal is left", goal_->position.x(), goal_->position.y(),
               follower_.recoveries());
    else if (step.state == FollowerState::kFailed)
      ROS_WARN("explorer: goal (%.2f, %.2f) not reached (%d recoveries, no progress); blacklisted (%s)",
               goal_->position.x(), goal_->position.y(), follower_.recoveries(),
               released_later ? "a second try when no other goal is left" : "it failed there on its second try");
    const size_t blocked_before = passages_.blockedPoints().size();
    if (step.state == FollowerState::kFailed && !robot_stuck &&
        passages_.addFailure(Point2(pose.x, pose.y), follower_.path())) {
      planner_.setBlockedPoints(passages_.blockedPoints(), options_.passages.radius);
      if (passages_.blockedPoints().size() > blocked_before)
        ROS_WARN("explorer: %d goals failed from (%.2f, %.2f) in one direction: the path ahead is blocked for the "
                 "planner", options_.passages.failures, pose.x, pose.y);
      else
        ROS_WARN("explorer: goals failed from (%.2f, %.2f) in different directions: the robot is stuck there, not "
                 "a passage ahead; opened again", pose.x, pose.y);
    }
    goal_.reset();
    plan(pose, now);
    if (goal_) {
      publishCommand(follower_.update(pose, obstacles, now.toSec()).command);
      return;
    }
  }
  // No goal: turn in place to look around until a frontier shows up or done is confirmed.
  VelocityCommand look_around;
  if (!done_) look_around.angular = options_.search_angular_velocity;
  publishCommand(look_around);
}

void Explorer::plan(const Pose2& pose, const ros::Time& now) {
  last_plan_ = now;
  const bool new_map = map_changed_;
  if (map_changed_) {
    try {
      planner_.setMap(fromRos(*latest_map_));
    } catch (const InputError& error) {
      ROS_WARN_THROTTLE(5.0, "explorer: unusable map: %s", error.what());
      map_changed_ = false;
      return;
    }
    map_changed_ = false;
  }
  const FrontierMap frontiers = findFrontiers(planner_.map(), options_.frontiers);
  if (!planner_.computeCostsFrom(Point2(pose.x, pose.y))) {
    ROS_WARN_THROTTLE(5.0, "explorer: robot at (%.2f, %.2f) is not within %.2f m of a traversable map cell; "
                      "waiting for the map (or a recovery) to free it", pose.x, pose.y,
                      options_.planner.start_escape_radius);
    publishMarkers(frontiers, now);
    return;
  }
  const std::optional<Point2> previous =
      goal_ && follower_.state() == FollowerState::kFollowing ? std::optional<Point2>(goal_->position) : std::nullopt;
  // The nearest goal with the current blacklist and costs (tried again after each release below).
  const auto nearest = [&] {
    return nearestFrontierGoal(frontiers, planner_, blacklist_, options_.frontiers, previous, options_.goal_hysteresis);
  };
  std::optional<FrontierGoal> goal = nearest();
  if (!goal && !blacklist_.stuck_points.empty()) {
    // Not done while the only goals left failed because the robot could not move: try them again (their
    // recoveries are what may free the robot).
    ROS_WARN("explorer: no other goal; %zu goals failed while the robot could not move: trying them again",
             blacklist_.releaseStuck());
    goal = nearest();
  }
  if (!goal) {
    const size_t unblocked = passages_.releaseOnce();
    if (unblocked > 0) {
      // A passage may have been blocked by failures with another cause: before done, each is tried once more.
      ROS_WARN("explorer: no other goal; opening the blocked passages again (%zu points, once)", unblocked);
      planner_.setBlockedPoints({}, 0.0);
      if (planner_.computeCostsFrom(Point2(pose.x, pose.y)))
        goal = nearest();
    }
  }
  if (!goal && !blacklist_.failed_points.empty()) {
    ROS_WARN("explorer: no other goal; %zu failed goals get their second try", blacklist_.releaseFailed());
    goal = nearest();
  }
  if (!goal) {
    goal_.reset();
    follower_.stop();
    // Only plans on new maps count towards done (the map must have had the chance to change).
    if (new_map) ++plans_without_goal_;
    if (plans_without_goal_ >= options_.done_confirmations && !done_) setDone(true, now);
    if (!done_)
      ROS_INFO("explorer: no reachable frontier (%zu frontiers, %zu blacklisted places); checking again",
               frontiers.frontiers.size(), blacklist_.points.size());
    publishMarkers(frontiers, now);
    return;
  }
  plans_without_goal_ = 0;
  if (done_) setDone(false, now);
  std::vector<Point2> path = planner_.pathTo(goal->cell.x, goal->cell.y);
  const bool same_goal = goal_ && (goal_->position - goal->position).norm() < 1e-6;
  if (same_goal && follower_.state() == FollowerState::kFollowing) {
    follower_.updatePath(path);
  } else {
    follower_.setPath(path, now.toSec());
    ++goals_chosen_;
    ROS_DEBUG("explorer: goal (%.2f, %.2f), path %.2f m, cost %.2f", goal->position.x(), goal->position.y(),
              pathLength(path), goal->cost);
  }
  goal_ = goal;
  publishMarkers(frontiers, now);
}

void Explorer::setDone(bool done, const ros::Time& now) {
  done_ = done;
  std_msgs::Bool message;
  message.data = done;
  done_publisher_.publish(message);
  if (done)
    ROS_INFO("explorer: exploration done: no reachable frontier left (t = %.1f s, %.1f m driven, %d goals, "
             "%zu blacklisted places)", now.toSec(), distance_driven_, goals_chosen_, blacklist_.points.size());
  else
    ROS_INFO("explorer: a reachable frontier appeared; exploring again");
}

void Explorer::publishCommand(const VelocityCommand& command) {
  const bool stop = command.linear == 0.0 && command.angular == 0.0;
  if (stop && stopped_) return;  // one stop is enough (the simulator's watchdog also stops a silent robot)
  stopped_ = stop;
  command_publisher_.publish(toRos(command));
}

void Explorer::publishMarkers(const FrontierMap& frontiers, const ros::Time& now) {
  if (markers_publisher_.getNumSubscribers() == 0) return;
  ExplorationView view;
  view.frontiers = &frontiers;
  if (goal_) {
    view.goal_frontier_label = goal_->frontier_label;
    view.goal = goal_->position;
    view.path = follower_.path();
  }
  view.blacklist = blacklist_.points;
  view.blocked_passages = passages_.blockedPoints();
  view.blocked_passage_radius = options_.passages.radius;
  markers_publisher_.publish(toMarkers(planner_.map(), view, options_.map_frame, now));
}

}  // namespace hidden_rooms
