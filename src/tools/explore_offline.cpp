// explore_offline ENV.xml --config rbpf.ini --out DIR [options]: one exploration run (simulator, SLAM mapper,
// nearest-frontier explorer) in one process on a simulated clock, as fast as the CPU allows, without ROS. Writes
// what explore_worlds keeps of an online run: the map, both pose logs and the doors in the map frame.
#include <chrono>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/pose_log.h"
#include "hidden_rooms/evaluation/door_translation.h"
#include "hidden_rooms/pipeline/offline_exploration.h"
#include "hidden_rooms/world/environment.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

// The log's poses thinned to one per `period` seconds (the first and the last kept); period 0 keeps all.
std::string poseLogText(const std::string& parent, const std::string& child,
                        const std::vector<common::TimedPose>& poses, double period) {
  std::string text = common::poseLogHeader(parent, child);
  double next = -1e300;
  for (size_t k = 0; k < poses.size(); ++k)
    if (poses[k].time >= next || k + 1 == poses.size()) {
      text += common::poseLogLine(poses[k]);
      next = poses[k].time + period;
    }
  return text;
}

int run(int argc, char** argv) {
  std::string environment_path, config_path, out_dir, closed_spec;
  int seed = 0;
  double pose_period = 0.0, door_width = 0.9;
  bool quiet = false;
  pipeline::OfflineExplorationOptions run_options;
  po::options_description options("Options");
  options.add_options()
      ("environment", po::value(&environment_path)->required(), "environment XML (thesis schema)")
      ("config", po::value(&config_path)->required(), "MRPT ini of the mapper (the package's config/rbpf.ini)")
      ("out", po::value(&out_dir)->required(), "output folder (created)")
      ("closed", po::value(&closed_spec)->default_value(""),
       "doors closed during the run: numbers or ids, 'closable' or 'all' (as the simulator's ~closed_doors)")
      ("seed", po::value(&seed)->default_value(0), "seed of the simulation (noise) and of the filter")
      ("max-time", po::value(&run_options.max_time)->default_value(1800.0), "simulated seconds at most")
      ("growth-interval", po::value(&run_options.growth_interval)->default_value(120.0),
       "simulated seconds between the map growth checks (explore_worlds' --timeout)")
      ("growth", po::value(&run_options.growth)->default_value(0.001),
       "a check with less than this fraction more free cells did not grow; negative = never stop for it")
      ("patience", po::value(&run_options.patience)->default_value(3), "checks in a row without growth that stop")
      ("pose-period", po::value(&pose_period)->default_value(0.0),
       "seconds between logged poses (0: every scan)")
      ("door-width", po::value(&door_width)->default_value(0.9), "width written for every door, metres")
      ("quiet", po::bool_switch(&quiet), "no progress line");
  po::positional_options_description positional;
  positional.add("environment", 1);
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: explore_offline ENV.xml --config rbpf.ini --out DIR [--closed SPEC] [--seed N] [--max-time S]\n"
          "Explores the environment as exploration_run.launch does (simulator, mapper, explorer with their\n"
          "default parameters), in one process on the simulated clock, and writes DIR/map.yaml + map.png,\n"
          "DIR/truth.log (world -> base_link), DIR/estimate.log (map -> base_link), DIR/doors.yaml (every\n"
          "closable door that was open, in the map frame, with the transform that carried it over) and\n"
          "DIR/run.yaml (why it stopped, simulated and wall seconds, distance, scans, goals).",
          options, positional, &values))
    return common::kExitOk;
  if (seed < 0) throw common::InputError("--seed", "must be zero or positive");
  if (!(pose_period >= 0.0)) throw common::InputError("--pose-period", "must be zero or positive");
  if (!(door_width > 0.0)) throw common::InputError("--door-width", "must be positive");
  pipeline::validate(run_options);

  const world::Environment environment = world::loadEnvironment(environment_path);
  world::printRepairs(environment, environment_path, std::cerr);
  const std::set<int> closed = world::parseDoorSelection(environment, closed_spec, "--closed");
  const simulation::SimulationWorld world = simulation::worldFromEnvironment(environment, closed);
  run_options.simulation.seed = static_cast<uint64_t>(seed);
  run_options.mapper.config_file = config_path;
  run_options.mapper.seed = static_cast<uint32_t>(seed);

  const auto start = std::chrono::steady_clock::now();
  const auto wallSeconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const pipeline::OfflineExplorationResult result =
      pipeline::exploreOffline(world, run_options, [&](double now) {
        if (!quiet)
          std::fprintf(stderr, "\rexplore_offline: %.0f simulated s, %.0fx real time ", now, now / wallSeconds());
      });
  const double wall = wallSeconds();
  if (!quiet) std::fprintf(stderr, "\n");
  if (result.map.empty()) throw common::InputError(environment_path, "the run inserted no scan: no map");

  // The doors that were open and hide a room, carried into the map frame.
  std::vector<int> open_closable;
  for (int index : world::closableDoors(environment))
    if (!closed.count(index)) open_closable.push_back(index);
  const common::DoorsFile doors =
      evaluation::translateDoors(environment, open_closable, result.truth, result.estimate, door_width, true);

  // Created only now: bad input (a missing or malformed ini, ...) writes nothing.
  common::OutputFolder out(out_dir, {environment_path, config_path});
  common::saveMap(result.map, out.mapPrefix("map", ".png"), ".png");
  common::writeTextAtomically(out.file("truth.log"),
                              poseLogText("world", "base_link (ground truth)", result.truth, pose_period), "pose log");
  common::writeTextAtomically(out.file("estimate.log"), poseLogText("map", "base_link", result.estimate, pose_period),
                              "pose log");
  common::saveDoors(doors, out.file("doors.yaml"));
  std::ostringstream report;
  report << std::fixed << std::setprecision(2) << "# explore_offline: " << environment_path << "\n"
         << "stop: " << pipeline::toString(result.stop) << "\n"
         << "closed: \"" << closed_spec << "\"\n"
         << "seed: " << seed << "\n"
         << "simulated_seconds: " << result.simulated_seconds << "\n"
         << "wall_seconds: " << wall << "\n"
         << "distance_driven: " << result.distance_driven << "  # metres, true path\n"
         << "scans: " << result.scans << "\n"
         << "scans_inserted: " << result.scans_inserted << "\n"
         << "goals: " << result.goals << "\n";
  common::writeTextAtomically(out.file("run.yaml"), report.str(), "run report");
  out.commit();
  std::cout << "explore_offline: " << pipeline::toString(result.stop) << " after " << std::fixed
            << std::setprecision(0) << result.simulated_seconds << " simulated s in " << wall << " s ("
            << std::setprecision(1) << result.simulated_seconds / std::max(wall, 1e-9) << "x), " << doors.doors.size()
            << " doors -> " << out_dir << std::endl;
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("explore_offline", [&] { return run(argc, argv); });
}
