// toMrptScan (mrpt-ros1bridge): beam order, directions, invalid beams and bad messages.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <mrpt/poses/CPose3D.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/ros/conversions.h"
#include "ros/mrpt_scan.h"

namespace hidden_rooms {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The simulator's laser: 1081 beams over 270 degrees, beam k at range 1 + k / 1000 m.
sensor_msgs::LaserScan simulatorScan() {
  sensor_msgs::LaserScan scan;
  scan.header.frame_id = "base_laser_link";
  scan.angle_min = static_cast<float>(-0.75 * kPi);
  scan.angle_increment = static_cast<float>(1.5 * kPi / 1080);
  scan.angle_max = scan.angle_min + 1080 * scan.angle_increment;
  scan.range_min = 0.02f;
  scan.range_max = 30.0f;
  for (int k = 0; k < 1081; ++k) scan.ranges.push_back(1.0f + 0.001f * k);
  return scan;
}

// Direction (world frame, sensor at `sensor`) of MRPT beam i.
double beamDirection(const mrpt::obs::CObservation2DRangeScan& scan, size_t i) {
  const double step = scan.aperture / static_cast<double>(scan.getScanSize() - 1);
  return scan.sensorPose.yaw() - 0.5 * scan.aperture + step * static_cast<double>(i);
}

TEST(MrptScan, KeepsEveryBeamAtItsDirection) {
  const sensor_msgs::LaserScan message = simulatorScan();
  const mrpt::obs::CObservation2DRangeScan scan = toMrptScan(message, common::Pose2{0.2, 0.0, 0.0});
  ASSERT_EQ(scan.getScanSize(), 1081u);
  EXPECT_NEAR(scan.sensorPose.x(), 0.2, 1e-9);
  EXPECT_FLOAT_EQ(scan.maxRange, 30.0f);
  int wrong = 0;
  for (size_t i = 0; i < 1081; ++i) {
    wrong += scan.getScanRange(i) != message.ranges[i];
    EXPECT_TRUE(scan.getScanRangeValidity(i));
    EXPECT_NEAR(beamDirection(scan, i), message.angle_min + message.angle_increment * i, 1e-5);
  }
  EXPECT_EQ(wrong, 0) << "beams taken from a neighbour";
}

TEST(MrptScan, AsymmetricAndClockwiseScansKeepTheirDirections) {
  sensor_msgs::LaserScan message;
  message.angle_min = 0.1f;
  message.angle_increment = 0.01f;
  message.range_max = 10.0f;
  message.ranges = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f};
  const auto forward = toMrptScan(message, common::Pose2{0.0, 0.0, 0.5});
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_FLOAT_EQ(forward.getScanRange(i), message.ranges[i]);
    EXPECT_NEAR(beamDirection(forward, i), 0.5 + 0.1 + 0.01 * i, 1e-6);
  }
  // The same beams listed clockwise: same directions, same ranges.
  message.angle_min = 0.14f;
  message.angle_increment = -0.01f;
  message.ranges = {5.0f, 4.0f, 3.0f, 2.0f, 1.0f};
  const auto backward = toMrptScan(message, common::Pose2{0.0, 0.0, 0.5});
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_FLOAT_EQ(backward.getScanRange(i), forward.getScanRange(i));
    EXPECT_NEAR(beamDirection(backward, i), beamDirection(forward, i), 1e-6);
  }
}

TEST(MrptScan, NanInfinityAndOutOfRangeBeamsAreInvalid) {
  sensor_msgs::LaserScan message = simulatorScan();
  message.ranges[10] = std::numeric_limits<float>::quiet_NaN();
  message.ranges[11] = std::numeric_limits<float>::infinity();
  message.ranges[12] = -std::numeric_limits<float>::infinity();
  message.ranges[13] = 0.01f;   // below range_min
  message.ranges[14] = 30.0f;   // no return
  const auto scan = toMrptScan(message, common::Pose2{});
  for (size_t i = 10; i <= 14; ++i) {
    EXPECT_FALSE(scan.getScanRangeValidity(i)) << i;
    EXPECT_TRUE(std::isfinite(scan.getScanRange(i))) << i;
  }
  EXPECT_TRUE(scan.getScanRangeValidity(15));
  EXPECT_EQ(countValidRanges(message), message.ranges.size() - 5);
  // A scan of nothing but such beams has no valid range (the mapper ignores it).
  for (size_t i = 0; i < message.ranges.size(); ++i) message.ranges[i] = message.ranges[10 + i % 5];
  EXPECT_EQ(countValidRanges(message), 0u);
}

// A laser hanging upside down (its mount rolled by pi, here also yawed by 90 degrees): its beams sweep clockwise seen
// from above, so the upright scan negates and reverses them, and the mount keeps its yaw.
TEST(MrptScan, AnUpsideDownLaserIsTurnedUpright) {
  geometry_msgs::Transform transform;
  transform.translation.x = 0.2;
  const double half = M_PI / 4;  // yaw 90 degrees times roll 180 degrees
  transform.rotation.w = 0.0;
  transform.rotation.x = std::cos(half);
  transform.rotation.y = std::sin(half);
  transform.rotation.z = 0.0;
  const LaserMount mount = laserMountFromRos(transform);
  EXPECT_TRUE(mount.upside_down);
  EXPECT_NEAR(mount.pose.yaw, M_PI / 2, 1e-9);
  EXPECT_NEAR(mount.pose.x, 0.2, 1e-12);
  sensor_msgs::LaserScan scan;
  scan.angle_min = -0.5f;
  scan.angle_max = 1.0f;
  scan.angle_increment = 0.5f;
  scan.ranges = {1.0f, 2.0f, 3.0f, 4.0f};
  const sensor_msgs::LaserScan upright = uprightScan(scan, mount);
  EXPECT_FLOAT_EQ(upright.angle_min, -1.0f);
  EXPECT_FLOAT_EQ(upright.angle_max, 0.5f);
  EXPECT_EQ(upright.ranges, (std::vector<float>{4.0f, 3.0f, 2.0f, 1.0f}));
  // Right way up: unchanged.
  transform.rotation.w = std::cos(half);
  transform.rotation.x = 0.0;
  transform.rotation.y = 0.0;
  transform.rotation.z = std::sin(half);
  EXPECT_FALSE(laserMountFromRos(transform).upside_down);
  EXPECT_EQ(uprightScan(scan, laserMountFromRos(transform)).ranges, scan.ranges);
}

TEST(MrptScan, BadMessagesGiveClearErrors) {
  sensor_msgs::LaserScan message = simulatorScan();
  message.ranges.resize(1);
  EXPECT_THROW(toMrptScan(message, common::Pose2{}), common::InputError);
  message = simulatorScan();
  message.angle_increment = 0.0f;
  EXPECT_THROW(toMrptScan(message, common::Pose2{}), common::InputError);
  message = simulatorScan();
  message.range_max = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(toMrptScan(message, common::Pose2{}), common::InputError);
  EXPECT_THROW(toMrptScan(simulatorScan(), common::Pose2{std::nan(""), 0.0, 0.0}), common::InputError);
}

}  // namespace
}  // namespace hidden_rooms
