// rostest: map_publisher publishes a rendered world, latched, exactly as the core renders it, and serves it.
#include <gtest/gtest.h>
#include <nav_msgs/GetMap.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>

#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

namespace {

hidden_rooms::common::OccupancyGrid expectedMap() {
  std::string environment_path;
  ros::NodeHandle("~").getParam("environment", environment_path);
  const hidden_rooms::world::Environment environment = hidden_rooms::world::loadEnvironment(environment_path);
  return hidden_rooms::world::renderEnvironment(environment, {0, 1})
      .map;  // doors 1 and 2 closed, as in the launch file
}

TEST(MapPublisher, PublishesTheRenderedWorldLatched) {
  ros::NodeHandle nh;
  nav_msgs::OccupancyGrid::ConstPtr map =
      ros::topic::waitForMessage<nav_msgs::OccupancyGrid>("map", nh, ros::Duration(30.0));
  ASSERT_TRUE(map != nullptr) << "no map within 30 s";
  EXPECT_EQ(map->header.frame_id, "map");
  const hidden_rooms::common::OccupancyGrid expected = expectedMap();
  const hidden_rooms::common::OccupancyGrid received = hidden_rooms::fromRos(*map);
  ASSERT_EQ(received.width(), expected.width());
  ASSERT_EQ(received.height(), expected.height());
  EXPECT_NEAR(received.resolution, expected.resolution, 1e-6);
  EXPECT_NEAR(received.origin.x(), expected.origin.x(), 1e-9);
  EXPECT_NEAR(received.origin.y(), expected.origin.y(), 1e-9);
  EXPECT_EQ(cv::countNonZero(received.cells != expected.cells), 0);
  EXPECT_GT(cv::countNonZero(received.cells == hidden_rooms::common::OccupancyGrid::kFree), 1000);
}

TEST(MapPublisher, ServesStaticMap) {
  ros::NodeHandle nh;
  ASSERT_TRUE(ros::service::waitForService("static_map", ros::Duration(30.0)));
  nav_msgs::GetMap service;
  ASSERT_TRUE(ros::service::call("static_map", service));
  EXPECT_EQ(service.response.map.info.width, static_cast<uint32_t>(expectedMap().width()));
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_map_publisher");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
