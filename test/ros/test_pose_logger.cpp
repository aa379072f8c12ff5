// rostest: pose_logger (test/pose_logger.test) logs tf map -> base_link and the simulator's true pose every 0.1 s
// of simulated time, in the pose-log format the door translation reads.
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/pose_log.h"
#include "hidden_rooms/ros/pose_logger.h"

namespace {

TEST(PoseLogger, LogsTheEstimateAndTheTruthEveryPeriod) {
  ros::NodeHandle nh;
  std::string log_dir;
  ASSERT_TRUE(nh.getParam("log_dir", log_dir));
  nav_msgs::Odometry::ConstPtr truth;
  ros::Subscriber truth_subscriber = nh.subscribe<nav_msgs::Odometry>(
      "base_pose_ground_truth", 10, [&truth](const nav_msgs::Odometry::ConstPtr& message) { truth = message; });
  ros::Publisher command_publisher = nh.advertise<geometry_msgs::Twist>("cmd_vel", 10);

  // Both logs have a pose once the logger runs (on a loaded machine it may start well after the simulator).
  const auto logging = [&log_dir] {
    for (const char* name : {"/poses_map.log", "/poses_truth.log"}) {
      try {
        if (hidden_rooms::common::loadPoseLog(log_dir + name).poses.empty()) return false;
      } catch (const std::exception&) {
        return false;  // not written yet
      }
    }
    return true;
  };
  // From the first true pose received once the logger runs: drive 1.5 m at 0.5 m/s, then stand for 2 s of
  // simulated time.
  double start_time = -1.0;
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while ((start_time < 0.0 || truth->header.stamp.toSec() < start_time + 5.0) && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    if (truth != nullptr && start_time < 0.0 && logging()) start_time = truth->header.stamp.toSec();
    geometry_msgs::Twist command;
    if (truth != nullptr && truth->header.stamp.toSec() < start_time + 3.0) command.linear.x = 0.5;
    command_publisher.publish(command);
    ros::WallDuration(0.01).sleep();
  }
  ASSERT_NE(truth, nullptr) << "no ground truth from the simulator";
  ASSERT_GE(start_time, 0.0) << "the logger wrote no poses";
  ASSERT_GE(truth->header.stamp.toSec(), start_time + 5.0) << "simulated time did not advance";

  const hidden_rooms::common::PoseLog estimate = hidden_rooms::common::loadPoseLog(log_dir + "/poses_map.log");
  const hidden_rooms::common::PoseLog ground_truth = hidden_rooms::common::loadPoseLog(log_dir + "/poses_truth.log");
  EXPECT_EQ(estimate.parent_frame, "map");
  EXPECT_EQ(estimate.child_frame, "base_link");
  EXPECT_EQ(ground_truth.parent_frame, "world");
  // One pose per 0.1 s, over the 5 s since the start (the estimate waits for tf a little).
  for (const hidden_rooms::common::PoseLog* log : {&estimate, &ground_truth}) {
    ASSERT_GE(log->poses.back().time - log->poses.front().time, 4.5);
    ASSERT_GE(log->poses.size(), 45u);
    for (size_t k = 1; k < log->poses.size(); ++k) {
      const double step = log->poses[k].time - log->poses[k - 1].time;
      EXPECT_GT(step, 0.099 - 1e-6);
      EXPECT_LT(step, 0.21);
    }
  }
  // The estimate is the odometry seen from a map frame shifted against odom: over the drive, both logs move by
  // the same 1.5 m (up to the odometry drift).
  const auto displacement = [start_time](const hidden_rooms::common::PoseLog& log) {
    const hidden_rooms::common::Pose2 before = hidden_rooms::common::poseAt(log.poses, start_time);
    const hidden_rooms::common::Pose2 after = log.poses.back().pose;
    return std::hypot(after.x - before.x, after.y - before.y);
  };
  EXPECT_NEAR(displacement(ground_truth), 1.5, 0.3);
  EXPECT_NEAR(displacement(estimate), displacement(ground_truth), 0.1);
}

// Spins until `seconds` more of simulated time have passed (or 30 s of wall time).
void spinSimulated(double seconds) {
  const ros::Time until = ros::Time::now() + ros::Duration(seconds);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (ros::Time::now() < until && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
}

int headerCount(const std::string& path) {
  const std::string text = hidden_rooms::common::readTextFile(path, "log");
  int count = 0;
  for (size_t at = text.find("# frame:"); at != std::string::npos; at = text.find("# frame:", at + 1)) ++count;
  return count;
}

// A respawned logger (exploration_run.launch) continues its logs: run in this process twice with `append`, the
// first run's last lines cut as a kill during a write leaves them.
TEST(PoseLogger, ARestartedLoggerContinuesItsLogs) {
  std::string log_dir;
  ASSERT_TRUE(ros::NodeHandle().getParam("log_dir", log_dir));
  hidden_rooms::PoseLoggerOptions options;
  options.estimate_log = log_dir + "/restart/poses_map.log";
  options.ground_truth_log = log_dir + "/restart/poses_truth.log";
  options.append = true;
  std::filesystem::remove_all(log_dir + "/restart");
  ASSERT_GT(ros::Time::now().toSec(), 0.0) << "no simulated time";
  {
    hidden_rooms::PoseLogger logger(ros::NodeHandle(), options);
    spinSimulated(4.0);
    ASSERT_GT(logger.estimatesLogged(), 5);
    ASSERT_GT(logger.groundTruthLogged(), 5);
  }
  for (const std::string& path : {options.estimate_log, options.ground_truth_log})
    std::ofstream(path, std::ios::app) << "99999.0000 1.2";  // cut by the kill
  const double restart = ros::Time::now().toSec();
  spinSimulated(1.0);  // the respawn delay
  {
    hidden_rooms::PoseLogger logger(ros::NodeHandle(), options);
    spinSimulated(4.0);
    ASSERT_GT(logger.estimatesLogged(), 5);
  }
  for (const std::string& path : {options.estimate_log, options.ground_truth_log}) {
    hidden_rooms::common::PoseLog log;
    ASSERT_NO_THROW(log = hidden_rooms::common::loadPoseLog(path)) << path;  // times increase, no cut line
    EXPECT_EQ(headerCount(path), 1) << path;
    ASSERT_GE(log.poses.size(), 20u) << path;
    size_t before = 0, after = 0;
    for (const hidden_rooms::common::TimedPose& pose : log.poses) (pose.time < restart ? before : after) += 1;
    EXPECT_GE(before, 10u) << path << ": the first run's poses";
    EXPECT_GE(after, 10u) << path << ": the second run's poses";
  }
  EXPECT_EQ(hidden_rooms::common::loadPoseLog(options.ground_truth_log).parent_frame, "world");
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_pose_logger");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
