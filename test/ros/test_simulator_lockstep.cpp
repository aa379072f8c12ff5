// rostest: the simulator in lockstep with this test node (test/ros/simulator_lockstep.test). The world starts once
// the node and a start node (whose ready report this node sends) have reported ready; it steps on only after the
// node reports each scan and the commands it reports have arrived; an unreported scan is re-sent and, after
// ~lockstep_timeout, the world steps on anyway; run_until holds the clock and refuses bad times.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <hidden_rooms/LockstepAck.h>
#include <hidden_rooms/RunUntil.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/LaserScan.h>

#include "ros_test_util.h"

namespace {

using hidden_rooms::testing::spinUntil;

const std::string kLockstepNode = "/test_ros_simulator_lockstep";  // the launch file's ~lockstep_nodes
const std::string kStartNode = "/start_node";                      // and its ~lockstep_start_nodes

class SimulatorLockstepTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // rostest names the node after the test: were it another, the world would step on timeouts alone.
    ASSERT_EQ(ros::this_node::getName(), kLockstepNode);
    scan_subscriber_ = nh_.subscribe<sensor_msgs::LaserScan>(
        "base_scan", 100, [this](const sensor_msgs::LaserScan::ConstPtr& m) { scans_.push_back(m->header.stamp); });
    clock_subscriber_ = nh_.subscribe<rosgraph_msgs::Clock>(
        "/clock", 1000, [this](const rosgraph_msgs::Clock::ConstPtr& m) { clock_ = m->clock; });
    truth_subscriber_ = nh_.subscribe<nav_msgs::Odometry>(
        "base_pose_ground_truth", 100, [this](const nav_msgs::Odometry::ConstPtr& m) { truth_ = m; });
    ack_publisher_ = nh_.advertise<hidden_rooms::LockstepAck>("lockstep", 10, true);
    command_publisher_ = nh_.advertise<geometry_msgs::Twist>("cmd_vel", 10);
    ASSERT_TRUE(ros::service::waitForService("run_until", ros::Duration(30.0)));
    // Latched, the topic keeps one report per publisher: this one sends the start node's too, so none may go out
    // before the simulator listens.
    ASSERT_TRUE(spinUntil([this] { return ack_publisher_.getNumSubscribers() > 0; }, 30.0));
  }

  // Reports ready as this node, then as the start node, and waits for the first scan.
  void startWorld() {
    report(ros::Time());
    report(ros::Time(), false, kStartNode);
    ASSERT_TRUE(spinUntil([this] { return !scans_.empty(); }, 30.0)) << "no scan";
  }

  void report(const ros::Time& stamp, bool finished = false, const std::string& node = ros::this_node::getName()) {
    hidden_rooms::LockstepAck ack;
    ack.node = node;
    ack.stamp = stamp;
    ack.commands = commands_;
    ack.finished = finished;
    ack_publisher_.publish(ack);
  }

  // Reports the newest scan and waits for the next one; its stamp, or 0 when none came within `wall_seconds`.
  double stepOnce(double wall_seconds = 5.0) {
    const ros::Time last = scans_.back();
    report(last);
    if (!spinUntil([&] { return scans_.back() > last; }, wall_seconds)) return 0.0;
    return scans_.back().toSec();
  }

  hidden_rooms::RunUntil runUntil(double time) {
    hidden_rooms::RunUntil call;
    call.request.time = time;
    EXPECT_TRUE(ros::service::call("run_until", call));
    return call;
  }

  ros::NodeHandle nh_;
  ros::Subscriber scan_subscriber_, clock_subscriber_, truth_subscriber_;
  ros::Publisher ack_publisher_, command_publisher_;
  std::vector<ros::Time> scans_;
  ros::Time clock_;
  nav_msgs::Odometry::ConstPtr truth_;
  uint32_t commands_ = 0;
};

// Run first: the world has not started yet.
TEST_F(SimulatorLockstepTest, StartsOnceItsNodesAndThenItsStartNodesAreReady) {
  spinUntil([] { return false; }, 1.0);
  EXPECT_TRUE(scans_.empty()) << "started before any node was ready";
  EXPECT_TRUE(clock_.isZero());
  report(ros::Time(), false, kStartNode);  // before the lockstep node: does not count
  report(ros::Time());
  spinUntil([] { return false; }, 1.0);
  EXPECT_TRUE(scans_.empty()) << "started on a start node's report sent before the lockstep nodes were ready";
  report(ros::Time(), false, kStartNode);
  ASSERT_TRUE(spinUntil([this] { return !scans_.empty(); }, 5.0)) << "did not start when every node was ready";
  EXPECT_NEAR(scans_.front().toSec(), 0.1, 1e-6);
}

TEST_F(SimulatorLockstepTest, StepsOneScanPerReportWaitsForCommandsAndRunsUntilAHold) {
  startWorld();
  // Unreported, the first scan is re-sent (to nodes that subscribed late) and the clock stays at it.
  ASSERT_TRUE(spinUntil([this] { return scans_.size() >= 2; }, 5.0)) << "the unreported scan was not re-sent";
  EXPECT_EQ(scans_[0], scans_[1]);
  EXPECT_NEAR(clock_.toSec(), scans_[0].toSec(), 1e-9);

  // One report, one scan further (the laser at 10 Hz).
  for (int k = 0; k < 5; ++k) {
    const double before = scans_.back().toSec();
    const double next = stepOnce();
    ASSERT_GT(next, 0.0) << "no scan after the report of " << before;
    EXPECT_NEAR(next - before, 0.1, 1e-6);
  }

  // A report that counts a command not yet arrived holds the world until the command comes.
  ++commands_;
  const ros::Time waiting = scans_.back();
  report(waiting);
  spinUntil([] { return false; }, 1.0);
  EXPECT_EQ(scans_.back(), waiting) << "stepped on before the reported command arrived";
  geometry_msgs::Twist forward;
  forward.linear.x = 0.3;
  command_publisher_.publish(forward);
  ASSERT_TRUE(spinUntil([&] { return scans_.back() > waiting; }, 5.0)) << "the command arrived, no step followed";

  // run_until holds the clock at a time: reports go on, no scan after it.
  const double hold = std::round(scans_.back().toSec() * 10.0) / 10.0 + 0.5;
  hidden_rooms::RunUntil call = runUntil(hold);
  EXPECT_TRUE(call.response.success) << call.response.message;
  EXPECT_FALSE(call.response.reached);
  for (int k = 0; k < 10 && scans_.back().toSec() < hold - 1e-6; ++k) ASSERT_GT(stepOnce(), 0.0);
  EXPECT_NEAR(scans_.back().toSec(), hold, 1e-6);
  report(scans_.back(), true);
  ASSERT_TRUE(spinUntil([&] { return runUntil(hold).response.reached; }, 5.0)) << "the hold is not reached";
  call = runUntil(hold);
  EXPECT_NEAR(call.response.now, hold, 1e-6);
  EXPECT_EQ(call.response.finished, std::vector<std::string>{ros::this_node::getName()});
  spinUntil([] { return false; }, 0.5);
  EXPECT_NEAR(scans_.back().toSec(), hold, 1e-6) << "stepped past the hold";
  EXPECT_NEAR(clock_.toSec(), hold, 1e-6);
  ASSERT_TRUE(truth_);
  EXPECT_LT(truth_->pose.pose.position.y, 5.2 - 0.05) << "the command did not move the robot (-y)";

  // Bad times are refused and change nothing; 0 lifts the hold.
  for (double bad : {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    call = runUntil(bad);
    EXPECT_FALSE(call.response.success) << bad;
    EXPECT_NE(call.response.message.find("finite"), std::string::npos) << call.response.message;
  }
  EXPECT_TRUE(runUntil(hold).response.reached);
  EXPECT_TRUE(runUntil(0.0).response.success);
  ASSERT_GT(stepOnce(), hold);
}

TEST_F(SimulatorLockstepTest, AnUnreportedScanIsGivenUpAfterTheTimeout) {
  startWorld();
  EXPECT_TRUE(runUntil(0.0).response.success);
  ASSERT_GT(stepOnce(), 0.0);  // a fresh scan: the wait for its report starts now
  const ros::Time silent = scans_.back();
  const ros::WallTime started = ros::WallTime::now();
  ASSERT_TRUE(spinUntil([&] { return scans_.back() > silent; }, 20.0)) << "the world waited past the timeout";
  EXPECT_GT((ros::WallTime::now() - started).toSec(), 9.0);  // ~lockstep_timeout is 10 s
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_simulator_lockstep");
  return RUN_ALL_TESTS();
}
