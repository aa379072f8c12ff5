// The simulator's core: world building, laser casting (Box2D and grid DDA) against analytic distances, the
// robot's kinematics and collisions, doors at run time, odometry, determinism and bad input.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/simulation/simulation.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"
#include "test_util.h"

namespace hidden_rooms::simulation {
namespace {

constexpr double kPi = 3.14159265358979323846;

// corridorWithTwoRoomsXml(): corridor x 0..10, y 4..6 m; room A x 0..4, room B x 4..10, y 0..4; door 1 at
// (2, 4) into A, door 2 at (7, 4) into B; walls 0.15 m thick, doors 0.9 m wide.
world::Environment corridorWorld() { return world::parseEnvironment(testing::corridorWithTwoRoomsXml(), "synthetic"); }

SimulationOptions quietOptions(const common::Pose2& start, LaserCasterKind caster = LaserCasterKind::kBox2d) {
  SimulationOptions options;
  options.start_pose = start;
  options.laser.caster = caster;
  options.laser.range_noise = 0.0;
  options.odometry_noise = {0.0, 0.0, 0.0};
  return options;
}

// Range of the beam pointing at `angle` (laser frame) in a 1081-beam, 270-degree scan.
float beamAt(const std::vector<float>& ranges, double angle) {
  const int index = static_cast<int>(std::lround((angle + 0.75 * kPi) / (1.5 * kPi / 1080)));
  return ranges.at(static_cast<size_t>(index));
}

void drive(Simulation* simulation, double linear, double angular, double seconds) {
  const int steps = static_cast<int>(std::lround(seconds / simulation->options().physics_step));
  for (int k = 0; k < steps; ++k) {
    simulation->setCommand({linear, angular});
    simulation->step();
  }
}

TEST(SimulationWorld, EnvironmentWallsMergedAndDoorsOpenable) {
  const world::Environment environment = corridorWorld();
  const SimulationWorld world = worldFromEnvironment(environment, {0});
  ASSERT_EQ(world.doors.size(), 2u);
  EXPECT_TRUE(world.doors[0].closed);
  EXPECT_FALSE(world.doors[1].closed);
  EXPECT_FALSE(world.doors[0].pieces.empty());
  EXPECT_EQ(world.findDoor("door_b"), 1);
  EXPECT_EQ(world.findDoor("1"), 0);
  EXPECT_EQ(world.findDoor("3"), -1);
  // 20 wall segments (shared walls drawn twice) merge into far fewer fixtures.
  const world::WallGeometry raw = world::wallGeometry(environment, {0, 1});
  EXPECT_LT(world.walls.size(), raw.walls.size());
  EXPECT_LE(world.walls.size(), 12u);
}

TEST(SimulationWorld, GridWorldBoxesCoverExactlyTheOccupiedCells) {
  const world::RenderedEnvironment rendered = world::renderEnvironment(corridorWorld(), {0, 1});
  const SimulationWorld world = worldFromGrid(rendered.map);
  double box_area = 0.0;
  for (const common::Polygon& box : world.walls) box_area += common::area(box);
  const double cell_area = rendered.map.resolution * rendered.map.resolution;
  EXPECT_NEAR(box_area / cell_area, cv::countNonZero(rendered.map.cells == common::OccupancyGrid::kOccupied), 1e-3);
  EXPECT_LT(world.walls.size() * 20,
            static_cast<size_t>(cv::countNonZero(rendered.map.cells == common::OccupancyGrid::kOccupied)));
  common::OccupancyGrid empty;
  EXPECT_THROW(worldFromGrid(empty), common::InputError);
}

class CasterTest : public ::testing::TestWithParam<LaserCasterKind> {};

TEST_P(CasterTest, RangesEqualAnalyticDistancesAndFollowTheDoors) {
  const LaserCasterKind kind = GetParam();
  const double tolerance = kind == LaserCasterKind::kBox2d ? 0.002 : 0.03;
  Simulation simulation(worldFromEnvironment(corridorWorld(), {0}), quietOptions({2.0, 5.0, 0.0}, kind));
  std::vector<float> ranges;
  simulation.scan(&ranges);
  ASSERT_EQ(ranges.size(), 1081u);
  // The laser sits 0.2 m ahead of base_link: (2.2, 5).
  EXPECT_NEAR(beamAt(ranges, 0.0), 9.925 - 2.2, tolerance);            // east wall
  EXPECT_NEAR(beamAt(ranges, kPi / 2), 6.0 - 0.075 - 5.0, tolerance);  // corridor's north wall
  EXPECT_NEAR(beamAt(ranges, -kPi / 2), 5.0 - 4.075, tolerance);       // closed door 1 (x 1.55..2.45)
  EXPECT_NEAR(beamAt(ranges, -0.75 * kPi), 0.925 * std::sqrt(2.0), tolerance);  // wall beside the door
  simulation.setDoor("door_a", true);
  simulation.scan(&ranges);
  EXPECT_NEAR(beamAt(ranges, -kPi / 2), 5.0 - 0.075, tolerance);  // through the door to room A's south wall
  simulation.setDoor("1", false);
  simulation.scan(&ranges);
  EXPECT_NEAR(beamAt(ranges, -kPi / 2), 5.0 - 4.075, tolerance);
}

INSTANTIATE_TEST_SUITE_P(BothCasters, CasterTest,
                         ::testing::Values(LaserCasterKind::kBox2d, LaserCasterKind::kGrid),
                         [](const ::testing::TestParamInfo<LaserCasterKind>& info) {
                           return std::string(toString(info.param));
                         });

TEST(Simulation, NothingInRangeGivesMaxRange) {
  SimulationOptions options = quietOptions({2.0, 5.0, 0.0});
  options.laser.max_range = 1.0;
  Simulation simulation(worldFromEnvironment(corridorWorld(), {}), options);
  std::vector<float> ranges;
  for (LaserCasterKind kind : {LaserCasterKind::kBox2d, LaserCasterKind::kGrid}) {
    simulation.scanWith(kind, &ranges);
    EXPECT_FLOAT_EQ(beamAt(ranges, 0.0), 1.0f) << toString(kind);
    EXPECT_NEAR(beamAt(ranges, kPi / 2), 0.925, 0.03) << toString(kind);
  }
}

TEST(Simulation, CastersAgreeOnAShippedWorld) {
  const world::Environment environment =
      world::loadEnvironment(std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/worlds/large_1.xml");
  Simulation simulation(worldFromEnvironment(environment, {}), SimulationOptions{});
  // Poses along a drive through the world; compare every beam.
  CasterAgreement agreement;
  for (int k = 0; k < 40; ++k) {
    drive(&simulation, 0.6, k % 8 < 4 ? 0.8 : -0.5, 0.5);
    compareCasters(simulation, 0.05, &agreement);
  }
  ASSERT_EQ(agreement.beams, 40 * 1081);
  EXPECT_GT(static_cast<double>(agreement.within_tolerance) / agreement.beams, 0.85);
  EXPECT_GT(static_cast<double>(agreement.within_tolerance + agreement.same_surface) / agreement.beams, 0.995);
}

TEST(Simulation, StopsAtAClosedDoorPassesTheOpenedOneStopsAtTheWall) {
  Simulation simulation(worldFromEnvironment(corridorWorld(), {0}), quietOptions({2.0, 5.2, -kPi / 2}));
  drive(&simulation, 0.5, 0.0, 5.0);
  const double half_length = 0.313;
  EXPECT_GT(simulation.truePose().y, 4.075 + half_length - 0.02);  // against the closed door
  EXPECT_LT(simulation.truePose().y, 4.075 + half_length + 0.05);
  simulation.setDoor("door_a", true);
  drive(&simulation, 0.5, 0.0, 12.0);
  EXPECT_GT(simulation.truePose().y, 0.075 + half_length - 0.02);  // through the door, against room A's wall
  EXPECT_LT(simulation.truePose().y, 0.075 + half_length + 0.05);
  EXPECT_NEAR(simulation.truePose().x, 2.0, 0.05);
  // Odometry without error is the true motion, from zero at the start pose.
  EXPECT_NEAR(simulation.odometryPose().x, 5.2 - simulation.truePose().y, 1e-3);
  EXPECT_NEAR(simulation.odometryPose().y, 0.0, 1e-3);
  simulation.reset();
  EXPECT_NEAR(simulation.truePose().y, 5.2, 1e-4);
  EXPECT_NEAR(simulation.odometryPose().x, 0.0, 1e-9);
}

TEST(Simulation, AccelerationLimitsAndWatchdog) {
  SimulationOptions options = quietOptions({5.0, 5.0, 0.0});
  Simulation simulation(worldFromEnvironment(corridorWorld(), {}), options);
  simulation.setCommand({5.0, 0.0});  // clamped to 0.7 m/s
  simulation.step();
  EXPECT_NEAR(simulation.velocity().linear, options.robot.linear_acceleration * options.physics_step, 1e-3);
  for (int k = 0; k < 40; ++k) simulation.step();  // 0.41 s: within the watchdog
  EXPECT_NEAR(simulation.velocity().linear, 0.41, 0.01);
  for (int k = 0; k < 200; ++k) simulation.step();  // no command for 2 s: stopped
  EXPECT_NEAR(simulation.velocity().linear, 0.0, 1e-6);
  const double x = simulation.truePose().x;
  for (int k = 0; k < 100; ++k) simulation.step();
  EXPECT_NEAR(simulation.truePose().x, x, 1e-6);
  simulation.setCommand({5.0, 0.0});
  for (int k = 0; k < 200; ++k) {
    simulation.setCommand({5.0, 0.0});
    simulation.step();
  }
  EXPECT_NEAR(simulation.velocity().linear, options.robot.max_linear_velocity, 1e-3);
}

TEST(Simulation, SameSeedSameRunOtherSeedOtherNoise) {
  auto run = [](uint64_t seed, std::vector<float>* ranges) {
    SimulationOptions options;
    options.seed = seed;
    options.start_pose = common::Pose2{5.0, 5.0, 0.0};
    Simulation simulation(worldFromEnvironment(corridorWorld(), {}), options);
    for (int k = 0; k < 300; ++k) {
      simulation.setCommand({0.4, std::sin(k * 0.05)});
      simulation.step();
    }
    simulation.scan(ranges);
    return simulation.odometryPose();
  };
  std::vector<float> a, b, c;
  const common::Pose2 pa = run(7, &a), pb = run(7, &b), pc = run(8, &c);
  EXPECT_EQ(a, b);
  EXPECT_EQ(pa.x, pb.x);
  EXPECT_EQ(pa.yaw, pb.yaw);
  EXPECT_NE(a, c);
  EXPECT_NE(pa.x, pc.x);
}

TEST(Simulation, DefaultStartPoseIsInTheCorridor) {
  Simulation simulation(worldFromEnvironment(corridorWorld(), {}), SimulationOptions{});
  EXPECT_GT(simulation.startPose().y, 4.3);
  EXPECT_LT(simulation.startPose().y, 5.7);
}

TEST(Simulation, BadInputGivesClearErrors) {
  const SimulationWorld world = worldFromEnvironment(corridorWorld(), {});
  Simulation simulation(world, quietOptions({5.0, 5.0, 0.0}));
  EXPECT_THROW(simulation.setCommand({std::numeric_limits<double>::quiet_NaN(), 0.0}), common::InputError);
  EXPECT_THROW(simulation.setCommand({0.0, std::numeric_limits<double>::infinity()}), common::InputError);
  EXPECT_THROW(simulation.setDoor("no_such_door", true), common::InputError);
  EXPECT_THROW(simulation.setDoor("9", true), common::InputError);
  SimulationOptions bad = quietOptions({5.0, 5.0, 0.0});
  bad.physics_step = 0.0;
  EXPECT_THROW(Simulation(world, bad), common::InputError);
  bad = quietOptions({5.0, 5.0, 0.0});
  bad.laser.beams = 0;
  EXPECT_THROW(Simulation(world, bad), common::InputError);
  bad = quietOptions({5.0, 5.0, 0.0});
  bad.laser.range_noise = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(Simulation(world, bad), common::InputError);
  EXPECT_THROW(Simulation(world, quietOptions({4.0, 4.0, 0.0})), common::InputError);  // start pose on a wall
  for (const common::Pose2 outside : {common::Pose2{500.0, 5.0, 0.0}, common::Pose2{-3.0, -3.0, 0.0}})
    EXPECT_NE(testing::inputErrorMessage([&] { Simulation(world, quietOptions(outside)); })
                  .find("is not in the world's free space"),
              std::string::npos);
  EXPECT_THROW(laserCasterFromString("bresenham"), common::InputError);
  EXPECT_THROW(worldFromEnvironment(corridorWorld(), {5}), common::InputError);
  EXPECT_THROW(world::loadEnvironment("/nonexistent/world.xml"), common::InputError);
  EXPECT_THROW(world::parseEnvironment("<building><floor>", "broken.xml"), common::InputError);
}

}  // namespace
}  // namespace hidden_rooms::simulation
