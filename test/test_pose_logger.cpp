// rostest: pose_logger (test/pose_logger.test) logs tf map -> base_link and the simulator's true pose every 0.1 s
// of simulated time, in the pose-log format the door translation reads.
#include <cmath>
#include <string>

#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include "hidden_rooms/pose_log.h"

namespace {

TEST(PoseLogger, LogsTheEstimateAndTheTruthEveryPeriod) {
  ros::NodeHandle nh;
  std::string log_dir;
  ASSERT_TRUE(nh.getParam("log_dir", log_dir));
  nav_msgs::Odometry::ConstPtr truth;
  ros::Subscriber truth_subscriber = nh.subscribe<nav_msgs::Odometry>(
      "base_pose_ground_truth", 10, [&truth](const nav_msgs::Odometry::ConstPtr& message) { truth = message; });
  ros::Publisher command_publisher = nh.advertise<geometry_msgs::Twist>("cmd_vel", 10);

  // From the first true pose received: drive 1.5 m at 0.5 m/s, then stand for 2 s of simulated time.
  double start_time = -1.0;
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while ((start_time < 0.0 || truth->header.stamp.toSec() < start_time + 5.0) && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    if (truth != nullptr && start_time < 0.0) start_time = truth->header.stamp.toSec();
    geometry_msgs::Twist command;
    if (truth != nullptr && truth->header.stamp.toSec() < start_time + 3.0) command.linear.x = 0.5;
    command_publisher.publish(command);
    ros::WallDuration(0.01).sleep();
  }
  ASSERT_NE(truth, nullptr) << "no ground truth from the simulator";
  ASSERT_GE(truth->header.stamp.toSec(), start_time + 5.0) << "simulated time did not advance";

  const hidden_rooms::PoseLog estimate = hidden_rooms::loadPoseLog(log_dir + "/poses_map.log");
  const hidden_rooms::PoseLog ground_truth = hidden_rooms::loadPoseLog(log_dir + "/poses_truth.log");
  EXPECT_EQ(estimate.parent_frame, "map");
  EXPECT_EQ(estimate.child_frame, "base_link");
  EXPECT_EQ(ground_truth.parent_frame, "world");
  // About one pose per 0.1 s (the logger may start a little after the simulator).
  for (const hidden_rooms::PoseLog* log : {&estimate, &ground_truth}) {
    ASSERT_GE(log->poses.size(), 50u);
    for (size_t k = 1; k < log->poses.size(); ++k) {
      const double step = log->poses[k].time - log->poses[k - 1].time;
      EXPECT_GT(step, 0.099 - 1e-6);
      EXPECT_LT(step, 0.21);
    }
  }
  // The estimate is the odometry seen from a map frame shifted against odom: over the drive, both logs move by
  // the same 1.5 m (up to the odometry drift).
  const auto displacement = [start_time](const hidden_rooms::PoseLog& log) {
    const hidden_rooms::Pose2 before = hidden_rooms::poseAt(log.poses, start_time);
    const hidden_rooms::Pose2 after = log.poses.back().pose;
    return std::hypot(after.x - before.x, after.y - before.y);
  };
  EXPECT_NEAR(displacement(ground_truth), 1.5, 0.3);
  EXPECT_NEAR(displacement(estimate), displacement(ground_truth), 0.1);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_pose_logger");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
