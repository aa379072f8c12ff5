// RbpfMapper (MRPT's RBPF) on scans of the core simulation: map quality against the rendered ground truth,
// trajectory error, determinism per seed, bad ini files.
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/evaluation/door_translation.h"
#include "hidden_rooms/evaluation/map_quality.h"
#include "hidden_rooms/mapping/rbpf_mapper.h"
#include "hidden_rooms/simulation/simulation.h"
#include "hidden_rooms/simulation/wander_driver.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"
#include "test_util.h"

namespace hidden_rooms::mapping {
namespace {

const std::string kConfig = std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/config/rbpf.ini";
const std::string kRealLaserConfig = std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/config/rbpf_real_laser.ini";

// Odometry that drifts as a real robot's can: 5 % too long and 2 degrees of heading per metre travelled.
class DriftingOdometry {
 public:
  common::Pose2 next(const common::Pose2& odometry) {
    if (!started_) {
      started_ = true;
      last_ = drifted_ = odometry;
      return drifted_;
    }
    common::Pose2 step = common::composePoses(common::invertPose(last_), odometry);
    last_ = odometry;
    const double length = std::hypot(step.x, step.y);
    step.x *= 1.05;
    step.y *= 1.05;
    step.yaw += 2.0 * 3.14159265358979323846 / 180.0 * length;
    drifted_ = common::composePoses(drifted_, step);
    return drifted_;
  }

 private:
  bool started_ = false;
  common::Pose2 last_, drifted_;
};

struct MappingRun {
  common::OccupancyGrid map;
  evaluation::MapQuality quality;
  evaluation::TrajectoryError trajectory;
  int scans = 0;
  int inserted = 0;
  std::vector<RbpfParticle> particles;
  std::vector<common::Pose2> online_poses;  // pose() after each scan
  std::vector<common::Pose2> final_poses;   // trajectory() at the end
};

// Drives the robot (wander) through a world for `seconds` and maps it with scans at 10 Hz, with the mapper's
// ini `config`, from the simulator's odometry or (`drift`) that odometry drifting further; with `map_every`, takes
// the map after every that many scans as well (as the node publishes it).
MappingRun mapWorld(const std::string& world_file, double seconds, uint32_t mapper_seed,
                    const std::string& config = kConfig, bool drift = false, int map_every = 0) {
  const world::Environment environment = world::loadEnvironment(world_file);
  const world::RenderedEnvironment truth = world::renderEnvironment(environment, {});
  simulation::SimulationOptions options;
  options.seed = 3;
  simulation::Simulation simulation(simulation::worldFromEnvironment(environment, {}), options);
  RbpfMapperOptions mapper_options;
  mapper_options.config_file = config;
  mapper_options.seed = mapper_seed;
  DriftingOdometry drifting;
  RbpfMapper mapper(mapper_options);
  simulation::WanderDriver driver;

  common::RangeScan scan;
  const common::LaserGeometry& laser = simulation.laserGeometry();
  scan.angle_min = laser.angle_min;
  scan.angle_increment = laser.angle_increment;
  scan.range_min = options.laser.min_range;
  scan.range_max = laser.max_range;
  scan.sensor_pose = options.laser.mount;
  std::vector<common::Pose2> estimate, true_poses;
  cv::Mat1b observed;
  MappingRun run;
  const int steps = static_cast<int>(std::lround(seconds / options.physics_step));
  for (int k = 1; k <= steps; ++k) {
    simulation.step();
    if (k % 10 != 0) continue;
    simulation.scan(&scan.ranges);
    simulation.setCommand(driver.next(scan.ranges, laser));
    const common::Pose2 odometry = drift ? drifting.next(simulation.odometryPose()) : simulation.odometryPose();
    if (mapper.addScan(odometry, scan))
      evaluation::markObservedCells(truth.map, simulation.laserPose(), scan, &observed);
    estimate.push_back(mapper.pose());
    true_poses.push_back(simulation.truePose());
    ++run.scans;
    if (map_every > 0 && run.scans % map_every == 0) mapper.map();
  }
  // Scored as map_from_bag scores: the map placed in the world by the rigid fit of the whole trajectory as the
  // mapper estimates it at the end (loop closures move earlier poses).
  const std::vector<common::Pose2> final_poses = mapper.trajectory();
  std::vector<common::TimedPose> timed_truth, timed_estimate;
  for (size_t i = 0; i < final_poses.size(); ++i) {
    timed_truth.push_back({static_cast<double>(i), true_poses[i]});
    timed_estimate.push_back({static_cast<double>(i), final_poses[i]});
  }
  const common::Pose2 world_from_map = evaluation::fitWorldFromMap(timed_truth, timed_estimate);
  run.map = mapper.map();
  run.quality = evaluation::evaluateMap(run.map, world_from_map, truth.map, observed);
  run.trajectory = evaluation::trajectoryError(final_poses, true_poses, world_from_map);
  run.inserted = mapper.scansInserted();
  run.particles = mapper.particles();
  run.online_poses = estimate;
  run.final_poses = final_poses;
  return run;
}

// Without loop closure no pose moves once estimated: trajectory() is pose() after each scan.
void expectTrajectoryIsTheOnlinePoses(const MappingRun& run) {
  ASSERT_EQ(run.final_poses.size(), static_cast<size_t>(run.scans));
  for (size_t i = 0; i < run.final_poses.size(); ++i) {
    EXPECT_NEAR(run.final_poses[i].x, run.online_poses[i].x, 1e-9) << "scan " << i;
    EXPECT_NEAR(run.final_poses[i].y, run.online_poses[i].y, 1e-9) << "scan " << i;
    EXPECT_NEAR(run.final_poses[i].yaw, run.online_poses[i].yaw, 1e-9) << "scan " << i;
  }
}

TEST(RbpfMapper, MapsASmallWorldCloseToTheGroundTruth) {
  const MappingRun run = mapWorld(std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/worlds/small_1.xml", 90.0, 1);
  std::printf("scans %d inserted %d free IoU %.3f (true %lld, map %lld) walls within 2 cells %.3f mean %.2f p95 %.2f "
              "RMSE %.3f m yaw %.3f rad max %.3f m\n",
              run.scans, run.inserted, run.quality.free_iou, run.quality.true_free_cells, run.quality.map_free_cells,
              run.quality.walls_within_2_cells, run.quality.wall_distance_mean, run.quality.wall_distance_p95,
              run.trajectory.position_rmse, run.trajectory.yaw_rmse, run.trajectory.position_max);
  EXPECT_GT(run.inserted, 20);
  EXPECT_GE(run.quality.free_iou, 0.85);
  EXPECT_GE(run.quality.walls_within_2_cells, 0.85);
  EXPECT_LT(run.trajectory.position_rmse, 0.25);
  double weights = 0.0;
  for (const RbpfParticle& p : run.particles) weights += p.weight;
  EXPECT_EQ(run.particles.size(), 8u);
  EXPECT_NEAR(weights, 1.0, 1e-9);
  EXPECT_NEAR(run.map.resolution, 0.05, 1e-6);
  expectTrajectoryIsTheOnlinePoses(run);
}

TEST(RbpfMapper, SameScansAndSeedGiveTheSameMap) {
  const std::string world = std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/worlds/small_2.xml";
  const MappingRun a = mapWorld(world, 25.0, 7), b = mapWorld(world, 25.0, 7);
  ASSERT_EQ(a.map.cells.size(), b.map.cells.size());
  EXPECT_EQ(cv::countNonZero(a.map.cells != b.map.cells), 0);
  EXPECT_EQ(a.map.origin, b.map.origin);
}

TEST(RbpfMapper, AMapTakenAtEveryPublicationHasTheCellsOfOneDrawnOnce) {
  // Taken every 2 s, the map is drawn on along the best particle's path, from the copy of its rendering kept behind
  // the newest scans when that path changes; taken once, every scan is drawn along the final path. The grids may
  // have grown differently, but the cells they share are the same and they know the same cells.
  const std::string world = std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/worlds/small_1.xml";
  const MappingRun published = mapWorld(world, 150.0, 1, kConfig, false, 20), once = mapWorld(world, 150.0, 1);
  ASSERT_GT(published.inserted, 120);  // well past the copy's 50 scans
  const common::OccupancyGrid &a = published.map, &b = once.map;
  ASSERT_NEAR(a.resolution, b.resolution, 1e-9);
  const common::Point2 shift = (a.origin - b.origin) / a.resolution;  // a's cell (0, 0) in b's cells
  const int dx = static_cast<int>(std::lround(shift.x())), dy = static_cast<int>(std::lround(shift.y()));
  ASSERT_NEAR(shift.x(), dx, 1e-6);
  ASSERT_NEAR(shift.y(), dy, 1e-6);
  // Rows count from the top: a's row r is b's row r + (b.height - a.height) - dy.
  const int row_shift = b.height() - a.height() - dy;
  const cv::Rect in_b = cv::Rect(dx, row_shift, a.width(), a.height()) & cv::Rect(0, 0, b.width(), b.height());
  const cv::Rect in_a = in_b - cv::Point(dx, row_shift);
  EXPECT_EQ(cv::countNonZero(a.cells(in_a) != b.cells(in_b)), 0);
  EXPECT_EQ(cv::countNonZero(a.cells != common::OccupancyGrid::kUnknown),
            cv::countNonZero(b.cells != common::OccupancyGrid::kUnknown));
}

TEST(RbpfMapper, StartsAtTheFirstOdometryPose) {
  RbpfMapperOptions options;
  options.config_file = kConfig;
  RbpfMapper mapper(options);
  EXPECT_TRUE(mapper.map().empty());
  common::RangeScan scan;
  scan.angle_min = -1.0;
  scan.angle_increment = 0.01;
  scan.range_min = 0.05;
  scan.range_max = 10.0;
  scan.ranges.assign(201, 2.0f);
  EXPECT_TRUE(mapper.addScan({1.0, 2.0, 0.5}, scan));
  const common::Pose2 pose = mapper.pose(), map_to_odom = mapper.mapToOdom();
  // The filter's first step draws the particles around the start (the motion model's minimum noise).
  EXPECT_NEAR(pose.x, 1.0, 0.02);
  EXPECT_NEAR(pose.y, 2.0, 0.02);
  EXPECT_NEAR(pose.yaw, 0.5, 0.02);
  EXPECT_NEAR(map_to_odom.x, 0.0, 0.02);
  EXPECT_NEAR(map_to_odom.yaw, 0.0, 0.02);
  const common::OccupancyGrid map = mapper.map();
  ASSERT_FALSE(map.empty());
  int col = 0, row = 0;
  ASSERT_TRUE(map.cellOf(common::Point2(1.0 + 1.0 * std::cos(0.5), 2.0 + 1.0 * std::sin(0.5)), &col, &row));
  EXPECT_GE(map.cells(row, col), 0);
  EXPECT_LT(map.cells(row, col), 50) << "free in front of the robot";
  ASSERT_TRUE(map.cellOf(common::Point2(1.0 + 2.0 * std::cos(0.5), 2.0 + 2.0 * std::sin(0.5)), &col, &row));
  EXPECT_GT(map.cells(row, col), 50) << "the hit";
  ASSERT_TRUE(map.cellOf(common::Point2(1.0 - 1.0 * std::cos(0.5), 2.0 - 1.0 * std::sin(0.5)), &col, &row));
  EXPECT_EQ(map.cells(row, col), common::OccupancyGrid::kUnknown) << "behind the robot, outside the scan";
  EXPECT_THROW(mapper.addScan({0.0, 0.0, 0.0}, common::RangeScan()), common::InputError);
}

// The real-laser configuration: its scan-matching front-end (and its loop closure, as the wander comes back to
// places it left 20 m before) takes out most of a drifting odometry's error, which the same ini without the
// front-end (one particle following the odometry) keeps. What loop closure is worth shows on the real logs
// (test/python/test_carmen.py).
TEST(RbpfMapper, TheScanMatchingFrontEndCorrectsDriftingOdometry) {
  const std::string world = std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/worlds/small_1.xml";
  std::ifstream in(kRealLaserConfig);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find("enabled = 1");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 11, "enabled = 0");
  const std::string without = testing::makeTempDir("rbpf_front_end") + "/without_front_end.ini";
  std::ofstream(without) << text;
  const MappingRun with_front_end = mapWorld(world, 90.0, 1, kRealLaserConfig, true);
  const MappingRun odometry_only = mapWorld(world, 90.0, 1, without, true);
  for (const MappingRun* run : {&with_front_end, &odometry_only})
    std::printf("free IoU %.3f walls within 2 cells %.3f RMSE %.3f m relative %.4f per metre\n", run->quality.free_iou,
                run->quality.walls_within_2_cells, run->trajectory.position_rmse,
                run->trajectory.relative_translation_per_metre);
  EXPECT_LT(with_front_end.trajectory.position_rmse, 0.5 * odometry_only.trajectory.position_rmse);
  EXPECT_GT(with_front_end.quality.walls_within_2_cells, odometry_only.quality.walls_within_2_cells + 0.1);
  EXPECT_GE(with_front_end.quality.free_iou, 0.8);
  // The loops closed moved poses estimated before them.
  ASSERT_EQ(with_front_end.final_poses.size(), static_cast<size_t>(with_front_end.scans));
  double moved = 0.0;
  for (size_t i = 0; i < with_front_end.final_poses.size(); ++i)
    moved = std::max(moved, std::hypot(with_front_end.final_poses[i].x - with_front_end.online_poses[i].x,
                                       with_front_end.final_poses[i].y - with_front_end.online_poses[i].y));
  EXPECT_GT(moved, 0.001);
  expectTrajectoryIsTheOnlinePoses(odometry_only);
}

TEST(RbpfMapper, RejectsBadIniFiles) {
  const std::string dir = testing::makeTempDir("rbpf_ini");
  RbpfMapperOptions options;
  options.config_file = dir + "/missing.ini";
  EXPECT_THROW({ RbpfMapper mapper(options); }, common::InputError);
  options.config_file = dir + "/garbage.ini";
  std::ofstream(options.config_file) << "this is not [an ini\n\x01\x02 = =\n";
  try {
    RbpfMapper mapper(options);
    ADD_FAILURE() << "garbage accepted";
  } catch (const common::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("garbage.ini"), std::string::npos) << error.what();
  }
  // A valid ini without the grid.
  std::ifstream in(kConfig);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find("occupancyGrid_count = 1");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 23, "occupancyGrid_count = 0");
  options.config_file = dir + "/nogrid.ini";
  std::ofstream(options.config_file) << text;
  EXPECT_THROW({ RbpfMapper mapper(options); }, common::InputError);

  // A published map's certainty outside (0.5, 1).
  text.replace(at, 23, "occupancyGrid_count = 1");
  const std::string freeness = "maxFreenessUpdateCertainty  = 0.70";
  const size_t freeness_at = text.find(freeness);
  ASSERT_NE(freeness_at, std::string::npos);
  text.replace(freeness_at, freeness.size(), "maxFreenessUpdateCertainty  = 1.5");
  options.config_file = dir + "/published.ini";
  std::ofstream(options.config_file) << text;
  try {
    RbpfMapper mapper(options);
    ADD_FAILURE() << "certainty 1.5 accepted";
  } catch (const common::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("PublishedMap"), std::string::npos) << error.what();
  }

  // A front-end option out of its range.
  text.replace(text.find("maxFreenessUpdateCertainty  = 1.5"), 33, freeness);
  options.config_file = dir + "/front_end.ini";
  std::ofstream(options.config_file) << text << "\n[ScanMatching]\nenabled = 1\nmin_goodness = 2\n";
  try {
    RbpfMapper mapper(options);
    ADD_FAILURE() << "min_goodness 2 accepted";
  } catch (const common::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("[ScanMatching] min_goodness and loop_min_goodness must be in [0, 1]"),
              std::string::npos)
        << error.what();
  }
  // Loop closure with an empty search window.
  std::ofstream(options.config_file) << text
                                     << "\n[ScanMatching]\nenabled = 1\nloop_min_travel = 20\nloop_search_radius = 0\n";
  try {
    RbpfMapper mapper(options);
    ADD_FAILURE() << "loop_search_radius 0 accepted";
  } catch (const common::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("loop_search_radius"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace hidden_rooms::mapping
