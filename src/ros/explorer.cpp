#include "hidden_rooms/ros/explorer.h"

#include <cmath>

#include <geometry_msgs/Twist.h>
#include <hidden_rooms/ExplorationStatus.h>
#include <std_msgs/Bool.h>
#include <visualization_msgs/MarkerArray.h>

#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/range_scan.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/ros/lockstep.h"
#include "hidden_rooms/ros/markers.h"
#include "hidden_rooms/ros/parameters.h"

namespace hidden_rooms {

const common::OptionTable<ExplorerOptions>& explorerNodeOptionTable() {
  using O = ExplorerOptions;
  static const common::OptionTable<O> table{
      {"map_frame", &O::map_frame, "frame of the map", common::anyFinite(), true},
      {"base_frame", &O::base_frame, "frame of the robot", common::anyFinite(), true},
      {"control_rate", &O::control_rate, "Hz (ROS time) of cmd_vel", common::above(0)},
      {"scan_timeout", &O::scan_timeout, "seconds: an older scan stops the robot", common::above(0)},
      {"pose_timeout", &O::pose_timeout, "seconds: an older map -> base transform stops the robot",
       common::above(0)},
      {"map_timeout", &O::map_timeout, "seconds without a new map stop the robot; 0 = never", common::atLeast(0)},
      {"start_paused", &O::start_paused, "wait for true on ~resume before exploring"},
      {"background_planning", static_cast<bool O::*>(&O::background_planning),
       "plan on a thread of its own while the robot follows its path; false = in the control loop (deterministic)"},
      {"lockstep_mapper", &O::lockstep_mapper,
       "lockstep: the mapper node whose reports the steps follow (one per scan); \"\" = free-running"},
      {"odom_frame", &O::odom_frame, "lockstep: the odometry frame (map -> odom -> base)", common::anyFinite(), true},
      {"lockstep_wait", &O::lockstep_wait, "lockstep: wall seconds a step waits for the mapper's results",
       common::above(0)},
  };
  return table;
}

std::vector<common::OptionDescription> explorerParameters() {
  std::vector<common::OptionDescription> rows;
  const auto add = [&rows](const std::vector<common::OptionDescription>& more) {
    rows.insert(rows.end(), more.begin(), more.end());
  };
  add(common::describeOptions(explorerNodeOptionTable()));
  add(common::describeOptions(exploration::explorationPolicyOptionTable()));
  add(common::describeOptions(exploration::gridPlannerOptionTable()));
  add(common::describeOptions(exploration::frontierOptionTable()));
  add(common::describeOptions(exploration::pathFollowerOptionTable()));
  add(common::describeOptions(exploration::blockedPassagesOptionTable()));
  return rows;
}

ExplorerOptions readExplorerOptions(const ros::NodeHandle& nh) {
  ExplorerOptions options;
  readParameters(nh, exploration::gridPlannerOptionTable(), &options.planner);
  exploration::validate(options.planner);  // the rules between parameters
  options.frontiers.free_threshold = options.planner.free_threshold;
  options.frontiers.occupied_threshold = options.planner.occupied_threshold;
  readParameters(nh, exploration::frontierOptionTable(), &options.frontiers);
  readParameters(nh, exploration::pathFollowerOptionTable(), &options.follower);
  readParameters(nh, exploration::blockedPassagesOptionTable(), &options.passages);
  exploration::validate(options.passages);  // the rules between parameters
  readParameters(nh, exploration::explorationPolicyOptionTable(),
                 static_cast<exploration::ExplorationPolicyOptions*>(&options));
  readParameters(nh, explorerNodeOptionTable(), &options);
  if (!options.lockstep_mapper.empty()) options.background_planning = false;  // a plan's length must not matter
  return options;
}

Explorer::Explorer(ros::NodeHandle nh, const ExplorerOptions& options)
    : options_(options), policy_(options), tf_buffer_(ros::Duration(10.0)), tf_listener_(tf_buffer_) {
  // In lockstep a map waits for its step, and the mapper may publish the next one meanwhile: none may be dropped.
  map_subscriber_ = nh.subscribe("map", options.lockstep_mapper.empty() ? 1 : 2, &Explorer::onMap, this);
  scan_subscriber_ = nh.subscribe("scan", 1, &Explorer::onScan, this);
  resume_subscriber_ = ros::NodeHandle("~").subscribe("resume", 10, &Explorer::onResume, this);
  paused_ = options.start_paused;
  if (paused_) ROS_INFO("explorer: paused until true on %s", resume_subscriber_.getTopic().c_str());
  command_publisher_ = nh.advertise<geometry_msgs::Twist>("cmd_vel", 1);
  done_publisher_ = nh.advertise<std_msgs::Bool>("exploration_done", 1, true);
  markers_publisher_ = nh.advertise<visualization_msgs::MarkerArray>("exploration_markers", 1, true);
  status_publisher_ = nh.advertise<ExplorationStatus>("exploration_status", 1, true);
  std_msgs::Bool not_done;
  done_publisher_.publish(not_done);
  if (options.lockstep_mapper.empty()) {
    timer_ = nh.createTimer(ros::Duration(1.0 / options.control_rate), &Explorer::onTimer, this);
  } else {
    lockstep_mapper_ = resolvedNodeName(options.lockstep_mapper, "lockstep_mapper");
    lockstep_publisher_ = nh.advertise<hidden_rooms::LockstepAck>("lockstep", 10, true);
    lockstep_subscriber_ = nh.subscribe("lockstep", 100, &Explorer::onLockstepAck, this);
    reportLockstep(ros::Time());  // ready
    ROS_INFO("explorer: lockstep: one step per scan, after %s's report of the scan before", lockstep_mapper_.c_str());
  }
}

void Explorer::onMap(const nav_msgs::OccupancyGrid::ConstPtr& map) {
  if (map->info.width == 0 || map->info.height == 0) {
    ROS_WARN_THROTTLE(5.0, "explorer: empty map received; ignored");
    return;
  }
  if (lockstep_mapper_.empty()) {
    applyMap(map, ros::Time::now());
    return;
  }
  pending_maps_.push_back(map);
  tryLockstepStep();
}

void Explorer::applyMap(const nav_msgs::OccupancyGrid::ConstPtr& map, const ros::Time& received) {
  latest_map_ = map;
  map_received_ = received;
  try {
    policy_.setMap(fromRos(*map));
  } catch (const common::InputError& error) {
    policy_.setUnusableMap(error.what());  // reported when the policy plans with it
  }
}

void Explorer::onScan(const sensor_msgs::LaserScan::ConstPtr& scan) {
  if (!lockstep_mapper_.empty()) {
    if (scan->header.stamp == last_step_stamp_) {  // the simulator re-sent a scan already stepped
      reportLockstep(last_step_stamp_);
      return;
    }
    if (pending_scan_ && scan->header.stamp == pending_scan_->header.stamp) {  // re-sent while its step waits
      tryLockstepStep();
      return;
    }
  }
  LaserMount mount;
  try {
    mount = laserMountFromRos(tf_buffer_.lookupTransform(options_.base_frame, scan->header.frame_id, ros::Time(0)).transform);
  } catch (const tf2::TransformException& error) {
    ROS_WARN_THROTTLE(5.0, "explorer: no transform %s -> %s (%s); scan ignored", options_.base_frame.c_str(),
                      scan->header.frame_id.c_str(), error.what());
    return;
  }
  try {
    int skipped = 0;
    scan_points_ = exploration::obstaclePoints(fromRos(uprightScan(*scan, mount), mount.pose), &skipped);
    scan_remembered_ = false;
    int non_finite = 0;
    for (float range : scan->ranges) non_finite += !std::isfinite(range);
    if (non_finite > 0)
      ROS_WARN_THROTTLE(10.0, "explorer: %d of %zu ranges of a scan are not finite; skipped", non_finite,
                        scan->ranges.size());
    latest_scan_ = scan;
  } catch (const common::InputError& error) {
    ROS_WARN_THROTTLE(5.0, "explorer: bad scan: %s", error.what());
  }
  if (!lockstep_mapper_.empty()) {
    pending_scan_ = scan;
    pending_since_ = ros::WallTime::now();
    tryLockstepStep();
  }
}

void Explorer::onLockstepAck(const hidden_rooms::LockstepAck::ConstPtr& ack) {
  if (ack->node != lockstep_mapper_) return;
  mapper_heard_ = true;
  if (!mapper_acks_.empty() && ack->stamp <= mapper_acks_.back().stamp) return;  // re-sent
  mapper_acks_.push_back(*ack);
  tryLockstepStep();
}

void Explorer::tryLockstepStep() {
  if (!pending_scan_) return;
  const ros::Time stamp = pending_scan_->header.stamp;
  // The mapper's report of the scan before this one (none before the first step): it handles this one meanwhile.
  while (!mapper_acks_.empty() && mapper_acks_.front().stamp < last_step_stamp_) mapper_acks_.pop_front();
  const bool first = last_step_stamp_.isZero();
  // A message sent before its connection is made is lost (the latched report only keeps the newest).
  const bool connected = mapper_heard_ && map_subscriber_.getNumPublishers() > 0 &&
                         command_publisher_.getNumSubscribers() > 0;
  const bool reported = first ? connected
                              : !mapper_acks_.empty() && mapper_acks_.front().stamp == last_step_stamp_;
  const ros::Time map_stamp = reported && !first ? mapper_acks_.front().map_stamp : ros::Time();
  const bool map_here = map_stamp.isZero() || (latest_map_ && latest_map_->header.stamp >= map_stamp) ||
                        (!pending_maps_.empty() && pending_maps_.back()->header.stamp >= map_stamp);
  if (!(reported && map_here)) {
    if ((ros::WallTime::now() - pending_since_).toSec() < options_.lockstep_wait) return;  // a later callback retries
    // Not throttled: a throttle counts ROS time, which starts at 0 here, and each of these costs ~lockstep_wait.
    ROS_WARN("explorer: lockstep: %s %s for the scan at %.2f s after %.1f s (wall); stepping with what is here",
             first ? "not connected to" : reported ? "no map from" : "no report from", lockstep_mapper_.c_str(),
             last_step_stamp_.toSec(), options_.lockstep_wait);
  }
  // The newest map up to the reported one (maps the mapper published later wait for their step).
  const auto due = [&](const nav_msgs::OccupancyGrid& map) {
    return map_stamp.isZero() ? !reported : map.header.stamp <= map_stamp;
  };
  while (!pending_maps_.empty() && due(*pending_maps_.front())) {
    applyMap(pending_maps_.front(), stamp);
    pending_maps_.pop_front();
  }
  map_to_odom_.reset();
  if (reported && !first && !mapper_acks_.front().map_to_odom.header.stamp.isZero())
    map_to_odom_ = fromRos(mapper_acks_.front().map_to_odom.transform);
  pending_scan_.reset();
  controlStep(stamp);
  last_step_stamp_ = stamp;
  reportLockstep(stamp);
}

void Explorer::reportLockstep(const ros::Time& stamp) {
  hidden_rooms::LockstepAck ack = lockstepReport(stamp);
  ack.commands = commands_published_;
  ack.finished = policy_.done();
  lockstep_publisher_.publish(ack);
}

void Explorer::onResume(const std_msgs::Bool::ConstPtr& resume) {
  if (paused_ == !resume->data) return;
  paused_ = !resume->data;
  if (paused_)
    ROS_INFO("explorer: paused (true on %s resumes)", resume_subscriber_.getTopic().c_str());
  else
    ROS_INFO("explorer: resumed");
  publishStatus(ros::Time::now());
}

bool Explorer::robotPose(const ros::Time& now, common::Pose2* pose) {
  try {
    if (lockstep_mapper_.empty()) {
      const geometry_msgs::TransformStamped transform =
          tf_buffer_.lookupTransform(options_.map_frame, options_.base_frame, ros::Time(0));
      if ((now - transform.header.stamp).toSec() > options_.pose_timeout) {
        ROS_WARN_THROTTLE(5.0, "explorer: %s -> %s is %.1f s old; stopped", options_.map_frame.c_str(),
                          options_.base_frame.c_str(), (now - transform.header.stamp).toSec());
        return false;
      }
      *pose = fromRos(transform.transform);
      return true;
    }
    // Lockstep: map -> odom as the mapper reported it, odom -> base at the scan's stamp (tf's thread brings it; the
    // simulator sends it again while it waits, should this node's tf connection have come late).
    if (!map_to_odom_) throw tf2::LookupException("the mapper has reported no map -> odom yet");
    waitOnWallClock([&] { return tf_buffer_.canTransform(options_.odom_frame, options_.base_frame, now); },
                    options_.lockstep_wait);
    *pose = common::composePoses(
        *map_to_odom_, fromRos(tf_buffer_.lookupTransform(options_.odom_frame, options_.base_frame, now).transform));
    return true;
  } catch (const tf2::TransformException& error) {
    ROS_WARN_THROTTLE(5.0, "explorer: waiting for %s -> %s: %s", options_.map_frame.c_str(), options_.base_frame.c_str(),
                      error.what());
    return false;
  }
}

void Explorer::holdRobot(const ros::Time& now) {
  policy_.hold(now.toSec());
  publishCommand(common::VelocityCommand());
}

void Explorer::onTimer(const ros::TimerEvent&) { controlStep(ros::Time::now()); }

void Explorer::controlStep(const ros::Time& now) {
  if (!latest_map_) {
    ROS_INFO_THROTTLE(10.0, "explorer: waiting for a map on %s", map_subscriber_.getTopic().c_str());
    return;
  }
  if (paused_) {
    holdRobot(now);
    return;
  }
  common::Pose2 pose;
  if (!robotPose(now, &pose)) {
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
    if (!policy_.done())
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

  // The latest scan is remembered with the robot's current pose.
  if (!scan_remembered_) {
    policy_.addScan(scan_points_, pose, now.toSec());
    scan_remembered_ = true;
  }
  const exploration::ExplorationStep step = policy_.update(pose, now.toSec());
  report(step, now);
  if (step.planned) {
    publishMarkers(now);
    publishStatus(now);
  }
  publishCommand(step.command);
}

void Explorer::report(const exploration::ExplorationStep& step, const ros::Time& now) {
  for (const exploration::ExplorationEvent& event : step.events) {
    const double x = event.position.x(), y = event.position.y();
    switch (event.type) {
      case exploration::ExplorationEventType::kMapUnusable:
        ROS_WARN_THROTTLE(5.0, "explorer: unusable map: %s", event.message.c_str());
        break;
      case exploration::ExplorationEventType::kStartBlocked:
        ROS_WARN_THROTTLE(5.0, "explorer: robot at (%.2f, %.2f) is not within %.2f m of a traversable map cell; "
                          "waiting for the map (or a recovery) to free it", x, y,
                          options_.planner.start_escape_radius);
        break;
      case exploration::ExplorationEventType::kGoalChosen:
        ++goals_chosen_;
        ROS_DEBUG("explorer: %sgoal (%.2f, %.2f), path %.2f m, cost %.2f",
                  event.look ? "look " : "", x, y, event.path_length, event.cost);
        break;
      case exploration::ExplorationEventType::kGoalReached:
        ++goals_reached_;
        break;
      case exploration::ExplorationEventType::kGoalFailedStuck:
        ++goals_failed_;
        ROS_WARN("explorer: goal (%.2f, %.2f) failed: the robot did not move in %d recoveries (stuck?); "
                 "blacklisted until no other goal is left", x, y, event.recoveries);
        break;
      case exploration::ExplorationEventType::kGoalFailed:
        ++goals_failed_;
        ROS_WARN("explorer: goal (%.2f, %.2f) not reached (%d recoveries, no progress); blacklisted (%s)", x, y,
                 event.recoveries,
                 event.retry_later ? "a second try when no other goal is left" : "it failed there on its second try");
        break;
      case exploration::ExplorationEventType::kPassageBlocked:
        ROS_WARN("explorer: %d goals failed from (%.2f, %.2f) in one direction: the path ahead is blocked for the "
                 "planner", options_.passages.failures, x, y);
        break;
      case exploration::ExplorationEventType::kPassageOpened:
        ROS_WARN("explorer: goals failed from (%.2f, %.2f) in different directions: the robot is stuck there, not "
                 "a passage ahead; opened again", x, y);
        break;
      case exploration::ExplorationEventType::kStuckReleased:
        ROS_WARN("explorer: no other goal; %zu goals failed while the robot could not move: trying them again",
                 event.count);
        break;
      case exploration::ExplorationEventType::kPassagesReleased:
        ROS_WARN("explorer: no other goal; opening the blocked passages again (%zu points, once)", event.count);
        break;
      case exploration::ExplorationEventType::kFailedReleased:
        ROS_WARN("explorer: no other goal; %zu failed goals get their second try", event.count);
        break;
      case exploration::ExplorationEventType::kTrailOpened:
        ROS_WARN("explorer: no other goal; the robot's last %.1f m of path are passable however narrow the map "
                 "draws them (the way in is a way out)", event.path_length);
        break;
      case exploration::ExplorationEventType::kNoGoal:
        ROS_INFO("explorer: no reachable frontier (%zu frontiers, %zu blacklisted places); checking again",
                 event.count, event.blacklisted);
        break;
      case exploration::ExplorationEventType::kDone:
      case exploration::ExplorationEventType::kResumed: {
        const bool done = event.type == exploration::ExplorationEventType::kDone;
        std_msgs::Bool message;
        message.data = done;
        done_publisher_.publish(message);
        if (done)
          ROS_INFO("explorer: exploration done: no reachable frontier left (t = %.1f s, %.1f m driven, %d goals, "
                   "%zu blacklisted places)", now.toSec(), distance_driven_, goals_chosen_, event.blacklisted);
        else
          ROS_INFO("explorer: a reachable frontier appeared; exploring again");
        break;
      }
    }
  }
}

void Explorer::publishCommand(const common::VelocityCommand& command) {
  const bool stop = command.linear == 0.0 && command.angular == 0.0;
  if (stop && stopped_) return;  // one stop is enough (the simulator's watchdog also stops a silent robot)
  stopped_ = stop;
  command_publisher_.publish(toRos(command));
  ++commands_published_;
}

void Explorer::publishStatus(const ros::Time& now) {
  ExplorationStatus status;
  status.stamp = now;
  status.paused = paused_;
  status.done = policy_.done();
  status.goals_chosen = static_cast<uint32_t>(goals_chosen_);
  status.goals_reached = static_cast<uint32_t>(goals_reached_);
  status.goals_failed = static_cast<uint32_t>(goals_failed_);
  status.frontiers = static_cast<uint32_t>(policy_.frontiers().frontiers.size());
  status.blacklisted = static_cast<uint32_t>(policy_.blacklist().points.size());
  status.distance_driven = distance_driven_;
  status_publisher_.publish(status);
}

void Explorer::publishMarkers(const ros::Time& now) {
  if (markers_publisher_.getNumSubscribers() == 0) return;
  ExplorationView view;
  view.frontiers = &policy_.frontiers();
  if (policy_.goal()) {
    view.goal_frontier_label = policy_.goal()->frontier_label;
    view.goal = policy_.goal()->position;
    view.path = policy_.follower().path();
  }
  view.blacklist = policy_.blacklist().points;
  view.blocked_passages = policy_.passages().blockedPoints();
  view.blocked_passage_radius = options_.passages.radius;
  markers_publisher_.publish(toMarkers(policy_.planner().map(), view, options_.map_frame, now));
}

}  // namespace hidden_rooms
