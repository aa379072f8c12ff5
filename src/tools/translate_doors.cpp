// translate_doors --environment ENV.xml --closed SPEC --truth GT.log --estimate MAP.log --out DIR [--map MAP.yaml]: the
// closed doors of a simulated exploration placed in the map the robot built (docs/method.md#closed-doors-in-the-map)
// and, with the map, the run scored against the world it explored.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/input_limits.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/common/range_scan.h"
#include "hidden_rooms/evaluation/door_translation.h"
#include "hidden_rooms/evaluation/map_quality.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

constexpr double kLocalFitRadius = 5.0;  // metres: poses near a door that place the world for its error

// Distance (metres) of every cell of `map` to its nearest occupied cell (a large value when there is none).
cv::Mat1f distanceToOccupied(const common::OccupancyGrid& map) {
  cv::Mat1b not_occupied(map.height(), map.width());
  for (int row = 0; row < map.height(); ++row)
    for (int col = 0; col < map.width(); ++col) not_occupied(row, col) = map.cells(row, col) >= 65 ? 0 : 255;
  cv::Mat1f distance;
  cv::distanceTransform(not_occupied, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  return distance * map.resolution;
}

// `wanted`, or the finest resolution at which the world's rendering stays within the map size limit when that is
// coarser.
double reachResolution(const world::Environment& environment, const world::RenderOptions& options, double wanted) {
  const auto [low, high] = environment.bounds();
  const double border = 2.0 * options.margin + 1.0;  // the margin both sides, and a metre for rounding
  const double area = (high.x() - low.x() + border) * (high.y() - low.y() + border);
  return std::max(wanted, std::sqrt(area / common::kMaxMapCells));
}

int run(int argc, char** argv) {
  po::options_description options("Options");
  std::string environment_path, closed_spec, truth_path, estimate_path, map_path, out_dir;
  double door_width = 0.9, robot_radius = 0.25, reach_resolution = 0.02;
  world::RenderOptions render_options;
  options.add_options()
      ("environment", po::value(&environment_path)->required(), "environment XML the robot explored")
      ("closed", po::value(&closed_spec)->default_value(""),
       "doors that were closed (as the simulator's ~closed_doors); doors with status CLOSED are added; "
       "only those hiding a room (closable) are written")
      ("truth", po::value(&truth_path)->required(), "true pose log (world frame, pose_logger's ground truth)")
      ("estimate", po::value(&estimate_path)->required(), "estimated pose log (map -> base_link, pose_logger)")
      ("out", po::value(&out_dir)->required(), "output folder (created)")
      ("map", po::value(&map_path), "the explored map (map_server yaml): also score the run")
      ("door-width", po::value(&door_width)->default_value(0.9), "width written for every door, metres")
      ("robot-radius", po::value(&robot_radius)->default_value(0.25),
       "half the robot's width, metres: coverage counts the free area a body this wide can reach (0: every free "
       "cell connected to the start)")
      ("reach-resolution", po::value(&reach_resolution)->default_value(0.02),
       "metres per cell of the world's rendering on which the area the robot's body reaches is decided (the "
       "coverage is scored on the map's 5 cm grid; coarser when the world is too large for this)")
      ("wall-thickness", po::value<double>(), "wall thickness as simulated, metres (default: the world's)");
  po::positional_options_description positional;
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: translate_doors --environment ENV.xml --closed SPEC --truth GT.log --estimate MAP.log\n"
          "                       --out DIR [--map MAP.yaml]\n"
          "Writes DIR/doors.yaml: the closed doors in the map frame, each carried over from the world\n"
          "by the robot pose closest to it (docs/method.md#closed-doors-in-the-map). With --map also\n"
          "DIR/true_rooms.png (label k = the room behind the k-th door, in the map's grid) and\n"
          "DIR/exploration.yaml: coverage of the reachable free area, map quality, path length and each\n"
          "door's translation error (against the world placed by the poses within 5 m of the door, and\n"
          "by the whole run).",
          options, positional, &values))
    return common::kExitOk;
  if (!(door_width > 0.0)) throw common::InputError("--door-width", "must be positive");
  if (!(robot_radius >= 0.0)) throw common::InputError("--robot-radius", "must be zero or positive");
  if (!(reach_resolution > 0.0)) throw common::InputError("--reach-resolution", "must be positive");
  if (values.count("wall-thickness")) render_options.wall_thickness = values["wall-thickness"].as<double>();
  render_options.door_width = door_width;

  const world::Environment environment = world::loadEnvironment(environment_path);
  world::printRepairs(environment, environment_path, std::cerr);
  const std::set<int> closed = world::parseDoorSelection(environment, closed_spec, "--closed");
  const world::RenderedEnvironment rendered = world::renderEnvironment(environment, closed, render_options);
  // The closed doors that hide a room (closable): a closed door of a room with another door hides nothing.
  std::vector<int> door_indices;
  for (const common::MapDoor& door : rendered.closed_doors.doors) {
    const int index = environment.findDoor(std::to_string(door.id));
    if (world::roomBehindDoor(environment, index) >= 0)
      door_indices.push_back(index);
    else
      std::cout << "translate_doors: door " << door.id << " is closed but hides no room (its other side has more "
                << "doors); not written" << std::endl;
  }
  const common::PoseLog truth = common::loadPoseLog(truth_path);
  const common::PoseLog estimate = common::loadPoseLog(estimate_path);

  const common::DoorsFile doors =
      evaluation::translateDoors(environment, door_indices, truth.poses, estimate.poses, door_width);
  const common::OccupancyGrid map = map_path.empty() ? common::OccupancyGrid() : common::loadMap(map_path);
  common::OutputFolder out(out_dir, {environment_path, truth_path, estimate_path, map_path});
  common::saveDoors(doors, out.file("doors.yaml"));
  // Every output in place at once, then reported.
  const auto commit = [&] {
    out.commit();
    std::cout << "translate_doors: " << doors.doors.size() << " closed doors -> "
              << (std::filesystem::path(out_dir) / "doors.yaml").string() << std::endl;
  };
  if (map_path.empty()) {
    commit();
    return common::kExitOk;
  }

  // Scoring: the world placed in the map frame by the least-squares fit of the two trajectories.
  const common::Pose2 world_from_map = evaluation::fitWorldFromMap(truth.poses, estimate.poses);
  const common::Pose2 start = truth.poses.front().pose;
  world::RenderOptions fine_options = render_options;
  fine_options.resolution =
      std::min(render_options.resolution, reachResolution(environment, render_options, reach_resolution));
  const world::RenderedEnvironment fine = world::renderEnvironment(environment, closed, fine_options);
  const cv::Mat1b reachable =
      evaluation::reachableFreeArea(rendered.map, fine.map, common::Point2(start.x, start.y), robot_radius);
  const evaluation::MapQuality quality = evaluation::evaluateMap(map, world_from_map, rendered.map, reachable);
  const evaluation::MapQuality all_free = evaluation::evaluateMap(
      map, world_from_map, rendered.map, evaluation::reachableFreeArea(rendered.map, common::Point2(start.x, start.y)));
  const cv::Mat1w true_rooms = evaluation::trueRoomsInMap(environment, door_indices,
                                                          evaluation::spaceLabelsInMap(rendered, map, world_from_map));
  common::saveLabelImage(true_rooms, out.file("true_rooms.png"));

  const auto coverageOf = [](const evaluation::MapQuality& q) {
    return q.true_free_cells ? double(q.intersection_cells) / double(q.true_free_cells) : 0.0;
  };
  const double coverage = coverageOf(quality);
  const cv::Mat1f wall_distance = distanceToOccupied(map);
  std::ostringstream report;
  report << std::fixed << std::setprecision(4);
  report << "# translate_doors: the run against its world (world frame = the environment's)\n"
         << "world_from_map: [" << world_from_map.x << ", " << world_from_map.y << ", " << world_from_map.yaw << "]\n"
         << "coverage: " << coverage << "  # mapped free / true free cells the robot's body can reach from the start\n"
         << "coverage_all_free: " << coverageOf(all_free)
         << "  # mapped free / true free cells 4-connected to the start (also behind gaps narrower than the robot)\n"
         << "robot_radius: " << robot_radius << "\n"
         << "reach_resolution: " << fine_options.resolution
         << "  # metres per cell on which the body's reach is decided\n"
         << "free_iou: " << all_free.free_iou << "\n"
         << "walls_within_2_cells: " << all_free.walls_within_2_cells << "\n"
         << "path_length: " << pathLength(truth.poses) << "  # metres, true trajectory\n"
         << "duration: " << truth.poses.back().time - truth.poses.front().time << "  # seconds of the run's clock\n"
         << "doors:\n";
  double worst_error = 0.0;
  for (size_t k = 0; k < doors.doors.size(); ++k) {
    const world::Door& door = environment.doors[door_indices[k]];
    // Where the map shows the door: the world placed by the poses within kLocalFitRadius of it.
    const common::Point2 fitted = common::transformPoint(
        common::invertPose(evaluation::fitWorldFromMapNear(truth.poses, estimate.poses, door.centre, kLocalFitRadius)),
        door.centre);
    const double error = (doors.doors[k].position - fitted).norm();
    const double global_error =
        (doors.doors[k].position - common::transformPoint(common::invertPose(world_from_map), door.centre)).norm();
    int col = 0, row = 0;
    const double to_wall =
        map.cellOf(doors.doors[k].position, &col, &row) ? wall_distance(row, col) : std::numeric_limits<double>::infinity();
    worst_error = std::max(worst_error, error);
    report << "  - {id: " << door.number << ", position: [" << doors.doors[k].position.x() << ", "
           << doors.doors[k].position.y() << "], fitted_position: [" << fitted.x() << ", " << fitted.y()
           << "], error: " << error << ", global_error: " << global_error << ", to_mapped_wall: " << (std::isfinite(to_wall) ? std::to_string(to_wall) : std::string(".inf"))
           << "}\n";
  }
  common::writeTextAtomically(out.file("exploration.yaml"), report.str(), "exploration report");
  commit();
  std::cout << "translate_doors: coverage " << std::fixed << std::setprecision(3)
            << coverage << " (all free cells " << coverageOf(all_free) << ")"
            << ", free IoU " << all_free.free_iou << ", worst door error " << worst_error << " m -> "
            << (std::filesystem::path(out_dir) / "exploration.yaml").string() << std::endl;
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("translate_doors", [&] { return run(argc, argv); });
}
