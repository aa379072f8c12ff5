// benchmark_simulation WORLD: the simulator's core without ROS on a world, with a scripted drive: real-time
// factor reached with each laser caster, the casters' speed per scan and how far they agree.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/simulation/simulation.h"
#include "hidden_rooms/simulation/wander_driver.h"
#include "hidden_rooms/world/environment.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::duration duration) { return std::chrono::duration<double>(duration).count(); }

double percentile(std::vector<float> values, double fraction) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, static_cast<size_t>(fraction * values.size()))];
}

struct RunResult {
  double wall_seconds = 0.0;
  double distance = 0.0;
  int scans = 0;
};

// `sim_seconds` of simulated time: physics every step, a noisy scan at `laser_rate` feeding the drive.
RunResult runDrive(simulation::Simulation* simulation, double sim_seconds, double laser_rate,
                   simulation::CasterAgreement* agreement, std::vector<float>* box2d_times,
                   std::vector<float>* grid_times) {
  RunResult result;
  const double dt = simulation->options().physics_step;
  const int laser_period = std::max(1, static_cast<int>(std::lround(1.0 / (laser_rate * dt))));
  const int steps = static_cast<int>(std::lround(sim_seconds / dt));
  std::vector<float> ranges;
  simulation::WanderDriver driver;
  Clock::duration excluded{0};
  const Clock::time_point start = Clock::now();
  common::Pose2 last = simulation->truePose();
  for (int k = 1; k <= steps; ++k) {
    simulation->step();
    const common::Pose2 pose = simulation->truePose();
    result.distance += std::hypot(pose.x - last.x, pose.y - last.y);
    last = pose;
    if (k % laser_period != 0) continue;
    simulation->scan(&ranges);
    ++result.scans;
    simulation->setCommand(driver.next(ranges, simulation->laserGeometry()));
    if (agreement != nullptr && result.scans % 5 == 0) {  // measurements, not counted in the run's time
      const Clock::time_point t0 = Clock::now();
      std::vector<float> probe;
      simulation->scanWith(simulation::LaserCasterKind::kBox2d, &probe);
      const Clock::time_point t1 = Clock::now();
      simulation->scanWith(simulation::LaserCasterKind::kGrid, &probe);
      const Clock::time_point t2 = Clock::now();
      box2d_times->push_back(static_cast<float>(seconds(t1 - t0) * 1e6));
      grid_times->push_back(static_cast<float>(seconds(t2 - t1) * 1e6));
      simulation::compareCasters(*simulation, 0.05, agreement);
      excluded += Clock::now() - t0;
    }
  }
  result.wall_seconds = seconds(Clock::now() - start - excluded);
  return result;
}

int run(int argc, char** argv) {
  po::options_description options("Options");
  std::string world_path, closed_spec;
  double sim_seconds = 300.0, laser_rate = 10.0;
  simulation::SimulationOptions simulation_options;
  int seed = 1;
  options.add_options()
      ("world", po::value(&world_path)->required(), "environment XML or map_server yaml")
      ("sim-seconds", po::value(&sim_seconds)->default_value(300.0), "simulated seconds per caster")
      ("laser-rate", po::value(&laser_rate)->default_value(10.0), "scans per simulated second")
      ("grid-resolution", po::value(&simulation_options.laser.grid_resolution)->default_value(0.02),
       "cell size of the grid caster, metres")
      ("physics-step", po::value(&simulation_options.physics_step)->default_value(0.01), "seconds")
      ("closed", po::value(&closed_spec), "environment doors closed: numbers or ids, 'closable' or 'all'")
      ("seed", po::value(&seed)->default_value(1), "random seed");
  po::positional_options_description positional;
  positional.add("world", 1);
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: benchmark_simulation WORLD.xml|MAP.yaml [--sim-seconds S] [--grid-resolution R]\n"
          "Drives the simulated robot (scripted, reactive) with each laser caster and prints, as YAML,\n"
          "the real-time factor of the core, the casters' time per scan and their agreement.",
          options, positional, &values))
    return common::kExitOk;
  if (!(sim_seconds > 0.0) || !(laser_rate > 0.0))
    throw common::InputError("command line", "durations and rates must be positive");
  simulation_options.seed = static_cast<uint64_t>(std::max(seed, 0));

  const Clock::time_point load_start = Clock::now();
  simulation::SimulationWorld world;
  const bool is_map = world_path.size() > 5 && world_path.substr(world_path.size() - 5) == ".yaml";
  if (is_map) {
    world = simulation::worldFromGrid(common::loadMap(world_path));
  } else {
    const world::Environment environment = world::loadEnvironment(world_path);
    world::printRepairs(environment, world_path, std::cerr);
    world =
        simulation::worldFromEnvironment(environment, world::parseDoorSelection(environment, closed_spec, "--closed"));
  }
  const double load_seconds = seconds(Clock::now() - load_start);

  std::printf("world: %s\n", world_path.c_str());
  std::printf("load_seconds: %.3f\n", load_seconds);
  simulation::CasterAgreement agreement;
  std::vector<float> box2d_times, grid_times;
  for (simulation::LaserCasterKind kind : {simulation::LaserCasterKind::kBox2d, simulation::LaserCasterKind::kGrid}) {
    simulation::SimulationOptions run_options = simulation_options;
    run_options.laser.caster = kind;
    const Clock::time_point build_start = Clock::now();
    simulation::Simulation simulation(world, run_options);
    const double build_seconds = seconds(Clock::now() - build_start);
    const bool measure = kind == simulation::LaserCasterKind::kBox2d;
    const RunResult result = runDrive(&simulation, sim_seconds, laser_rate, measure ? &agreement : nullptr,
                                      &box2d_times, &grid_times);
    if (measure)
      std::printf("static_fixtures: %d\nwalls: %zu\ndoors: %zu\n", simulation.staticFixtureCount(), world.walls.size(),
                  world.doors.size());
    std::printf("%s:\n  build_seconds: %.3f\n  realtime_factor: %.1f\n  scans: %d\n  distance_driven_m: %.1f\n",
                toString(kind), build_seconds, sim_seconds / result.wall_seconds, result.scans, result.distance);
  }
  std::printf("scan_microseconds_median:\n  box2d: %.0f\n  grid: %.0f\n", percentile(box2d_times, 0.5),
              percentile(grid_times, 0.5));
  std::printf("agreement:\n  beams: %d\n  within_5cm: %.4f\n  same_surface_grazing: %.4f\n  disagree: %.4f\n"
              "  median_abs_difference_m: %.4f\n  p99_abs_difference_m: %.3f\n",
              agreement.beams, static_cast<double>(agreement.within_tolerance) / std::max(agreement.beams, 1),
              static_cast<double>(agreement.same_surface) / std::max(agreement.beams, 1),
              1.0 - static_cast<double>(agreement.within_tolerance + agreement.same_surface) / std::max(agreement.beams, 1),
              percentile(agreement.absolute_differences, 0.5), percentile(agreement.absolute_differences, 0.99));
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("benchmark_simulation", [&] { return run(argc, argv); });
}
