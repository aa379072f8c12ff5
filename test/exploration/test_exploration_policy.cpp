// The exploration policy on a synthetic corridor: the goal and the drive to it, the blacklist of reached and failed
// goals, the second try, the release order of blocked goals, done after the confirmations, the goal hysteresis, the
// plan in the background.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "hidden_rooms/exploration/exploration_policy.h"

namespace hidden_rooms::exploration {
namespace {

using Type = ExplorationEventType;

// A known corridor 8 m x 3 m (0.1 m cells; free x 1.0..9.0, y 0.1..3.1, walls along both long sides) between
// unknown ends (x < 1.0 and x > 9.0); an end that is not open has a wall (no frontier there). Goals on the
// frontiers' side of the robot lie 0.5 m inside the corridor (goal_reach 0.6 m is 5 whole cells): x = 1.55 and
// 8.45. Another size (`cols` x `rows` cells) keeps the 1 m unknown ends and the walls.
common::OccupancyGrid corridor(bool left_open, bool right_open, int cols = 100, int rows = 32) {
  common::OccupancyGrid grid;
  grid.resolution = 0.1;
  grid.cells = cv::Mat_<int8_t>(rows, cols, common::OccupancyGrid::kUnknown);
  grid.cells(cv::Rect(0, 0, cols, 1)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(0, rows - 1, cols, 1)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(10, 1, cols - 20, rows - 2)).setTo(common::OccupancyGrid::kFree);
  if (!left_open) grid.cells(cv::Rect(9, 1, 1, rows - 2)).setTo(common::OccupancyGrid::kOccupied);
  if (!right_open) grid.cells(cv::Rect(cols - 10, 1, 1, rows - 2)).setTo(common::OccupancyGrid::kOccupied);
  return grid;
}

// A closed room, every cell known: no frontier.
common::OccupancyGrid closedRoom() {
  common::OccupancyGrid grid = corridor(false, false);
  grid.cells.setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(10, 1, 80, 30)).setTo(common::OccupancyGrid::kFree);
  return grid;
}

constexpr double kCentreY = 1.55;  // the centre row of the corridor (row 16)
constexpr double kLeftGoalX = 1.55, kRightGoalX = 8.45;

std::vector<Type> types(const ExplorationStep& step) {
  std::vector<Type> result;
  for (const ExplorationEvent& event : step.events) result.push_back(event.type);
  return result;
}

bool has(const ExplorationStep& step, Type type) {
  const std::vector<Type> all = types(step);
  return std::find(all.begin(), all.end(), type) != all.end();
}

const ExplorationEvent& first(const ExplorationStep& step, Type type) {
  static const ExplorationEvent none;
  for (const ExplorationEvent& event : step.events)
    if (event.type == type) return event;
  ADD_FAILURE() << "no event of type " << static_cast<int>(type);
  return none;
}

// Steps at 10 Hz from *time on with poses from `pose_at` until an event of `type` comes (at most `seconds`).
ExplorationStep runUntil(ExplorationPolicy* policy, double* time, Type type, double seconds,
                         const std::function<common::Pose2(double)>& pose_at) {
  const double end = *time + seconds;
  while (*time < end) {
    *time += 0.1;
    const ExplorationStep step = policy->update(pose_at(*time), *time);
    if (has(step, type)) return step;
  }
  ADD_FAILURE() << "no event of type " << static_cast<int>(type) << " within " << seconds << " s";
  return ExplorationStep();
}

// Failure needs neither a real robot nor minutes: short stall and progress timeouts, one recovery; replans only on
// new maps; a blacklisted goal covers its whole frontier.
ExplorationPolicyOptions quickFailures() {
  ExplorationPolicyOptions options;
  options.replan_interval = 0.0;
  options.blacklist_radius = 3.0;
  options.follower.stall_timeout = 0.5;
  options.follower.backoff_time = 0.2;
  options.follower.recovery_rotate_time = 0.2;
  options.follower.max_recoveries = 1;
  options.follower.progress_timeout = 3.0;
  return options;
}

// A robot at `x` on the corridor's centre line that stands still (its recoveries move nothing: stuck).
std::function<common::Pose2(double)> standing(double x) {
  return [x](double) { return common::Pose2{x, kCentreY, 0.0}; };
}

// A robot at `x` that turns on the spot (it moves, so no stall, but makes no progress along its path).
std::function<common::Pose2(double)> turning(double x) {
  return [x](double time) { return common::Pose2{x, kCentreY, 2.0 * time}; };
}

TEST(ExplorationPolicy, ChoosesTheNearestFrontierAndDrivesThere) {
  ExplorationPolicy policy;
  policy.setMap(corridor(false, true));
  common::Pose2 pose{5.05, kCentreY, 0.0};
  ExplorationStep step = policy.update(pose, 0.1);
  EXPECT_TRUE(step.planned);
  ASSERT_EQ(types(step), std::vector<Type>{Type::kGoalChosen});
  const ExplorationEvent& chosen = step.events[0];
  EXPECT_NEAR(chosen.position.x(), kRightGoalX, 1e-9);
  EXPECT_NEAR(chosen.position.y(), kCentreY, 1e-9);
  EXPECT_NEAR(chosen.cost, kRightGoalX - 5.05, 0.05);
  ASSERT_TRUE(policy.goal());
  EXPECT_EQ(policy.goal()->position, chosen.position);
  EXPECT_NEAR(step.command.linear, policy.options().follower.max_linear_velocity, 1e-9);
  EXPECT_NEAR(step.command.angular, 0.0, 0.05);
  EXPECT_FALSE(policy.done());

  // Driving the commands (a unicycle at 10 Hz) reaches the goal.
  double time = 0.1;
  while (!has(step, Type::kGoalReached) && time < 20.0) {
    pose.x += 0.1 * step.command.linear * std::cos(pose.yaw);
    pose.y += 0.1 * step.command.linear * std::sin(pose.yaw);
    pose.yaw += 0.1 * step.command.angular;
    step = policy.update(pose, time += 0.1);
    if (!has(step, Type::kGoalReached)) {
      EXPECT_GT(step.command.linear, 0.0) << "at t = " << time;
    }
  }
  ASSERT_TRUE(has(step, Type::kGoalReached));
  EXPECT_NEAR(first(step, Type::kGoalReached).position.x(), kRightGoalX, 1e-9);
  EXPECT_LT(std::hypot(pose.x - kRightGoalX, pose.y - kCentreY), policy.options().follower.goal_tolerance + 0.06);
  EXPECT_LT(time, 2.0 * (kRightGoalX - 5.05) / policy.options().follower.max_linear_velocity);
}

// With background_planning the plan runs on a thread of its own: the robot does not drive until the first plan is
// in, then follows its path; a slow plan (a 200 m x 200 m map, a wavefront of about 0.6 s) does not hold up the
// commands.
TEST(ExplorationPolicy, ABackgroundPlanDoesNotHoldUpTheControlLoop) {
  ExplorationPolicyOptions options;
  options.background_planning = true;
  options.replan_interval = 0.0;
  ExplorationPolicy policy(options);
  policy.setMap(corridor(false, true));
  common::Pose2 pose{5.05, kCentreY, 0.0};
  double time = 0.1;
  ExplorationStep step = policy.update(pose, time);
  EXPECT_FALSE(step.planned);
  EXPECT_EQ(step.command.linear, 0.0);  // no goal yet: it turns in place while the plan runs
  for (int k = 0; k < 10000 && !step.planned; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    step = policy.update(pose, time);
  }
  ASSERT_TRUE(step.planned);
  ASSERT_TRUE(has(step, Type::kGoalChosen));
  EXPECT_NEAR(first(step, Type::kGoalChosen).position.x(), kRightGoalX, 1e-9);
  EXPECT_GT(step.command.linear, 0.0);

  policy.setMap(corridor(false, true, 2000, 2000));  // 198 m x 200 m, the frontier 194 m away
  int moving_while_planning = 0;
  step = ExplorationStep();
  for (int k = 0; k < 100000 && !step.planned; ++k) {  // about real time: 1 ms a step
    step = policy.update(pose, time += 0.001);
    pose.x += 0.001 * step.command.linear;
    if (!step.planned) {
      EXPECT_GT(step.command.linear, 0.0) << "the robot stopped while the plan ran, at update " << k;
      ++moving_while_planning;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  ASSERT_TRUE(step.planned) << "the plan on the large map never came in";
  EXPECT_GT(moving_while_planning, 0) << "update() waited for the plan";
  std::printf("%d updates steered while the large map's plan ran\n", moving_while_planning);
}

TEST(ExplorationPolicy, AReachedGoalIsBlacklisted) {
  ExplorationPolicy policy;
  policy.setMap(corridor(false, true));
  policy.update(common::Pose2{5.05, kCentreY, 0.0}, 0.1);
  ASSERT_TRUE(policy.goal());
  const common::Point2 reached = policy.goal()->position;
  // The robot stands at the goal; the frontier is still there (the map did not change).
  const ExplorationStep step = policy.update(common::Pose2{reached.x(), reached.y(), 0.0}, 0.2);
  EXPECT_EQ(types(step), (std::vector<Type>{Type::kGoalReached, Type::kGoalChosen}));
  EXPECT_TRUE(policy.blacklist().contains(reached));
  ASSERT_TRUE(policy.goal());
  EXPECT_GT((policy.goal()->position - reached).norm(), policy.options().blacklist_radius);
  // A reached place is not released when nothing else is left.
  EXPECT_TRUE(policy.blacklist().failed_points.empty());
  EXPECT_TRUE(policy.blacklist().stuck_points.empty());
}

TEST(ExplorationPolicy, AFailedGoalGetsOneSecondTry) {
  ExplorationPolicyOptions options = quickFailures();
  options.passages.failures = 0;  // no blocked passages here
  ExplorationPolicy policy(options);
  policy.setMap(corridor(false, true));
  double time = 0.1;
  policy.update(common::Pose2{5.05, kCentreY, 0.0}, time);
  ASSERT_TRUE(policy.goal());
  const common::Point2 goal = policy.goal()->position;

  // It fails while the robot moves: blacklisted, and as nothing else is left, tried again at once.
  ExplorationStep step = runUntil(&policy, &time, Type::kGoalFailed, 10.0, turning(5.05));
  EXPECT_EQ(types(step), (std::vector<Type>{Type::kGoalFailed, Type::kFailedReleased, Type::kGoalChosen}));
  EXPECT_EQ(first(step, Type::kGoalFailed).position, goal);
  EXPECT_EQ(first(step, Type::kGoalFailed).recoveries, 0);
  EXPECT_TRUE(first(step, Type::kGoalFailed).retry_later);
  EXPECT_EQ(first(step, Type::kFailedReleased).count, 1u);
  EXPECT_EQ(first(step, Type::kGoalChosen).position, goal);

  // It fails again: no third try; no goal, so the robot turns in place looking for one.
  step = runUntil(&policy, &time, Type::kGoalFailed, 10.0, turning(5.05));
  EXPECT_EQ(types(step), (std::vector<Type>{Type::kGoalFailed, Type::kNoGoal}));
  EXPECT_FALSE(first(step, Type::kGoalFailed).retry_later);
  EXPECT_TRUE(policy.blacklist().contains(goal));
  EXPECT_FALSE(policy.goal());
  EXPECT_EQ(step.command.linear, 0.0);
  EXPECT_EQ(step.command.angular, options.search_angular_velocity);
  // Without a new map that does not count towards done.
  EXPECT_FALSE(policy.done());
}

TEST(ExplorationPolicy, ReleasesStuckPlacesBeforeBlockedPassagesBeforeFailedGoals) {
  ExplorationPolicyOptions options = quickFailures();
  options.passages.failures = 1;  // one failure blocks the passage ahead
  ExplorationPolicy policy(options);
  policy.setMap(corridor(true, true));
  double time = 0.1;
  ExplorationStep step = policy.update(common::Pose2{5.05, kCentreY, 0.0}, time);
  ASSERT_TRUE(policy.goal());
  EXPECT_NEAR(policy.goal()->position.x(), kRightGoalX, 1e-9);

  // The right goal fails while the robot moves: blacklisted for a second try, the passage ahead blocked; the
  // left frontier is left, so nothing is released.
  step = runUntil(&policy, &time, Type::kGoalFailed, 10.0, turning(5.05));
  EXPECT_EQ(types(step), (std::vector<Type>{Type::kGoalFailed, Type::kPassageBlocked, Type::kGoalChosen}));
  EXPECT_FALSE(policy.passages().blockedPoints().empty());
  ASSERT_TRUE(policy.goal());
  EXPECT_NEAR(policy.goal()->position.x(), kLeftGoalX, 1e-9);

  // The left goal fails with the robot stuck: now every goal is blocked in one of the three ways. The stuck place
  // is released first, and as that gives a goal, the passage and the failed place stay.
  step = runUntil(&policy, &time, Type::kGoalFailedStuck, 10.0, standing(5.05));
  EXPECT_EQ(types(step), (std::vector<Type>{Type::kGoalFailedStuck, Type::kStuckReleased, Type::kGoalChosen}));
  EXPECT_EQ(first(step, Type::kGoalFailedStuck).recoveries, 1);
  EXPECT_NEAR(first(step, Type::kGoalChosen).position.x(), kLeftGoalX, 1e-9);
  EXPECT_FALSE(policy.passages().blockedPoints().empty());
  EXPECT_EQ(policy.blacklist().failed_points.size(), 1u);

  // The left goal is reached: with the right one failed and its passage blocked, the passage is opened first,
  // then the failed place released, which gives the goal.
  const common::Point2 left = policy.goal()->position;
  step = policy.update(common::Pose2{left.x(), left.y(), M_PI}, time + 0.1);
  EXPECT_EQ(types(step), (std::vector<Type>{Type::kGoalReached, Type::kPassagesReleased, Type::kFailedReleased,
                                            Type::kGoalChosen}));
  EXPECT_GT(first(step, Type::kPassagesReleased).count, 0u);
  EXPECT_NEAR(first(step, Type::kGoalChosen).position.x(), kRightGoalX, 1e-9);
  EXPECT_TRUE(policy.passages().blockedPoints().empty());
}

TEST(ExplorationPolicy, DoneOnlyAfterTheConfiguredPlansWithoutAGoal) {
  ExplorationPolicyOptions options;
  options.done_confirmations = 3;
  ExplorationPolicy policy(options);
  const common::Pose2 pose{5.05, kCentreY, 0.0};
  double time = 0.0;
  for (int plan = 1; plan < options.done_confirmations; ++plan) {
    policy.setMap(closedRoom());
    const ExplorationStep step = policy.update(pose, time += 0.1);
    EXPECT_EQ(types(step), std::vector<Type>{Type::kNoGoal}) << "plan " << plan;
    EXPECT_EQ(first(step, Type::kNoGoal).count, 0u);
    EXPECT_FALSE(policy.done());
    EXPECT_EQ(step.command.angular, options.search_angular_velocity);  // looking around
  }
  // Replans without a new map do not count.
  for (int replan = 0; replan < 2; ++replan) {
    time += options.replan_interval;
    EXPECT_EQ(types(policy.update(pose, time)), std::vector<Type>{Type::kNoGoal});
    EXPECT_FALSE(policy.done());
  }
  // Between plans nothing happens.
  EXPECT_TRUE(policy.update(pose, time += 0.1).events.empty());

  policy.setMap(closedRoom());
  ExplorationStep step = policy.update(pose, time += 0.1);
  EXPECT_EQ(types(step), std::vector<Type>{Type::kDone});
  EXPECT_TRUE(policy.done());
  EXPECT_EQ(step.command.linear, 0.0);
  EXPECT_EQ(step.command.angular, 0.0);
  policy.setMap(closedRoom());
  EXPECT_TRUE(policy.update(pose, time += 0.1).events.empty());  // done once

  // A frontier appears: exploring again.
  policy.setMap(corridor(false, true));
  step = policy.update(pose, time += 0.1);
  EXPECT_EQ(types(step), (std::vector<Type>{Type::kResumed, Type::kGoalChosen}));
  EXPECT_FALSE(policy.done());
  EXPECT_GT(step.command.linear, 0.0);
}

// The corridor open on the right with a wall across at x = 6.0 and a 0.4 m gap in it on the centre line: closer than
// min_clearance (0.30 m) to its jambs everywhere, so the map draws it closed for the planner.
common::OccupancyGrid corridorWithNarrowGap() {
  common::OccupancyGrid grid = corridor(false, true);
  grid.cells(cv::Rect(60, 1, 1, 13)).setTo(common::OccupancyGrid::kOccupied);
  grid.cells(cv::Rect(60, 18, 1, 13)).setTo(common::OccupancyGrid::kOccupied);
  return grid;
}

TEST(ExplorationPolicy, WhenNothingElseIsLeftTheWayInIsAWayOut) {
  // The robot drove from x = 8.0 through the gap to x = 3.0 while the map had no frontier; then the map draws the
  // gap too narrow and the only frontier lies behind it. With nothing else left, its trail opens the gap.
  for (const double trail_length : {20.0, 0.0}) {
    ExplorationPolicyOptions options = quickFailures();
    options.trail_length = trail_length;
    ExplorationPolicy policy(options);
    policy.setMap(closedRoom());
    double time = 0.0;
    for (double x = 8.0; x >= 3.0 - 1e-9; x -= 0.05) policy.update(common::Pose2{x, kCentreY, M_PI}, time += 0.1);
    policy.setMap(corridorWithNarrowGap());
    const ExplorationStep step = policy.update(common::Pose2{3.0, kCentreY, 0.0}, time += 0.1);  // turned round
    if (trail_length == 0.0) {
      EXPECT_EQ(types(step), std::vector<Type>{Type::kNoGoal});
      continue;
    }
    ASSERT_EQ(types(step), (std::vector<Type>{Type::kTrailOpened, Type::kGoalChosen}));
    EXPECT_NEAR(first(step, Type::kTrailOpened).path_length, 5.0, 0.1);
    EXPECT_NEAR(first(step, Type::kGoalChosen).position.x(), kRightGoalX, 1e-9);
    EXPECT_FALSE(first(step, Type::kGoalChosen).look);
    EXPECT_GT(step.command.linear, 0.0);
  }
}

TEST(ExplorationPolicy, KeepsItsGoalUnlessAnotherIsCheaperByTheHysteresis) {
  ExplorationPolicyOptions options;
  options.goal_hysteresis = 1.0;
  ExplorationPolicy policy(options);
  const common::OccupancyGrid map = corridor(true, true);
  policy.setMap(map);
  // At x = 5.05 the right goal costs 3.4, the left one 3.5.
  ExplorationStep step = policy.update(common::Pose2{5.05, kCentreY, 0.0}, 0.1);
  ASSERT_TRUE(policy.goal());
  EXPECT_NEAR(policy.goal()->position.x(), kRightGoalX, 1e-9);
  // At x = 4.75 the left goal is 0.5 cheaper: the right one stays (replanned, not chosen anew).
  policy.setMap(map);
  step = policy.update(common::Pose2{4.75, kCentreY, 0.0}, 0.2);
  EXPECT_TRUE(step.planned);
  EXPECT_TRUE(step.events.empty());
  ASSERT_TRUE(policy.goal());
  EXPECT_NEAR(policy.goal()->position.x(), kRightGoalX, 1e-9);
  EXPECT_EQ(policy.follower().state(), FollowerState::kFollowing);
  // At x = 4.25 it is 1.5 cheaper: switched.
  policy.setMap(map);
  step = policy.update(common::Pose2{4.25, kCentreY, 0.0}, 0.3);
  EXPECT_EQ(types(step), std::vector<Type>{Type::kGoalChosen});
  EXPECT_NEAR(first(step, Type::kGoalChosen).position.x(), kLeftGoalX, 1e-9);
}

TEST(ExplorationPolicy, AnUnusableMapKeepsTheOldOne) {
  ExplorationPolicy policy;
  policy.setMap(corridor(false, true));
  policy.update(common::Pose2{5.05, kCentreY, 0.0}, 0.1);
  ASSERT_TRUE(policy.goal());
  policy.setUnusableMap("rotated map origins are not supported");
  const ExplorationStep step = policy.update(common::Pose2{5.05, kCentreY, 0.0}, 0.2);
  ASSERT_EQ(types(step), std::vector<Type>{Type::kMapUnusable});
  EXPECT_EQ(step.events[0].message, "rotated map origins are not supported");
  EXPECT_FALSE(step.planned);
  EXPECT_EQ(policy.planner().map().width(), 100);
  EXPECT_TRUE(policy.goal());
  EXPECT_GT(step.command.linear, 0.0);
}

TEST(ExplorationPolicy, AHeldRobotDoesNotFailItsGoal) {
  ExplorationPolicyOptions options = quickFailures();
  ExplorationPolicy policy(options);
  policy.setMap(corridor(false, true));
  const common::Pose2 pose{5.05, kCentreY, 0.0};
  policy.update(pose, 0.1);
  // Held (a stale scan) for longer than the progress timeout: no failure, no recovery afterwards.
  policy.hold(0.2);
  const ExplorationStep step = policy.update(pose, 0.2 + 2.0 * options.follower.progress_timeout);
  EXPECT_TRUE(step.events.empty());
  EXPECT_EQ(policy.follower().state(), FollowerState::kFollowing);
  EXPECT_GT(step.command.linear, 0.0);
}

}  // namespace
}  // namespace hidden_rooms::exploration
