#pragma once

#include <string>
#include <vector>

#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/options.h"
#include "hidden_rooms/common/range_scan.h"
#include "hidden_rooms/common/velocity_command.h"

namespace hidden_rooms::exploration {

struct PathFollowerOptions {
  double max_linear_velocity = 0.5;    // m/s
  double max_angular_velocity = 0.8;   // rad/s
  double lookahead = 0.6;              // metres: the pursued point is this far from the robot along the path
  double goal_tolerance = 0.3;         // metres: the goal is reached within this distance of the path's end
  double rotate_in_place_angle = 0.8;  // rad: a larger heading error to the pursued point turns in place
  double heading_gain = 2.0;           // rad/s per rad of heading error when turning in place
  // Robot box (metres) centred on base_link, and the free margin kept beside it when moving: side_margin, or 70%
  // of the present gap (footprint to nearest laser point) when something is already closer, so the robot may go
  // on through a passage as tight as where it stands but not into a tighter one.
  double footprint_length = 0.626;
  double footprint_width = 0.505;
  double side_margin = 0.05;
  // Metres: with less free space ahead of the front the robot does not go on. When what stops it lies in the lane's
  // side margins only (a wall's end beside its way), it creeps straight on at creep_velocity while the footprint's
  // own width has more than this free ahead; else it turns towards the path.
  double stop_distance = 0.12;
  double deceleration = 0.8;           // m/s^2: speed ahead is capped at sqrt(2 * deceleration * free space)
  // Turning in place with laser points inside the circle the footprint sweeps (plus side_margin) on its front or
  // rear half only, the robot also moves away from them at this speed (m/s); with points on both halves (a
  // doorway) it first creeps straight ahead; either only when the lane that way is free.
  double creep_velocity = 0.1;
  // Seconds of the commanded arc checked against the laser points (footprint + the moving margin above, up to the
  // path's end); when it would hit, the nearest turn rate with a clear arc is taken (then at half the speed); when
  // there is none the command stays (the front speed cap stops the robot). 0 = no check.
  double arc_horizon = 1.0;
  // In a doorway (laser points beside both sides of the footprint, within doorway_distance of them) the turn
  // rate is capped at doorway_angular_velocity (rad/s): the rear, which the laser does not see, would swing into
  // the frame.
  double doorway_distance = 0.3;
  double doorway_angular_velocity = 0.15;
  // A narrow gap on the way to the pursued point (laser points on both sides of that way, at least the footprint's
  // width apart and at most the lane's plus gap_slack metres each side): the robot aims at the middle between
  // them, where the map's gap may lie a few centimetres off the real one. 0 = off.
  double gap_slack = 0.1;
  // Recovery: not moving (less than stall_distance and stall_angle) for stall_timeout seconds while it should
  // triggers a recovery: back off for backoff_time at backoff_velocity (when the laser sees room behind), then
  // turn in place towards the freer side for recovery_rotate_time. When the last recovery (of any goal) did not
  // move the robot and it is still where that one started, the turn goes the other way: a robot wedged
  // diagonally in a passage is freed only by the turn that straightens it.
  double stall_timeout = 3.0;
  double stall_distance = 0.05;
  double stall_angle = 0.15;
  double backoff_time = 1.5;
  double backoff_velocity = 0.15;
  double recovery_rotate_time = 1.5;
  // Failure: the remaining path has not shrunk by progress_distance within progress_timeout seconds, or
  // max_recoveries recoveries did not help.
  double progress_timeout = 20.0;
  double progress_distance = 0.3;
  int max_recoveries = 3;
};

// Throws InputError("explorer options", ...) naming a non-finite, negative or inconsistent option.
void validate(const PathFollowerOptions& options);
// The explorer's parameters of the follower (docs/ros_api.md).
const common::OptionTable<PathFollowerOptions>& pathFollowerOptionTable();

enum class FollowerState { kIdle, kFollowing, kBackingOff, kRecoveryRotating, kGoalReached, kFailed };
const char* toString(FollowerState state);

struct FollowerStep {
  common::VelocityCommand command;
  FollowerState state = FollowerState::kIdle;
  double front_clearance = 0.0;  // metres of free space ahead of the robot's front in its lane
};

// The returns of a scan as points in base_link (through scan.sensor_pose); beams without a valid return
// (non-finite, at or below range_min, at or beyond range_max) are skipped and counted in `skipped` when given.
std::vector<common::Point2> obstaclePoints(const common::RangeScan& scan, int* skipped = nullptr);

// Laser points of the last few scans, kept in the map frame, so that what the laser no longer sees (beside and
// behind the robot's rear, outside a 270 degree field of view) still counts for a little while.
class ObstacleMemory {
 public:
  explicit ObstacleMemory(double duration = 1.5) : duration_(duration) {}
  // Adds the points (base_link) of a scan taken with the robot at `pose` (map frame) at `time` (seconds); scans
  // older than `duration` before it are forgotten.
  void add(const std::vector<common::Point2>& points, const common::Pose2& pose, double time);
  // Every remembered point in the base_link of a robot at `pose`.
  std::vector<common::Point2> points(const common::Pose2& pose) const;
  void clear() { scans_.clear(); }

 private:
  struct Scan {
    double time = 0.0;
    std::vector<common::Point2> points;  // map frame
  };
  double duration_;
  std::vector<Scan> scans_;
};

// Free space (metres) ahead of the robot's front edge within its lane (footprint width plus the moving margin,
// side_margin or 70% of the present gap, on both sides), from obstacle points in base_link; +infinity when the
// lane is empty. Points inside the footprint's front half count as 0; points beside it (in the side margins) do
// not count: driving straight does not come closer.
double frontClearance(const std::vector<common::Point2>& obstacles, const PathFollowerOptions& options);
// The same behind the rear edge (the laser may not see there: then +infinity).
double rearClearance(const std::vector<common::Point2>& obstacles, const PathFollowerOptions& options);

// Pure pursuit along a path with a laser speed limit and a recovery state machine. Times are seconds of any
// monotonic clock (the node uses ROS time).
class PathFollower {
 public:
  explicit PathFollower(const PathFollowerOptions& options = PathFollowerOptions());

  // Follows `path` (map frame) from `time` on; resets progress and recoveries. An empty path stops (kIdle).
  void setPath(const std::vector<common::Point2>& path, double time);
  // Keeps following the new path of the same goal (a replan): progress and recovery counters stay.
  void updatePath(const std::vector<common::Point2>& path);
  void stop();
  // The robot is held still from outside at `time` (the node stops it while its map, pose or scan is stale).
  // The held time, up to the next update, counts neither for the progress timeout nor for the stall watch, and a
  // recovery manoeuvre in progress goes on for the rest of its duration.
  void hold(double time);

  // The command for the robot at `pose` (map frame) with obstacle points (metres, base_link). kGoalReached and
  // kFailed stay (with zero commands) until the next setPath.
  FollowerStep update(const common::Pose2& pose, const std::vector<common::Point2>& obstacles, double time);

  FollowerState state() const { return state_; }
  int recoveries() const { return recoveries_; }
  // Recoveries since setPath after which the robot had neither moved stall_distance nor turned stall_angle
  // from where the recovery started: its commands produced no motion (the robot is pinned, or its drive is off).
  int recoveriesWithoutMotion() const { return recoveries_without_motion_; }
  const std::vector<common::Point2>& path() const { return path_; }
  const PathFollowerOptions& options() const { return options_; }

 private:
  FollowerStep follow(const common::Pose2& pose, const std::vector<common::Point2>& obstacles, double clearance);
  // True when the footprint (plus the moving margin) moving forward on the arc (linear > 0, angular) from
  // base_link meets an obstacle point within arc_horizon seconds and max_distance metres.
  bool arcHitsObstacle(const std::vector<common::Point2>& obstacles, double linear, double angular,
                       double max_distance) const;
  // Laser points beside both sides of the footprint within doorway_distance.
  bool inDoorway(const std::vector<common::Point2>& obstacles) const;
  // `local` (the pursued point, robot frame) moved across the way to it into the middle of a narrow gap.
  common::Point2 centredInGap(const std::vector<common::Point2>& obstacles, const common::Point2& local) const;
  // Turning in place at `angular`, with laser points inside the circle the footprint sweeps (+ side_margin): on
  // the front half only, also backing away at creep_velocity (rear lane free); on the rear half only, creeping
  // forward (lane ahead free); on both halves, creeping straight ahead without turning (lane ahead free).
  common::VelocityCommand turnInPlace(double angular, const std::vector<common::Point2>& obstacles,
                                      double front_clearance) const;
  double remainingLength(const common::Pose2& pose);
  // Whether `pose` is within stall_distance and stall_angle of `since` (the robot has not moved).
  bool withinStall(const common::Pose2& pose, const common::Pose2& since) const;

  PathFollowerOptions options_;
  std::vector<common::Point2> path_;
  FollowerState state_ = FollowerState::kIdle;
  size_t closest_index_ = 0;
  // Progress: best remaining length and when it last improved by progress_distance.
  double best_remaining_ = 0.0;
  double progress_time_ = 0.0;
  // Stall watch: where and when the robot last moved.
  common::Pose2 anchor_pose_;
  double anchor_time_ = 0.0;
  bool anchor_set_ = false;
  double recovery_until_ = 0.0;
  double recovery_turn_sign_ = 1.0;
  common::Pose2 recovery_start_pose_;
  int recoveries_ = 0;
  int recoveries_without_motion_ = 0;
  // Kept across goals: whether the last recovery moved the robot (else the next one turns the other way).
  bool last_recovery_moved_ = true;
  // Held from outside since held_since_ (hold()).
  bool held_ = false;
  double held_since_ = 0.0;
};

}  // namespace hidden_rooms::exploration
