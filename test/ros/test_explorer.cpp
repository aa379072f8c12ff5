// rostest: simulator + mapper + explorer explore a world to completion (test/explorer.test). Checks the latched
// exploration_done, the coverage of the reachable free area (the rendered ground truth's free cells connected to
// the start, 4-connected) by the map's free cells (aligned by the ground-truth and map poses at the end), that
// the robot's footprint never touched a wall of the ground truth, and that it never stood still for long before
// done. Prints one line of figures ("explorer_figures: ...") and writes them to ~figures_file when set.
//
// Private parameters: ~world (environment XML, as the simulator's), ~closed_doors, ~wall_time_limit (seconds),
// ~min_coverage (fraction), ~clearance_resolution (metres per cell of the walls the footprint is checked against), ~max_stall (seconds of simulated time), ~footprint_length, ~footprint_width,
// ~map_frame, ~base_frame, ~figures_file, ~map_prefix (saves the final map there, with the alignment).
#include <cmath>
#include <fstream>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <opencv2/imgproc.hpp>
#include <ros/ros.h>
#include <std_msgs/Bool.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "hidden_rooms/common/range_scan.h"
#include "hidden_rooms/evaluation/map_quality.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

namespace hidden_rooms {
namespace {

struct Figures {
  bool done = false;
  double coverage = 0.0;
  long long reachable_cells = 0;
  double sim_seconds = 0.0;
  double wall_seconds = 0.0;
  double path_length = 0.0;
  double min_clearance = 1e9;  // metres between the footprint and the nearest wall cell (less half a cell), fine grid
  double longest_stall = 0.0;  // simulated seconds without moving 0.05 m or turning 0.15 rad
  common::Pose2 closest_pose;  // world frame pose where min_clearance was reached, and when
  double closest_time = 0.0;
};

class ExplorerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle private_nh("~");
    ASSERT_TRUE(private_nh.getParam("world", world_)) << "~world not set";
    private_nh.param("closed_doors", closed_doors_, closed_doors_);
    private_nh.param("wall_time_limit", wall_time_limit_, wall_time_limit_);
    private_nh.param("min_coverage", min_coverage_, min_coverage_);
    private_nh.param("max_stall", max_stall_, max_stall_);
    private_nh.param("footprint_length", footprint_length_, footprint_length_);
    private_nh.param("footprint_width", footprint_width_, footprint_width_);
    private_nh.param("map_frame", map_frame_, map_frame_);
    private_nh.param("base_frame", base_frame_, base_frame_);
    private_nh.param("figures_file", figures_file_, figures_file_);
    private_nh.param("map_prefix", map_prefix_, map_prefix_);

    private_nh.param("clearance_resolution", clearance_resolution_, clearance_resolution_);

    const world::Environment environment = world::loadEnvironment(world_);
    const std::set<int> closed = world::parseDoorSelection(environment, closed_doors_, "~closed_doors");
    truth_ = world::renderEnvironment(environment, closed).map;
    // Walls rasterized finer for the clearance (the 5 cm rendering's cells stick out of the walls by up to a cell).
    world::RenderOptions fine;
    fine.resolution = clearance_resolution_;
    fine_truth_ = world::renderEnvironment(environment, closed, fine).map;
    cv::Mat1b not_wall = (fine_truth_.cells < 65);
    cv::distanceTransform(not_wall, wall_distance_, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    wall_distance_ *= static_cast<float>(fine_truth_.resolution);

    done_subscriber_ = nh_.subscribe<std_msgs::Bool>("exploration_done", 1, [this](const std_msgs::Bool::ConstPtr& m) {
      done_ = m->data;
    });
    map_subscriber_ = nh_.subscribe<nav_msgs::OccupancyGrid>("map", 1, [this](const nav_msgs::OccupancyGrid::ConstPtr& m) {
      map_ = m;
    });
    truth_subscriber_ = nh_.subscribe<nav_msgs::Odometry>("base_pose_ground_truth", 100,
                                                         [this](const nav_msgs::Odometry::ConstPtr& m) { onTruth(*m); });
  }

  void onTruth(const nav_msgs::Odometry& message) {
    const common::Pose2 pose = fromRos(message.pose.pose);
    const double time = message.header.stamp.toSec();
    if (!truth_pose_) {
      start_ = pose;
      stall_anchor_ = pose;
      stall_anchor_time_ = time;
    } else {
      figures_.path_length += std::hypot(pose.x - truth_pose_->x, pose.y - truth_pose_->y);
    }
    truth_pose_ = pose;
    truth_stamp_ = message.header.stamp;
    // Footprint clearance: its outline sampled every 2 cm against the distance to the nearest wall cell centre.
    const double half_length = 0.5 * footprint_length_, half_width = 0.5 * footprint_width_;
    const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
    const auto check = [&](double x, double y) {
      int col = 0, row = 0;
      if (!fine_truth_.cellOf(common::Point2(pose.x + c * x - s * y, pose.y + s * x + c * y), &col, &row)) return;
      const double clearance = wall_distance_(row, col) - 0.5 * fine_truth_.resolution;
      if (clearance < figures_.min_clearance) {
        figures_.min_clearance = clearance;
        figures_.closest_pose = pose;
        figures_.closest_time = time;
      }
    };
    for (double x = -half_length; x <= half_length + 1e-9; x += 0.02) {
      check(x, half_width);
      check(x, -half_width);
    }
    for (double y = -half_width; y <= half_width + 1e-9; y += 0.02) {
      check(half_length, y);
      check(-half_length, y);
    }
    // Stall: standing still before done.
    if (std::hypot(pose.x - stall_anchor_.x, pose.y - stall_anchor_.y) > 0.05 ||
        std::abs(std::remainder(pose.yaw - stall_anchor_.yaw, 2.0 * M_PI)) > 0.15 || done_) {
      stall_anchor_ = pose;
      stall_anchor_time_ = time;
    }
    figures_.longest_stall = std::max(figures_.longest_stall, time - stall_anchor_time_);
  }

  // Coverage of the reachable free area at the end: world_from_map from the latest ground-truth pose and the
  // map -> base transform at its stamp.
  void measureCoverage() {
    ASSERT_TRUE(map_ != nullptr) << "no map";
    ASSERT_TRUE(truth_pose_.has_value()) << "no ground truth";
    tf2_ros::Buffer& buffer = *tf_buffer_;
    geometry_msgs::TransformStamped map_pose;
    ASSERT_NO_THROW(map_pose = buffer.lookupTransform(map_frame_, base_frame_, truth_stamp_, ros::Duration(5.0)));
    const common::Pose2 world_from_map =
        common::composePoses(*truth_pose_, common::invertPose(fromRos(map_pose.transform)));

    int col = 0, row = 0;
    ASSERT_TRUE(truth_.cellOf(common::Point2(start_.x, start_.y), &col, &row));
    cv::Mat1b free_cells = (truth_.cells == common::OccupancyGrid::kFree);
    cv::Mat1b mask = cv::Mat1b::zeros(truth_.height() + 2, truth_.width() + 2);
    ASSERT_NE(free_cells(row, col), 0) << "the start is not on a free cell of the rendering";
    cv::floodFill(free_cells, mask, cv::Point(col, row), 128, nullptr, 0, 0, 4 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
    const cv::Mat1b reachable = mask(cv::Rect(1, 1, truth_.width(), truth_.height())).clone();
    const common::OccupancyGrid map = fromRos(*map_);
    if (!map_prefix_.empty()) {
      common::saveMap(map, map_prefix_);
      std::ofstream(map_prefix_ + "_world_from_map.txt")
          << world_from_map.x << " " << world_from_map.y << " " << world_from_map.yaw << "\n";
    }
    const evaluation::MapQuality quality = evaluation::evaluateMap(map, world_from_map, truth_, reachable);
    figures_.reachable_cells = quality.true_free_cells;
    figures_.coverage = quality.true_free_cells > 0
                            ? static_cast<double>(quality.intersection_cells) / quality.true_free_cells
                            : 0.0;
  }

  ros::NodeHandle nh_;
  std::string world_, closed_doors_, figures_file_, map_prefix_;
  std::string map_frame_ = "map", base_frame_ = "base_link";
  double wall_time_limit_ = 150.0, min_coverage_ = 0.95, max_stall_ = 30.0;
  double footprint_length_ = 0.626, footprint_width_ = 0.505;
  double clearance_resolution_ = 0.01;
  common::OccupancyGrid truth_, fine_truth_;
  cv::Mat1f wall_distance_;
  bool done_ = false;
  nav_msgs::OccupancyGrid::ConstPtr map_;
  std::optional<common::Pose2> truth_pose_;
  ros::Time truth_stamp_;
  common::Pose2 start_, stall_anchor_;
  double stall_anchor_time_ = 0.0;
  Figures figures_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_ = std::make_unique<tf2_ros::Buffer>(ros::Duration(60.0));
  tf2_ros::TransformListener tf_listener_{*tf_buffer_};
  ros::Subscriber done_subscriber_, map_subscriber_, truth_subscriber_;
};

TEST_F(ExplorerTest, ExploresToCompletionWithoutCollision) {
  const ros::WallTime start = ros::WallTime::now();
  const ros::WallTime deadline = start + ros::WallDuration(wall_time_limit_);
  while (ros::WallTime::now() < deadline && !done_) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  figures_.done = done_;
  figures_.wall_seconds = (ros::WallTime::now() - start).toSec();
  figures_.sim_seconds = ros::Time::now().toSec();
  // Let the last map arrive (the mapper publishes every 2 s of simulated time).
  const ros::Time settle = ros::Time::now() + ros::Duration(2.5);
  const ros::WallTime settle_deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  while (ros::Time::now() < settle && ros::WallTime::now() < settle_deadline) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  measureCoverage();

  char line[1024];
  std::snprintf(line, sizeof(line),
                "explorer_figures: world=%s done=%d coverage=%.4f reachable_m2=%.1f sim_s=%.1f wall_s=%.1f "
                "speed=%.2f path_m=%.1f min_clearance_m=%.3f (at %.2f %.2f %.2f, t %.1f) longest_stall_s=%.1f",
                world_.c_str(), figures_.done, figures_.coverage,
                figures_.reachable_cells * truth_.resolution * truth_.resolution, figures_.sim_seconds,
                figures_.wall_seconds, figures_.sim_seconds / std::max(figures_.wall_seconds, 1e-9),
                figures_.path_length, figures_.min_clearance, figures_.closest_pose.x, figures_.closest_pose.y,
                figures_.closest_pose.yaw, figures_.closest_time, figures_.longest_stall);
  std::printf("%s\n", line);
  ROS_INFO("%s", line);
  if (!figures_file_.empty()) std::ofstream(figures_file_) << line << "\n";

  EXPECT_TRUE(figures_.done) << "exploration_done not true within " << wall_time_limit_ << " s";
  EXPECT_GE(figures_.coverage, min_coverage_);
  EXPECT_GT(figures_.min_clearance, 0.0) << "the footprint touched a wall";
  EXPECT_LT(figures_.longest_stall, max_stall_) << "the robot stood still too long";
  EXPECT_GT(figures_.path_length, 1.0);
}

}  // namespace
}  // namespace hidden_rooms

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_explorer");
  return RUN_ALL_TESTS();
}
