// rostest: the simulator node in a known world (test/simulator.test): publication rates, ranges equal to the
// analytic distances (within the noise), set_door changes the scan, the robot stops at a closed door, drives
// through the opened one and stops at the wall behind it, reset puts it back.
#include <cmath>
#include <string>
#include <vector>

#include <geometry_msgs/PolygonStamped.h>
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <hidden_rooms/SetDoor.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <std_srvs/Trigger.h>

#include "ros_test_util.h"

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHalfLength = 0.313;  // Pioneer 3-AT footprint / 2
constexpr double kNoise = 0.05;        // 5 sigma of the laser noise

class SimulatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scan_subscriber_ = nh_.subscribe<sensor_msgs::LaserScan>("base_scan", 100, [this](const sensor_msgs::LaserScan::ConstPtr& m) {
      scans_.push_back(m);
    });
    odom_subscriber_ = nh_.subscribe<nav_msgs::Odometry>("odom", 100, [this](const nav_msgs::Odometry::ConstPtr& m) {
      odom_.push_back(m);
    });
    footprint_subscriber_ = nh_.subscribe<geometry_msgs::PolygonStamped>(
        "footprint", 100, [this](const geometry_msgs::PolygonStamped::ConstPtr& m) { footprints_.push_back(m); });
    truth_subscriber_ = nh_.subscribe<nav_msgs::Odometry>("base_pose_ground_truth", 100,
                                                         [this](const nav_msgs::Odometry::ConstPtr& m) { truth_ = m; });
    command_publisher_ = nh_.advertise<geometry_msgs::Twist>("cmd_vel", 10);
    ASSERT_TRUE(ros::service::waitForService("set_door", ros::Duration(30.0)));
    ASSERT_TRUE(waitFor([this] { return truth_ != nullptr && !scans_.empty(); }, 30.0)) << "no messages";
  }

  template <typename Condition>
  bool waitFor(Condition condition, double wall_seconds, const geometry_msgs::Twist* command = nullptr) {
    return hidden_rooms::testing::spinUntil(condition, wall_seconds, [&] {
      if (command != nullptr) command_publisher_.publish(*command);
    }, 0.01);
  }

  // Publishes `linear` m/s for `seconds` of simulated time (ground-truth stamps).
  void drive(double linear, double seconds) {
    geometry_msgs::Twist command;
    command.linear.x = linear;
    const double until = truth_->header.stamp.toSec() + seconds;
    ASSERT_TRUE(waitFor([&] { return truth_->header.stamp.toSec() >= until; }, 60.0, &command));
    geometry_msgs::Twist stop;
    command_publisher_.publish(stop);
  }

  // A scan surely taken after the last service call: messages already queued are drained first, then the scan
  // must come a few laser periods after the newest ground truth.
  sensor_msgs::LaserScan::ConstPtr freshScan() {
    waitFor([] { return false; }, 0.1);
    const double after = truth_->header.stamp.toSec();
    scans_.clear();
    waitFor([&] { return !scans_.empty() && scans_.back()->header.stamp.toSec() > after + 0.3; }, 30.0);
    return scans_.empty() ? nullptr : scans_.back();
  }

  static float beamAt(const sensor_msgs::LaserScan& scan, double angle) {
    return scan.ranges.at(static_cast<size_t>(std::lround((angle - scan.angle_min) / scan.angle_increment)));
  }

  bool setDoor(const std::string& door, bool open, std::string* message = nullptr) {
    hidden_rooms::SetDoor service;
    service.request.door = door;
    service.request.open = open;
    EXPECT_TRUE(ros::service::call("set_door", service));
    if (message != nullptr) *message = service.response.message;
    return service.response.success;
  }

  ros::NodeHandle nh_;
  ros::Subscriber scan_subscriber_, odom_subscriber_, truth_subscriber_, footprint_subscriber_;
  ros::Publisher command_publisher_;
  std::vector<sensor_msgs::LaserScan::ConstPtr> scans_;
  std::vector<nav_msgs::Odometry::ConstPtr> odom_;
  std::vector<geometry_msgs::PolygonStamped::ConstPtr> footprints_;
  nav_msgs::Odometry::ConstPtr truth_;
};

TEST_F(SimulatorTest, PublishesAtItsRatesOnSimulatedTime) {
  scans_.clear();
  odom_.clear();
  footprints_.clear();
  ASSERT_TRUE(waitFor([&] {
    return scans_.size() >= 2 && scans_.back()->header.stamp.toSec() - scans_.front()->header.stamp.toSec() >= 3.0;
  }, 30.0));
  const double scan_span = scans_.back()->header.stamp.toSec() - scans_.front()->header.stamp.toSec();
  const double odom_span = odom_.back()->header.stamp.toSec() - odom_.front()->header.stamp.toSec();
  EXPECT_NEAR((scans_.size() - 1) / scan_span, 10.0, 0.5);
  EXPECT_NEAR((odom_.size() - 1) / odom_span, 20.0, 1.0);
  const sensor_msgs::LaserScan& scan = *scans_.back();
  EXPECT_EQ(scan.header.frame_id, "base_laser_link");
  EXPECT_EQ(scan.ranges.size(), 1081u);
  EXPECT_NEAR(scan.angle_max - scan.angle_min, 1.5 * kPi, 1e-4);
  EXPECT_FLOAT_EQ(scan.range_max, 30.0f);
  EXPECT_EQ(odom_.back()->header.frame_id, "odom");
  EXPECT_EQ(odom_.back()->child_frame_id, "base_link");
  EXPECT_EQ(truth_->header.frame_id, "world");
  EXPECT_GT(ros::Time::now().toSec(), 0.0);  // /clock drives this node's time
  // The footprint comes with each odometry message and its stamp (rviz places it at that stamp's pose).
  ASSERT_GE(footprints_.size(), 2u);
  EXPECT_GT(footprints_.back()->header.stamp, footprints_.front()->header.stamp);
  EXPECT_EQ(footprints_.back()->header.frame_id, "base_link");
  EXPECT_EQ(footprints_.back()->polygon.points.size(), 4u);
}

TEST_F(SimulatorTest, RangesEqualAnalyticDistancesAndSetDoorChangesTheScan) {
  // Robot at (2, 5.2) facing -y; laser 0.2 m ahead at (2, 5).
  sensor_msgs::LaserScan::ConstPtr scan = freshScan();
  ASSERT_TRUE(scan != nullptr);
  EXPECT_NEAR(beamAt(*scan, 0.0), 5.0 - 4.075, kNoise);           // closed door 1
  EXPECT_NEAR(beamAt(*scan, kPi / 2), 9.925 - 2.0, kNoise);       // east end of the corridor
  EXPECT_NEAR(beamAt(*scan, -kPi / 2), 2.0 - 0.075, kNoise);      // west end
  ASSERT_TRUE(setDoor("door_a", true));
  scan = freshScan();
  ASSERT_TRUE(scan != nullptr);
  EXPECT_NEAR(beamAt(*scan, 0.0), 5.0 - 0.075, kNoise);  // through the door to room A's far wall
  ASSERT_TRUE(setDoor("1", false));
  scan = freshScan();
  ASSERT_TRUE(scan != nullptr);
  EXPECT_NEAR(beamAt(*scan, 0.0), 5.0 - 4.075, kNoise);
  std::string message;
  EXPECT_FALSE(setDoor("no_such_door", true, &message));
  EXPECT_NE(message.find("no_such_door"), std::string::npos) << message;
}

TEST_F(SimulatorTest, StopsAtTheClosedDoorDrivesThroughTheOpenedOneAndResets) {
  drive(0.5, 5.0);
  EXPECT_GT(truth_->pose.pose.position.y, 4.075 + kHalfLength - 0.03);  // stopped at the door
  EXPECT_LT(truth_->pose.pose.position.y, 4.075 + kHalfLength + 0.06);
  ASSERT_TRUE(setDoor("door_a", true));
  drive(0.5, 12.0);
  EXPECT_GT(truth_->pose.pose.position.y, 0.075 + kHalfLength - 0.03);  // through it, stopped at the wall
  EXPECT_LT(truth_->pose.pose.position.y, 0.075 + kHalfLength + 0.06);
  EXPECT_NEAR(truth_->pose.pose.position.x, 2.0, 0.1);
  // Odometry moved about as far (it drifts by at most a few percent).
  ASSERT_FALSE(odom_.empty());
  EXPECT_NEAR(odom_.back()->pose.pose.position.x, 5.2 - truth_->pose.pose.position.y, 0.2);
  std_srvs::Trigger reset;
  ASSERT_TRUE(ros::service::call("reset", reset));
  EXPECT_TRUE(reset.response.success);
  ASSERT_TRUE(waitFor([&] { return std::abs(truth_->pose.pose.position.y - 5.2) < 0.01; }, 10.0));
  ASSERT_TRUE(setDoor("door_a", false));
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_simulator");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
