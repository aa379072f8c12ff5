// rostest of the mapper under faulty scans (test/mapper_faults.test). While the test drives the simulated robot
// with the core's WanderDriver, it relays the simulator's scans to two mappers: /clean/mapper gets them as they
// are, minus the ones replaced below; /faulty/mapper gets the same scans plus bad ones in between: in bursts of
// consecutive scans, a copy with nothing but NaN, infinite or out-of-range ranges in place of the real scan (which
// the clean mapper does not get either); copies of an older scan stamped in the past, and copies stamped seconds
// ahead of the clock, both with valid ranges shrunk to 70% (walls inside the rooms, were they inserted). The
// faulty mapper must ignore every bad scan: it keeps running and publishing, builds exactly the clean mapper's
// map (the same scans and seed give the same map, so any bad scan that reached the filter shows), and warns once
// per kind on rosout.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <hidden_rooms/SaveMap.h>
#include <nav_msgs/OccupancyGrid.h>
#include <opencv2/core.hpp>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/LaserScan.h>

#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/simulation/wander_driver.h"
#include "ros_test_util.h"
#include "test_util.h"

namespace hidden_rooms {
namespace {

constexpr int kBurstLength = 8;                      // consecutive scans replaced by a bad copy
const std::vector<int> kBurstStarts{25, 60, 95, 130};  // relayed scan numbers (10 Hz)
const std::vector<int> kPastCopies{45, 80, 115};       // after these, a copy of the scan 15 before (1.5 s older)
const std::vector<int> kFutureCopies{50, 85, 120};     // after these, a copy stamped ahead of the clock
const std::vector<double> kFutureLeads{3.0, 30.0, 300.0};  // seconds ahead (the mapper tolerates 1 s)

bool contains(const std::vector<int>& list, int value) {
  return std::find(list.begin(), list.end(), value) != list.end();
}

// The ranges of a scan without a valid return: all NaN, all +inf, or a mix of every invalid kind.
std::vector<float> invalidRanges(const sensor_msgs::LaserScan& scan, int kind) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<float> mix{nan, inf, -inf, 0.0f, -1.0f, scan.range_min, scan.range_max, 2.0f * scan.range_max};
  std::vector<float> ranges(scan.ranges.size());
  for (size_t k = 0; k < ranges.size(); ++k) ranges[k] = kind == 0 ? nan : kind == 1 ? inf : mix[k % mix.size()];
  return ranges;
}

sensor_msgs::LaserScan shrunk(const sensor_msgs::LaserScan& scan) {
  sensor_msgs::LaserScan copy = scan;
  for (float& range : copy.ranges) range *= 0.7f;
  return copy;
}

class MapperFaultsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle private_nh("~");
    private_nh.param("drive_seconds", drive_seconds_, drive_seconds_);
    command_publisher_ = nh_.advertise<geometry_msgs::Twist>("/cmd_vel", 10);
    clean_publisher_ = nh_.advertise<sensor_msgs::LaserScan>("/clean/base_scan", 100);
    faulty_publisher_ = nh_.advertise<sensor_msgs::LaserScan>("/faulty/base_scan", 100);
    scan_subscriber_ = nh_.subscribe("/base_scan", 100, &MapperFaultsTest::onScan, this);
    faulty_map_subscriber_ = nh_.subscribe<nav_msgs::OccupancyGrid>(
        "/faulty/map", 1, [this](const nav_msgs::OccupancyGrid::ConstPtr& m) { faulty_map_ = m; });
    rosout_subscriber_ = nh_.subscribe<rosgraph_msgs::Log>(
        "/rosout", 1000, [this](const rosgraph_msgs::Log::ConstPtr& m) { log_.push_back(m); });
  }

  void onScan(const sensor_msgs::LaserScan::ConstPtr& scan) {
    const common::VelocityCommand command =
        driving_ ? driver_.next(scan->ranges, laserGeometryOf(*scan)) : common::VelocityCommand();
    command_publisher_.publish(toRos(command));
    if (relaying_) relay(scan);
  }

  void relay(const sensor_msgs::LaserScan::ConstPtr& scan) {
    const int index = static_cast<int>(relayed_.size());
    relayed_.push_back(scan);
    int burst = -1;
    for (size_t b = 0; b < kBurstStarts.size(); ++b)
      if (index >= kBurstStarts[b] && index < kBurstStarts[b] + kBurstLength) burst = static_cast<int>(b);
    if (burst >= 0) {
      sensor_msgs::LaserScan bad = *scan;
      bad.ranges = invalidRanges(*scan, burst % 3);
      faulty_publisher_.publish(bad);
      ++invalid_sent_;
      last_fault_stamp_ = scan->header.stamp;
      return;
    }
    clean_publisher_.publish(scan);
    faulty_publisher_.publish(scan);
    if (contains(kPastCopies, index)) {
      faulty_publisher_.publish(shrunk(*relayed_[index - 15]));
      ++past_sent_;
      last_fault_stamp_ = scan->header.stamp;
    }
    if (contains(kFutureCopies, index)) {
      sensor_msgs::LaserScan ahead = shrunk(*scan);
      ahead.header.stamp += ros::Duration(kFutureLeads[future_sent_ % kFutureLeads.size()]);
      faulty_publisher_.publish(ahead);
      ++future_sent_;
      last_fault_stamp_ = scan->header.stamp;
    }
  }

  template <typename Condition>
  bool waitFor(Condition condition, double wall_seconds) {
    return testing::spinUntil(condition, wall_seconds);
  }

  double lastRelayedTime() const { return relayed_.empty() ? 0.0 : relayed_.back()->header.stamp.toSec(); }

  // Warnings of `node` on rosout containing `text`.
  int warnings(const std::string& node, const std::string& text) const {
    int count = 0;
    for (const auto& entry : log_)
      count += entry->name == node && entry->level == rosgraph_msgs::Log::WARN &&
               entry->msg.find(text) != std::string::npos;
    return count;
  }

  common::OccupancyGrid savedMap(const std::string& service, const std::string& prefix) {
    hidden_rooms::SaveMap save;
    save.request.prefix = prefix;
    EXPECT_TRUE(ros::service::waitForService(service, ros::Duration(10.0))) << service;
    EXPECT_TRUE(ros::service::call(service, save)) << service;
    EXPECT_TRUE(save.response.success) << service << ": " << save.response.message;
    return save.response.success ? common::loadMap(prefix + ".yaml") : common::OccupancyGrid();
  }

  ros::NodeHandle nh_;
  double drive_seconds_ = 18.0;
  bool driving_ = false;
  bool relaying_ = false;
  simulation::WanderDriver driver_;
  ros::Publisher command_publisher_, clean_publisher_, faulty_publisher_;
  ros::Subscriber scan_subscriber_, faulty_map_subscriber_, rosout_subscriber_;
  std::vector<sensor_msgs::LaserScan::ConstPtr> relayed_;
  int invalid_sent_ = 0, past_sent_ = 0, future_sent_ = 0;
  ros::Time last_fault_stamp_;
  nav_msgs::OccupancyGrid::ConstPtr faulty_map_;
  std::vector<rosgraph_msgs::Log::ConstPtr> log_;
};

TEST_F(MapperFaultsTest, BadScansAreIgnoredAndTheMapIsTheCleanOne) {
  // Both mappers listen before the first scan is relayed, so that they get the same scans.
  ASSERT_TRUE(waitFor([this] {
    return clean_publisher_.getNumSubscribers() > 0 && faulty_publisher_.getNumSubscribers() > 0 &&
           scan_subscriber_.getNumPublishers() > 0;
  }, 30.0)) << "mappers or simulator not up";
  ros::WallDuration(1.0).sleep();  // the mappers' tf listeners fill up
  relaying_ = driving_ = true;
  ASSERT_TRUE(waitFor([this] { return !relayed_.empty(); }, 10.0)) << "no scans";
  const double start = lastRelayedTime();
  ASSERT_TRUE(waitFor([&] { return lastRelayedTime() >= start + drive_seconds_; }, 3.0 * drive_seconds_ + 20.0))
      << "the simulation did not advance " << drive_seconds_ << " s";
  driving_ = false;  // at rest for 2 simulated seconds, then the relay stops: both mappers got the same scans
  const double stop = lastRelayedTime();
  ASSERT_TRUE(waitFor([&] { return lastRelayedTime() >= stop + 2.0; }, 20.0));
  relaying_ = false;
  ASSERT_EQ(invalid_sent_, static_cast<int>(kBurstStarts.size()) * kBurstLength);
  ASSERT_EQ(past_sent_, static_cast<int>(kPastCopies.size()));
  ASSERT_EQ(future_sent_, static_cast<int>(kFutureCopies.size()));
  waitFor([] { return false; }, 3.0);  // the last scans wait for their odometry

  // (a) the faulty mapper still runs and kept publishing after the last bad scan.
  ASSERT_NE(faulty_map_, nullptr) << "no map from /faulty/mapper";
  EXPECT_GT(faulty_map_->header.stamp.toSec(), last_fault_stamp_.toSec() + 2.0)
      << "the faulty mapper stopped publishing after the bad scans";

  // (b) its map is the clean mapper's, cell for cell.
  const std::string dir = testing::makeTempDir("mapper_faults");
  const common::OccupancyGrid clean = savedMap("/clean/save_map", dir + "/clean");
  const common::OccupancyGrid faulty = savedMap("/faulty/save_map", dir + "/faulty");
  ASSERT_FALSE(clean.empty());
  ASSERT_FALSE(faulty.empty());
  EXPECT_GT(cv::countNonZero(clean.cells == common::OccupancyGrid::kFree), 1000);
  EXPECT_GT(cv::countNonZero(clean.cells == common::OccupancyGrid::kOccupied), 100);
  ASSERT_EQ(faulty.cells.size(), clean.cells.size()) << "the maps differ in size";
  EXPECT_DOUBLE_EQ(faulty.origin.x(), clean.origin.x());
  EXPECT_DOUBLE_EQ(faulty.origin.y(), clean.origin.y());
  const int different = cv::countNonZero(faulty.cells != clean.cells);
  std::printf("relayed %zu scans, %d invalid, %d past, %d future; cells %d x %d, %d differ\n", relayed_.size(),
              invalid_sent_, past_sent_, future_sent_, clean.width(), clean.height(), different);
  EXPECT_EQ(different, 0) << "bad scans changed the map";

  // (c) one warning per kind (throttled) from the faulty mapper, none from the clean one.
  ros::spinOnce();
  EXPECT_GE(warnings("/faulty/mapper", "has no valid range"), 1);
  EXPECT_GE(warnings("/faulty/mapper", "before the last one"), 1);
  EXPECT_GE(warnings("/faulty/mapper", "ahead of ROS time"), 1);
  EXPECT_EQ(warnings("/clean/mapper", "ignored"), 0);
}

}  // namespace
}  // namespace hidden_rooms

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_mapper_faults");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
