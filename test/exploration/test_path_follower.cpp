// The path follower: pure pursuit outputs, the laser stop in front of an obstacle, turning in place, the goal,
// recovery after a stall and failure when nothing helps.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/exploration/path_follower.h"

namespace hidden_rooms::exploration {
namespace {

// A straight path along +x from (0, 0) to (length, 0), points every 0.05 m.
std::vector<common::Point2> straightPath(double length) {
  std::vector<common::Point2> path;
  for (double x = 0.0; x <= length + 1e-9; x += 0.05) path.emplace_back(x, 0.0);
  return path;
}

// A wall across the lane `distance` metres ahead of the robot's centre (base_link points).
std::vector<common::Point2> wallAhead(double distance) {
  std::vector<common::Point2> points;
  for (double y = -1.0; y <= 1.0; y += 0.02) points.emplace_back(distance, y);
  return points;
}

TEST(PathFollower, DrivesStraightAlongAFreePath) {
  PathFollower follower;
  follower.setPath(straightPath(5.0), 0.0);
  const FollowerStep step = follower.update(common::Pose2{0.0, 0.0, 0.0}, {}, 0.1);
  EXPECT_EQ(step.state, FollowerState::kFollowing);
  EXPECT_NEAR(step.command.linear, follower.options().max_linear_velocity, 1e-9);
  EXPECT_NEAR(step.command.angular, 0.0, 1e-9);
  EXPECT_TRUE(std::isinf(step.front_clearance));
}

TEST(PathFollower, SteersTowardsAPathBesideIt) {
  PathFollower follower;
  follower.setPath(straightPath(5.0), 0.0);
  // The robot 0.3 m right of the path (y = -0.3), facing along it: pure pursuit turns left (positive).
  const FollowerStep step = follower.update(common::Pose2{1.0, -0.3, 0.0}, {}, 0.1);
  EXPECT_GT(step.command.linear, 0.0);
  EXPECT_GT(step.command.angular, 0.0);
  EXPECT_LE(step.command.angular, follower.options().max_angular_velocity);
}

TEST(PathFollower, TurnsInPlaceWhenThePathIsBehind) {
  PathFollower follower;
  follower.setPath(straightPath(5.0), 0.0);
  const FollowerStep step = follower.update(common::Pose2{0.0, 0.0, M_PI}, {}, 0.1);
  EXPECT_EQ(step.command.linear, 0.0);
  EXPECT_NE(step.command.angular, 0.0);
}

TEST(PathFollower, TurningInPlaceMovesAwayFromAWallTheCornersWouldHit) {
  PathFollowerOptions options;
  PathFollower follower(options);
  follower.setPath(straightPath(5.0), 0.0);
  // The path is behind (turn in place); a wall 0.08 m from the left side (outside the lane, inside the circle
  // the turning footprint sweeps), along the front half.
  std::vector<common::Point2> wall;
  for (double x = 0.02; x <= 0.3; x += 0.02) wall.emplace_back(x, 0.5 * options.footprint_width + 0.08);
  FollowerStep step = follower.update(common::Pose2{0.0, 0.0, M_PI}, wall, 0.1);
  EXPECT_NE(step.command.angular, 0.0);
  EXPECT_NEAR(step.command.linear, -options.creep_velocity, 1e-9);  // backs away from the front corner's wall
  // The same wall along the rear half: creeps forward while turning.
  for (common::Point2& point : wall) point.x() = -point.x();
  step = follower.update(common::Pose2{0.0, 0.0, M_PI}, wall, 0.2);
  EXPECT_NEAR(step.command.linear, options.creep_velocity, 1e-9);
  EXPECT_NE(step.command.angular, 0.0);
  // Walls along both halves (a doorway): leaves straight ahead first.
  std::vector<common::Point2> both = wall;
  for (const common::Point2& point : wall) both.emplace_back(-point.x(), point.y());
  step = follower.update(common::Pose2{0.0, 0.0, M_PI}, both, 0.3);
  EXPECT_NEAR(step.command.linear, options.creep_velocity, 1e-9);
  EXPECT_EQ(step.command.angular, 0.0);
  // Nothing near: turns on the spot.
  step = follower.update(common::Pose2{0.0, 0.0, M_PI}, {}, 0.4);
  EXPECT_EQ(step.command.linear, 0.0);
  EXPECT_NE(step.command.angular, 0.0);
}

TEST(PathFollower, SteersAwayFromADoorFrameTheArcWouldTouch) {
  PathFollowerOptions options;
  PathFollower follower(options);
  follower.setPath(straightPath(5.0), 0.0);
  // A post 0.5 m ahead, 0.03 m beside the left side of the footprint's straight sweep (within side_margin; far
  // enough ahead for no speed cap): the robot turns right (negative) and keeps going.
  const std::vector<common::Point2> post{{0.313 + 0.5, 0.5 * options.footprint_width + 0.03}};
  const FollowerStep step = follower.update(common::Pose2{}, post, 0.1);
  EXPECT_GT(step.command.linear, 0.0);
  EXPECT_LT(step.command.angular, 0.0);
  // Without the check it drives straight on.
  options.arc_horizon = 0.0;
  PathFollower unchecked(options);
  unchecked.setPath(straightPath(5.0), 0.0);
  EXPECT_NEAR(unchecked.update(common::Pose2{}, post, 0.1).command.angular, 0.0, 1e-9);
}

TEST(PathFollower, TurnsSlowlyInADoorway) {
  PathFollowerOptions options;
  PathFollower follower(options);
  follower.setPath(straightPath(5.0), 0.0);
  // The robot 0.3 m right of the path, facing along it: pure pursuit turns left fast in the open ...
  const double open_turn = follower.update(common::Pose2{1.0, -0.3, 0.0}, {}, 0.1).command.angular;
  EXPECT_GT(open_turn, options.doorway_angular_velocity);
  // ... but between door frames 0.15 m beside both sides only at the doorway's rate.
  const double side = 0.5 * options.footprint_width + 0.15;
  const std::vector<common::Point2> frames{{0.0, side}, {-0.2, side}, {0.0, -side}, {-0.2, -side}};
  const FollowerStep step = follower.update(common::Pose2{1.0, -0.3, 0.0}, frames, 0.2);
  EXPECT_GT(step.command.linear, 0.0);
  EXPECT_NEAR(step.command.angular, options.doorway_angular_velocity, 1e-9);
}

// Jambs of a gap `width` wide whose middle lies `offset` metres left of the path, `distance` ahead (robot frame).
std::vector<common::Point2> gapAhead(double distance, double width, double offset) {
  std::vector<common::Point2> points;
  for (double y = 0.5 * width; y <= 1.5; y += 0.02) {
    points.emplace_back(distance, offset + y);
    points.emplace_back(distance, offset - y);
  }
  return points;
}

TEST(PathFollower, AimsAtTheMiddleOfANarrowGap) {
  PathFollowerOptions options;
  options.arc_horizon = 0.0;  // the pursuit alone
  PathFollower follower(options);
  follower.setPath(straightPath(5.0), 0.0);
  // A 0.70 m gap (lane 0.605 m) 0.5 m ahead, its middle 0.06 m left of the path: the robot turns left towards it.
  EXPECT_GT(follower.update(common::Pose2{}, gapAhead(0.5, 0.70, 0.06), 0.1).command.angular, 0.05);
  EXPECT_LT(follower.update(common::Pose2{}, gapAhead(0.5, 0.70, -0.06), 0.2).command.angular, -0.05);
  // A wide door (1 m) or the option off: the path is followed as it is.
  EXPECT_NEAR(follower.update(common::Pose2{}, gapAhead(0.5, 1.0, 0.06), 0.3).command.angular, 0.0, 1e-9);
  options.gap_slack = 0.0;
  PathFollower plain(options);
  plain.setPath(straightPath(5.0), 0.0);
  EXPECT_NEAR(plain.update(common::Pose2{}, gapAhead(0.5, 0.70, 0.06), 0.1).command.angular, 0.0, 1e-9);
  // A gap narrower than the robot is no way through: not aimed at.
  EXPECT_NEAR(follower.update(common::Pose2{}, gapAhead(0.5, 0.45, 0.06), 0.4).command.angular, 0.0, 1e-9);
}

TEST(PathFollower, SlowsDownAndStopsInFrontOfAnObstacle) {
  PathFollowerOptions options;
  PathFollower follower(options);
  follower.setPath(straightPath(5.0), 0.0);
  const double half_length = 0.5 * options.footprint_length;
  // Free space 0.2 m ahead of the front: capped at sqrt(2 a (0.2 - stop_distance)).
  FollowerStep step = follower.update(common::Pose2{}, wallAhead(half_length + 0.2), 0.1);
  EXPECT_NEAR(step.front_clearance, 0.2, 1e-9);
  EXPECT_NEAR(step.command.linear, std::sqrt(2.0 * options.deceleration * (0.2 - options.stop_distance)), 1e-9);
  // Closer than stop_distance: no forward motion.
  step = follower.update(common::Pose2{}, wallAhead(half_length + 0.5 * options.stop_distance), 0.2);
  EXPECT_EQ(step.command.linear, 0.0);
  EXPECT_EQ(step.state, FollowerState::kFollowing);
  // Walls beside the lane (a door frame 0.2 m from each side) do not slow it down.
  std::vector<common::Point2> door{{0.5, 0.5 * options.footprint_width + 0.2},
                                   {0.5, -0.5 * options.footprint_width - 0.2}};
  step = follower.update(common::Pose2{}, door, 0.3);
  EXPECT_NEAR(step.command.linear, options.max_linear_velocity, 1e-9);
}

TEST(PathFollower, CreepsStraightPastAWallsEndInTheLanesMargin) {
  PathFollowerOptions options;
  const double half_length = 0.5 * options.footprint_length, half_width = 0.5 * options.footprint_width;
  // A wall's end just ahead of the front, in the right side margin of the lane only (0.03 m beside the footprint's
  // width), and the path bending right round it: the robot neither stops nor turns into it, it creeps straight on.
  const std::vector<common::Point2> wall_end{{half_length + 0.05, -half_width - 0.03},
                                             {half_length + 0.10, -half_width - 0.03},
                                             {half_length + 0.15, -half_width - 0.03}};
  std::vector<common::Point2> bending;  // straight for 0.3 m, then 30 degrees to the right
  for (double x = 0.0; x < 0.3; x += 0.05) bending.emplace_back(x, 0.0);
  for (double t = 0.0; t <= 3.0; t += 0.05) bending.emplace_back(0.3 + t * std::cos(M_PI / 6), -t * std::sin(M_PI / 6));
  PathFollower follower(options);
  follower.setPath(bending, 0.0);
  FollowerStep step = follower.update(common::Pose2{}, wall_end, 0.1);
  EXPECT_NEAR(step.front_clearance, 0.05, 1e-9);
  EXPECT_NEAR(step.command.linear, options.creep_velocity, 1e-9);
  EXPECT_EQ(step.command.angular, 0.0);
  // Within the footprint's width less than stop_distance ahead as well: it stops and turns towards the path.
  std::vector<common::Point2> blocked = wall_end;
  blocked.emplace_back(half_length + 0.5 * options.stop_distance, 0.0);
  step = follower.update(common::Pose2{}, blocked, 0.2);
  EXPECT_EQ(step.command.linear, 0.0);
  EXPECT_LT(step.command.angular, 0.0);
  // With creep_velocity 0 it does not creep: it turns towards the path.
  options.creep_velocity = 0.0;
  PathFollower still(options);
  still.setPath(bending, 0.0);
  step = still.update(common::Pose2{}, wall_end, 0.1);
  EXPECT_EQ(step.command.linear, 0.0);
  EXPECT_LT(step.command.angular, 0.0);
}

TEST(PathFollower, IgnoresNonFiniteObstaclePoints) {
  PathFollower follower;
  follower.setPath(straightPath(5.0), 0.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const FollowerStep step = follower.update(common::Pose2{}, {common::Point2(nan, 0.0), common::Point2(0.5, nan)}, 0.1);
  EXPECT_TRUE(std::isinf(step.front_clearance));
  EXPECT_GT(step.command.linear, 0.0);
}

TEST(PathFollower, ReachesTheGoal) {
  PathFollower follower;
  follower.setPath(straightPath(2.0), 0.0);
  EXPECT_EQ(follower.update(common::Pose2{1.0, 0.0, 0.0}, {}, 1.0).state, FollowerState::kFollowing);
  const FollowerStep step = follower.update(common::Pose2{1.8, 0.05, 0.0}, {}, 2.0);
  EXPECT_EQ(step.state, FollowerState::kGoalReached);
  EXPECT_EQ(step.command.linear, 0.0);
  EXPECT_EQ(follower.update(common::Pose2{1.8, 0.05, 0.0}, {}, 2.1).state, FollowerState::kGoalReached);  // stays
  follower.setPath({}, 3.0);
  EXPECT_EQ(follower.state(), FollowerState::kIdle);
}

TEST(PathFollower, StallTriggersRecoveryAndTooManyFail) {
  PathFollowerOptions options;
  options.max_recoveries = 2;
  PathFollower follower(options);
  follower.setPath(straightPath(5.0), 0.0);
  // Blocked: a wall just ahead, and the robot never moves.
  const std::vector<common::Point2> wall = wallAhead(0.5 * options.footprint_length + 0.05);
  const common::Pose2 stuck{0.5, 0.0, 0.0};
  double time = 0.0;
  FollowerStep step;
  for (; time < options.stall_timeout - 0.05; time += 0.1) {
    step = follower.update(stuck, wall, time);
    EXPECT_EQ(step.state, FollowerState::kFollowing);
    EXPECT_EQ(step.command.linear, 0.0);
  }
  for (; step.state == FollowerState::kFollowing && time < options.stall_timeout + 1.0; time += 0.1)
    step = follower.update(stuck, wall, time);
  ASSERT_EQ(step.state, FollowerState::kBackingOff);
  EXPECT_EQ(follower.recoveries(), 1);
  EXPECT_LT(step.command.linear, 0.0);  // nothing seen behind: backs off
  // Backing off, then turning in place, then following again.
  bool rotated = false;
  for (double until = time + options.backoff_time + options.recovery_rotate_time + 0.3; time < until; time += 0.1) {
    step = follower.update(stuck, wall, time);
    if (step.state == FollowerState::kRecoveryRotating) {
      rotated = true;
      EXPECT_EQ(step.command.linear, 0.0);
      EXPECT_NEAR(std::abs(step.command.angular), options.max_angular_velocity, 1e-9);
    }
  }
  EXPECT_TRUE(rotated);
  EXPECT_EQ(step.state, FollowerState::kFollowing);
  // Still stuck: a second recovery, then failure.
  for (; follower.recoveries() < 2 && time < 60.0; time += 0.1) follower.update(stuck, wall, time);
  EXPECT_EQ(follower.recoveries(), 2);
  for (; step.state != FollowerState::kFailed && time < 60.0; time += 0.1) step = follower.update(stuck, wall, time);
  EXPECT_EQ(step.state, FollowerState::kFailed);
  EXPECT_EQ(step.command.linear, 0.0);
  EXPECT_EQ(step.command.angular, 0.0);
}

TEST(PathFollower, FailsWithoutProgressEvenWhenMoving) {
  PathFollowerOptions options;
  options.progress_timeout = 5.0;
  PathFollower follower(options);
  follower.setPath(straightPath(5.0), 0.0);
  // The robot wobbles on the spot (so the stall watch sees motion) but never gets closer to the goal.
  FollowerStep step;
  double time = 0.0;
  for (int i = 0; step.state != FollowerState::kFailed && time < 10.0; ++i, time += 0.1)
    step = follower.update(common::Pose2{0.0, 0.0, i % 2 == 0 ? 0.3 : -0.3}, {}, time);
  EXPECT_EQ(step.state, FollowerState::kFailed);
  EXPECT_NEAR(time, options.progress_timeout, 0.25);
}

TEST(PathFollower, HeldTimeCountsNeitherForProgressNorForTheStallWatch) {
  PathFollowerOptions options;  // progress_timeout 20 s, stall_timeout 3 s
  PathFollower held(options), not_held(options);
  for (PathFollower* follower : {&held, &not_held}) {
    follower->setPath(straightPath(5.0), 0.0);
    follower->update(common::Pose2{0.0, 0.0, 0.0}, {}, 0.1);
    follower->update(common::Pose2{0.4, 0.0, 0.0}, {}, 1.0);  // progress
  }
  // Stopped from outside for 30 s (no map): the node holds the follower on every tick.
  const common::Pose2 still{0.4, 0.0, 0.0};
  for (double time = 1.1; time < 31.0; time += 0.1) held.hold(time);
  FollowerStep step = held.update(still, {}, 31.0);
  EXPECT_EQ(step.state, FollowerState::kFollowing);
  EXPECT_GT(step.command.linear, 0.0);
  EXPECT_EQ(held.recoveries(), 0);
  // Without the hold the same pause fails the goal at once.
  EXPECT_EQ(not_held.update(still, {}, 31.0).state, FollowerState::kFailed);
  // The stall watch starts afresh: a recovery only after stall_timeout more seconds without motion.
  double time = 31.1;
  for (; time < 31.0 + options.stall_timeout - 0.05; time += 0.1) {
    step = held.update(still, {}, time);
    EXPECT_EQ(step.state, FollowerState::kFollowing) << time;
  }
  for (; step.state == FollowerState::kFollowing && time < 31.0 + options.stall_timeout + 1.0; time += 0.1)
    step = held.update(still, {}, time);
  EXPECT_EQ(step.state, FollowerState::kBackingOff);
  EXPECT_EQ(held.recoveries(), 1);
}

TEST(PathFollower, AHeldRecoveryGoesOnForTheRestOfItsTime) {
  PathFollowerOptions options;  // backoff_time 1.5 s
  PathFollower follower(options);
  follower.setPath(straightPath(5.0), 0.0);
  const std::vector<common::Point2> wall = wallAhead(0.5 * options.footprint_length + 0.05);
  const common::Pose2 stuck{0.5, 0.0, 0.0};
  FollowerStep step;
  double time = 0.0;
  for (; step.state != FollowerState::kBackingOff && time < 10.0; time += 0.1) step = follower.update(stuck, wall, time);
  ASSERT_EQ(step.state, FollowerState::kBackingOff);
  const double backoff_start = time - 0.1;
  step = follower.update(stuck, wall, backoff_start + 0.5);
  EXPECT_EQ(step.state, FollowerState::kBackingOff);
  // Held for 10 s half-way through: 1 s of backing off is left afterwards.
  follower.hold(backoff_start + 0.5);
  step = follower.update(stuck, wall, backoff_start + 10.5);
  EXPECT_EQ(step.state, FollowerState::kBackingOff);
  EXPECT_LT(step.command.linear, 0.0);
  EXPECT_EQ(follower.update(stuck, wall, backoff_start + 11.3).state, FollowerState::kBackingOff);
  EXPECT_EQ(follower.update(stuck, wall, backoff_start + 11.6).state, FollowerState::kRecoveryRotating);
}

TEST(PathFollower, CountsTheRecoveriesThatMovedNothing) {
  PathFollowerOptions options;
  options.max_recoveries = 2;
  const std::vector<common::Point2> wall = wallAhead(0.5 * options.footprint_length + 0.05);
  {  // Pinned: no command moves the robot; both recoveries moved nothing.
    PathFollower follower(options);
    follower.setPath(straightPath(5.0), 0.0);
    FollowerStep step;
    for (double time = 0.0; step.state != FollowerState::kFailed && time < 60.0; time += 0.1)
      step = follower.update(common::Pose2{0.5, 0.0, 0.0}, wall, time);
    EXPECT_EQ(step.state, FollowerState::kFailed);
    EXPECT_EQ(follower.recoveries(), 2);
    EXPECT_EQ(follower.recoveriesWithoutMotion(), 2);
  }
  {  // Blocked ahead but free to move: the robot follows the recovery's commands, which counts as motion.
    PathFollower follower(options);
    follower.setPath(straightPath(5.0), 0.0);
    common::Pose2 pose{0.5, 0.0, 0.0};
    FollowerStep step;
    for (double time = 0.0; follower.recoveries() < 1 || step.state != FollowerState::kFollowing; time += 0.1) {
      ASSERT_LT(time, 30.0);
      step = follower.update(pose, wall, time);
      pose.x += 0.1 * step.command.linear;  // a unicycle that obeys
      pose.yaw += 0.1 * step.command.angular;
    }
    EXPECT_EQ(follower.recoveries(), 1);
    EXPECT_EQ(follower.recoveriesWithoutMotion(), 0);
  }
}

// A robot wedged diagonally in a passage turns free only one way: after a recovery that moved nothing the next
// one (of this goal or the next, while the robot is still there) turns the other way; after one that moved the
// robot, the laser picks the side again.
TEST(PathFollower, ARecoveryThatMovedNothingMakesTheNextTurnTheOtherWay) {
  PathFollowerOptions options;
  options.max_recoveries = 2;
  // The wall ahead leans to the left: the freer side is the right (a clockwise turn).
  std::vector<common::Point2> wall = wallAhead(0.5 * options.footprint_length + 0.05);
  for (double x = 0.0; x < 0.5; x += 0.02) wall.emplace_back(x, 0.35);
  const common::Pose2 pinned{0.5, 0.0, 0.0};
  // The turn direction of every recovery until the goal fails.
  const auto recovery_turns = [&](PathFollower* follower, double* time) {
    std::vector<double> turns;
    FollowerStep step;
    bool rotating = false;
    for (; step.state != FollowerState::kFailed && *time < 200.0; *time += 0.1) {
      step = follower->update(pinned, wall, *time);
      const bool now_rotating = step.state == FollowerState::kRecoveryRotating;
      if (now_rotating && !rotating) turns.push_back(step.command.angular > 0.0 ? 1.0 : -1.0);
      rotating = now_rotating;
    }
    return turns;
  };
  PathFollower follower(options);
  double time = 0.0;
  follower.setPath(straightPath(5.0), time);
  EXPECT_EQ(recovery_turns(&follower, &time), (std::vector<double>{-1.0, 1.0}));
  follower.setPath(straightPath(5.0), time);  // the next goal, the robot still pinned
  EXPECT_EQ(recovery_turns(&follower, &time), (std::vector<double>{-1.0, 1.0}));
  // A robot that follows the commands: every recovery moves it, so the laser's side every time.
  PathFollower free_follower(options);
  common::Pose2 pose = pinned;
  time = 0.0;
  free_follower.setPath(straightPath(5.0), time);
  std::vector<double> turns;
  bool rotating = false;
  for (; free_follower.recoveries() < 2 && time < 60.0; time += 0.1) {
    const FollowerStep step = free_follower.update(pose, wall, time);
    const bool now_rotating = step.state == FollowerState::kRecoveryRotating;
    if (now_rotating && !rotating) turns.push_back(step.command.angular > 0.0 ? 1.0 : -1.0);
    rotating = now_rotating;
    pose.yaw += 0.1 * step.command.angular;  // turns, but the wall (in the robot frame) stays where it is
  }
  for (double turn : turns) EXPECT_EQ(turn, -1.0);
}

TEST(PathFollower, ObstaclePointsSkipInvalidReturnsAndApplyTheLaserPose) {
  common::RangeScan scan;
  scan.angle_min = -M_PI / 2;
  scan.angle_increment = M_PI / 2;
  scan.range_min = 0.05;
  scan.range_max = 30.0;
  scan.ranges = {1.0f, std::numeric_limits<float>::quiet_NaN(), 30.0f, 0.01f, 2.0f};  // beams at -90, 0, 90, 180, 270 deg
  scan.sensor_pose = common::Pose2{0.2, 0.0, 0.0};
  int skipped = 0;
  const std::vector<common::Point2> points = obstaclePoints(scan, &skipped);
  EXPECT_EQ(skipped, 3);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_NEAR(points[0].x(), 0.2, 1e-9);
  EXPECT_NEAR(points[0].y(), -1.0, 1e-9);
  EXPECT_NEAR(points[1].x(), 0.2, 1e-9);
  EXPECT_NEAR(points[1].y(), -2.0, 1e-9);
}

TEST(PathFollower, WallsBesideTheFootprintLeaveItsLaneOpen) {
  PathFollowerOptions options;
  const double half_length = 0.5 * options.footprint_length, half_width = 0.5 * options.footprint_width;
  // Walls 0.03 m beside both sides (within side_margin) along the whole footprint: the robot may drive on and back
  // off straight.
  std::vector<common::Point2> tunnel;
  for (double x = -half_length; x <= half_length + 1e-9; x += 0.02) {
    tunnel.emplace_back(x, half_width + 0.03);
    tunnel.emplace_back(x, -half_width - 0.03);
  }
  EXPECT_EQ(frontClearance(tunnel, options), std::numeric_limits<double>::infinity());
  EXPECT_EQ(rearClearance(tunnel, options), std::numeric_limits<double>::infinity());
  // The walls go on ahead at the same 0.03 m: a passage as tight as where the robot stands, so the lane (which
  // keeps 70% of the present gap, 0.021 m, beside the footprint) stays open.
  tunnel.emplace_back(half_length + 0.4, half_width + 0.03);
  EXPECT_EQ(frontClearance(tunnel, options), std::numeric_limits<double>::infinity());
  // A tighter one ahead (0.015 m beside the footprint's side) ends the lane there; behind it stays open.
  tunnel.emplace_back(half_length + 0.5, half_width + 0.015);
  EXPECT_NEAR(frontClearance(tunnel, options), 0.5, 1e-9);
  EXPECT_EQ(rearClearance(tunnel, options), std::numeric_limits<double>::infinity());
  // A point inside the footprint's rear half (a wall it touches): no room behind; ahead the lane keeps no margin
  // now (the present gap is 0), and only what lies within the footprint's width would end it.
  tunnel.emplace_back(-0.2, half_width - 0.01);
  EXPECT_EQ(rearClearance(tunnel, options), 0.0);
  EXPECT_EQ(frontClearance(tunnel, options), std::numeric_limits<double>::infinity());
  tunnel.emplace_back(half_length + 0.6, half_width - 0.01);
  EXPECT_NEAR(frontClearance(tunnel, options), 0.6, 1e-9);
}

TEST(PathFollower, TheLaneKeepsTheFullSideMarginInTheOpen) {
  PathFollowerOptions options;
  const double half_length = 0.5 * options.footprint_length, half_width = 0.5 * options.footprint_width;
  // Nothing beside the footprint: a post 0.4 m ahead, 0.03 m beside the footprint's side line, is in the lane.
  const std::vector<common::Point2> post{{half_length + 0.4, half_width + 0.03}};
  EXPECT_NEAR(frontClearance(post, options), 0.4, 1e-9);
  // Without a side margin it is not.
  options.side_margin = 0.0;
  EXPECT_EQ(frontClearance(post, options), std::numeric_limits<double>::infinity());
}

TEST(PathFollower, ObstacleMemoryKeepsRecentPointsInTheRobotFrame) {
  ObstacleMemory memory(1.0);
  memory.add({common::Point2(1.0, 0.0)}, common::Pose2{0.0, 0.0, 0.0}, 0.0);       // a point at map (1, 0)
  memory.add({common::Point2(0.0, 1.0)}, common::Pose2{0.0, 0.0, M_PI / 2}, 0.5);  // map (-1, 0)
  std::vector<common::Point2> points =
      memory.points(common::Pose2{1.0, 0.0, M_PI});  // robot on the first point, facing -x
  ASSERT_EQ(points.size(), 2u);
  EXPECT_NEAR(points[0].norm(), 0.0, 1e-9);
  EXPECT_NEAR(points[1].x(), 2.0, 1e-9);  // map (-1, 0) is 2 m ahead
  EXPECT_NEAR(points[1].y(), 0.0, 1e-9);
  memory.add({}, common::Pose2{}, 1.2);  // the first scan is now too old
  EXPECT_EQ(memory.points(common::Pose2{}).size(), 1u);
}

TEST(PathFollower, RejectsBadOptions) {
  PathFollowerOptions options;
  options.max_linear_velocity = -1.0;
  EXPECT_THROW(PathFollower{options}, common::InputError);
  options = PathFollowerOptions();
  options.lookahead = std::numeric_limits<double>::infinity();
  EXPECT_THROW(PathFollower{options}, common::InputError);
}

}  // namespace
}  // namespace hidden_rooms::exploration
