// rostest of the explorer under faults (test/explorer_faults.test). The test publishes a fixed map every second of
// simulated time (the world rendered, the rooms unknown: frontiers in both doorways) and relays the explorer's
// commands (explorer_cmd_vel) to the simulator (cmd_vel). While the robot drives to a doorway:
//  0. the exploration is paused (false on /explorer/resume) for longer than the follower's timeouts: the robot
//     stops at once; resumed (true), it drives on, without a recovery or a failed goal caused by the pause;
//  1. the map stops (the mapper died) for longer than the follower's progress and stall timeouts: within
//     ~map_timeout the explorer stops the robot and warns; when maps come again it drives on, without a recovery
//     or a failed goal caused by the pause;
//  2. the robot is pinned (commands are no longer relayed): the explorer backs off and turns (recovery), fails
//     the goals saying the robot did not move, and, with no other goal left, tries them again instead of
//     reporting exploration_done; unpinned, the robot drives again.
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <hidden_rooms/ExplorationStatus.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <std_msgs/Bool.h>

#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"
#include "ros_test_util.h"

namespace hidden_rooms {
namespace {

struct TimedCommand {
  double time = 0.0;  // simulated seconds
  double linear = 0.0, angular = 0.0;
};

struct TimedPosition {
  double time = 0.0;
  common::Point2 position = common::Point2::Zero();
};

class ExplorerFaultsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle private_nh("~");
    std::string world;
    ASSERT_TRUE(private_nh.getParam("world", world)) << "~world not set";
    private_nh.param("map_timeout", map_timeout_, map_timeout_);
    // The world as rendered, everything below the corridor's wall line (y < 3.95 m: the rooms) unknown; the
    // open doorways in that wall are free cells next to the unknown rooms.
    map_ = world::renderEnvironment(world::loadEnvironment(world), {}).map;
    for (int row = 0; row < map_.height(); ++row)
      for (int col = 0; col < map_.width(); ++col)
        if (map_.cellCentre(col, row).y() < 3.95) map_.cells(row, col) = common::OccupancyGrid::kUnknown;

    map_publisher_ = nh_.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
    command_publisher_ = nh_.advertise<geometry_msgs::Twist>("cmd_vel", 10);
    command_subscriber_ = nh_.subscribe("explorer_cmd_vel", 100, &ExplorerFaultsTest::onCommand, this);
    truth_subscriber_ =
        nh_.subscribe<nav_msgs::Odometry>("base_pose_ground_truth", 100, [this](const nav_msgs::Odometry::ConstPtr& m) {
          const common::Pose2 pose = fromRos(m->pose.pose);
          positions_.push_back({m->header.stamp.toSec(), common::Point2(pose.x, pose.y)});
        });
    done_subscriber_ = nh_.subscribe<std_msgs::Bool>("exploration_done", 10, [this](const std_msgs::Bool::ConstPtr& m) {
      done_ = m->data;
      if (m->data && pinned_) done_while_pinned_ = true;
    });
    status_subscriber_ = nh_.subscribe<ExplorationStatus>(
        "exploration_status", 10, [this](const ExplorationStatus::ConstPtr& m) { status_ = m; });
    resume_publisher_ = nh_.advertise<std_msgs::Bool>("explorer/resume", 1, true);
    rosout_subscriber_ = nh_.subscribe<rosgraph_msgs::Log>(
        "/rosout", 1000, [this](const rosgraph_msgs::Log::ConstPtr& m) { log_.push_back(m); });
  }

  void onCommand(const geometry_msgs::Twist::ConstPtr& command) {
    commands_.push_back({ros::Time::now().toSec(), command->linear.x, command->angular.z});
    if (!pinned_) command_publisher_.publish(command);
  }

  // Spins, publishing the map every simulated second while it is alive, until `condition` or the wall timeout.
  template <typename Condition>
  bool waitFor(Condition condition, double wall_seconds) {
    return testing::spinUntil(condition, wall_seconds, [this] {
      const ros::Time now = ros::Time::now();
      if (map_alive_ && !now.isZero() && (last_map_.isZero() || (now - last_map_).toSec() >= 1.0)) {
        map_publisher_.publish(toRos(map_, "map", now));
        last_map_ = now;
      }
    });
  }
  bool waitUntilSimTime(double time, double wall_seconds) {
    return waitFor([&] { return ros::Time::now().toSec() >= time; }, wall_seconds);
  }

  std::optional<common::Point2> position() const {
    return positions_.empty() ? std::nullopt : std::optional<common::Point2>(positions_.back().position);
  }
  // The largest distance between two true positions logged within [from, to] (simulated seconds).
  double motionBetween(double from, double to) const {
    std::optional<common::Point2> first;
    double motion = 0.0;
    for (const TimedPosition& p : positions_) {
      if (p.time < from || p.time > to) continue;
      if (!first) first = p.position;
      motion = std::max(motion, (p.position - *first).norm());
    }
    return motion;
  }
  bool movedFrom(const common::Point2& origin, double distance) const {
    return position() && (*position() - origin).norm() >= distance;
  }

  // Warnings of the explorer on rosout containing `text`, stamped within [from, to] (simulated seconds).
  int explorerWarnings(const std::string& text, double from = 0.0, double to = 1e12) const {
    int count = 0;
    for (const auto& entry : log_) {
      const double time = entry->header.stamp.toSec();
      count += entry->name == "/explorer" && entry->level == rosgraph_msgs::Log::WARN &&
               entry->msg.find(text) != std::string::npos && time >= from && time <= to;
    }
    return count;
  }

  ros::NodeHandle nh_;
  double map_timeout_ = 2.0;
  common::OccupancyGrid map_;
  bool map_alive_ = true;
  ros::Time last_map_;
  bool pinned_ = false;
  bool done_ = false;
  bool done_while_pinned_ = false;
  // Publishes `run` on explorer/resume once the explorer listens; returns the ROS time the explorer reported the
  // new state at (its exploration_status), or a negative number when it did not within the wall timeout.
  double setRunning(bool run) {
    if (!waitFor([this] { return resume_publisher_.getNumSubscribers() > 0; }, 30.0)) return -1.0;
    std_msgs::Bool flag;
    flag.data = run;
    resume_publisher_.publish(flag);
    if (!waitFor([&] { return status_ && status_->paused == !run; }, 30.0)) return -1.0;
    return status_->stamp.toSec();
  }

  ros::Publisher map_publisher_, command_publisher_, resume_publisher_;
  ros::Subscriber command_subscriber_, truth_subscriber_, done_subscriber_, rosout_subscriber_, status_subscriber_;
  ExplorationStatus::ConstPtr status_;
  std::vector<TimedCommand> commands_;
  std::vector<TimedPosition> positions_;
  std::vector<rosgraph_msgs::Log::ConstPtr> log_;
};

TEST_F(ExplorerFaultsTest, PausesStopsWithoutMapsAndRecoversWhenPinned) {
  // Exploring: the robot drives towards a doorway.
  ASSERT_TRUE(waitFor([this] { return position().has_value(); }, 30.0)) << "no ground truth from the simulator";
  const common::Point2 start = *position();
  ASSERT_TRUE(waitFor([&] { return movedFrom(start, 0.3); }, 30.0)) << "the explorer did not drive";

  // 0. Paused for 9 simulated seconds, beyond progress_timeout (6 s) and stall_timeout (1 s), counted from when
  // the explorer took the pause (on a busy machine the message's way can take longer than a control period).
  const double paused = setRunning(false);
  ASSERT_GT(paused, 0.0) << "the explorer did not report the pause on exploration_status";
  ASSERT_TRUE(waitUntilSimTime(paused + 9.0, 30.0));
  const double paused_by = paused + 0.5;  // its control step after the pause (0.1 s), and the commands' way
  for (const TimedCommand& command : commands_) {
    if (command.time <= paused_by) continue;
    EXPECT_TRUE(command.linear == 0.0 && command.angular == 0.0)
        << "moving command " << command.linear << ", " << command.angular << " at " << command.time
        << " s, paused at " << paused << " s";
  }
  EXPECT_LT(motionBetween(paused_by + 1.0, paused + 9.0), 0.03) << "the robot did not stop when paused";
  const double unpaused = setRunning(true);
  ASSERT_GT(unpaused, 0.0) << "the explorer did not report the resume on exploration_status";
  const common::Point2 unpaused_at = *position();
  ASSERT_TRUE(waitFor([&] { return movedFrom(unpaused_at, 0.3); }, 20.0)) << "no driving after resume";
  EXPECT_EQ(explorerWarnings("not reached", paused, unpaused + 1.5), 0) << "the pause failed the goal";
  EXPECT_EQ(explorerWarnings("did not move", paused, unpaused + 1.5), 0) << "the pause failed the goal";

  // 1. No map for 11 simulated seconds: the robot stands still for more than 8 s, beyond the follower's
  // progress_timeout (6 s) and stall_timeout (1 s) of the launch file.
  map_alive_ = false;
  const double stale = ros::Time::now().toSec();
  constexpr double kPause = 11.0;
  ASSERT_TRUE(waitUntilSimTime(stale + kPause, 40.0));
  const double stopped_by = stale + map_timeout_ + 0.5;  // the last map came at most 1 s before `stale`
  for (const TimedCommand& command : commands_) {
    if (command.time <= stopped_by) continue;
    EXPECT_TRUE(command.linear == 0.0 && command.angular == 0.0)
        << "moving command " << command.linear << ", " << command.angular << " at " << command.time << " s, "
        << command.time - stale << " s after the last map";
  }
  EXPECT_LT(motionBetween(stopped_by + 1.0, stale + kPause), 0.03) << "the robot did not stop without maps";
  EXPECT_GE(explorerWarnings("no new map"), 1) << "no warning about the missing map";

  map_alive_ = true;
  const double resumed = ros::Time::now().toSec();
  const common::Point2 resumed_at = *position();
  ASSERT_TRUE(waitFor([&] { return movedFrom(resumed_at, 0.3); }, 20.0)) << "no driving when the map came back";
  for (const TimedCommand& command : commands_) {
    if (command.time < resumed || command.time > resumed + 1.5) continue;
    EXPECT_GE(command.linear, 0.0) << "a recovery (backing off) right after the pause, at " << command.time;
  }
  EXPECT_EQ(explorerWarnings("not reached", stale, resumed + 1.5), 0) << "the pause failed the goal";
  EXPECT_EQ(explorerWarnings("did not move", stale, resumed + 1.5), 0) << "the pause failed the goal";

  // 2. Pinned: the explorer's commands move nothing.
  pinned_ = true;
  const double pinned = ros::Time::now().toSec();
  waitFor([&] { return explorerWarnings("trying them again", pinned) > 0 || done_while_pinned_; }, 60.0);
  ASSERT_FALSE(done_while_pinned_) << "exploration_done while the robot was only stuck";
  ASSERT_GE(explorerWarnings("trying them again", pinned), 1)
      << "the explorer did not retry the goals it failed while pinned";
  bool backed_off = false, turned = false;
  for (const TimedCommand& command : commands_)
    if (command.time > pinned) {
      backed_off = backed_off || command.linear < 0.0;
      turned = turned || (command.linear == 0.0 && std::abs(command.angular) >= 0.75);  // max_angular_velocity 0.8
    }
  EXPECT_TRUE(backed_off) << "no recovery backing off";
  EXPECT_TRUE(turned) << "no recovery turn";
  EXPECT_GE(explorerWarnings("did not move", pinned), 1);
  const double retried = ros::Time::now().toSec();
  ASSERT_TRUE(waitUntilSimTime(retried + 2.0, 10.0));  // done would come with the next maps (done_confirmations 2)
  EXPECT_FALSE(done_while_pinned_) << "exploration_done while the robot was only stuck";

  pinned_ = false;
  const common::Point2 freed_at = *position();
  EXPECT_TRUE(waitFor([&] { return movedFrom(freed_at, 0.3); }, 30.0)) << "no driving once the robot was free";
  std::printf("pause %.1f..%.1f s, pinned %.1f..%.1f s, %zu commands, path from (%.2f, %.2f) to (%.2f, %.2f)\n",
              stale, resumed, pinned, ros::Time::now().toSec(), commands_.size(), start.x(), start.y(),
              position()->x(), position()->y());
}

}  // namespace
}  // namespace hidden_rooms

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_explorer_faults");
  return RUN_ALL_TESTS();
}
