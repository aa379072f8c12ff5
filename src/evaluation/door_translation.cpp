#include "hidden_rooms/evaluation/door_translation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/range_scan.h"

namespace hidden_rooms::evaluation {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kStartSearchCells = 5;  // a start pose this close to free space (cells) is moved onto it

double halfTurnAngle(double angle) {
  angle = std::fmod(angle, kPi);
  return angle < 0.0 ? angle + kPi : angle;
}

}  // namespace

DoorInMap translateDoor(const common::Point2& door_world, double wall_angle_world,
                        const std::vector<common::TimedPose>& truth, const std::vector<common::TimedPose>& estimate) {
  if (truth.empty() || estimate.empty()) throw common::InputError("door translation", "a trajectory is empty");
  size_t closest = 0;
  double closest_distance = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < truth.size(); ++k) {
    const double distance = (door_world - common::Point2(truth[k].pose.x, truth[k].pose.y)).norm();
    if (distance < closest_distance) {
      closest_distance = distance;
      closest = k;
    }
  }
  const common::TimedPose& robot_world = truth[closest];
  const common::Pose2 robot_map = common::poseAt(estimate, robot_world.time);
  const common::Point2 door_in_robot = common::transformPoint(common::invertPose(robot_world.pose), door_world);

  DoorInMap door;
  door.position = common::transformPoint(robot_map, door_in_robot);
  door.wall_angle = halfTurnAngle(wall_angle_world + common::wrapAngle(robot_map.yaw - robot_world.pose.yaw));
  door.time = robot_world.time;
  door.robot_distance = closest_distance;
  door.map_from_world = common::composePoses(robot_map, common::invertPose(robot_world.pose));
  return door;
}

common::DoorsFile translateDoors(const world::Environment& environment, const std::vector<int>& door_indices,
                                 const std::vector<common::TimedPose>& truth,
                                 const std::vector<common::TimedPose>& estimate, double door_width,
                                 bool with_map_from_world) {
  if (truth.empty() || estimate.empty()) throw common::InputError("door translation", "a trajectory is empty");
  if (estimate.back().time < truth.front().time || estimate.front().time > truth.back().time)
    throw common::InputError("door translation",
                             "the true and estimated poses never overlap in time (true " +
                                 common::formatNumber(truth.front().time) + " .. " +
                                 common::formatNumber(truth.back().time) + " s, estimated " +
                                 common::formatNumber(estimate.front().time) + " .. " +
                                 common::formatNumber(estimate.back().time) + " s): the logs are not of one run");
  common::DoorsFile doors;
  doors.frame = "map";
  for (int index : door_indices) {
    if (index < 0 || index >= static_cast<int>(environment.doors.size()))
      throw common::InputError("door translation", "no door with index " + std::to_string(index));
    const world::Door& door = environment.doors[index];
    const DoorInMap in_map = translateDoor(door.centre, door.wall_angle, truth, estimate);
    common::MapDoor map_door;
    map_door.id = door.number;
    map_door.position = in_map.position;
    map_door.width = door_width;
    map_door.orientation = std::abs(std::cos(in_map.wall_angle)) >= std::abs(std::sin(in_map.wall_angle))
                               ? common::DoorOrientation::kAlongX
                               : common::DoorOrientation::kAlongY;
    if (with_map_from_world) map_door.map_from_world = in_map.map_from_world;
    doors.doors.push_back(map_door);
  }
  return doors;
}

common::Pose2 fitWorldFromMap(const std::vector<common::TimedPose>& truth,
                              const std::vector<common::TimedPose>& estimate) {
  if (truth.empty()) throw common::InputError("trajectory alignment", "the true trajectory is empty");
  std::vector<common::Point2> map_points, world_points;
  for (const common::TimedPose& entry : estimate) {
    if (entry.time < truth.front().time || entry.time > truth.back().time) continue;
    const common::Pose2 world = common::poseAt(truth, entry.time);
    map_points.emplace_back(entry.pose.x, entry.pose.y);
    world_points.emplace_back(world.x, world.y);
  }
  if (map_points.size() < 2)
    throw common::InputError("trajectory alignment",
                             "fewer than two estimated poses fall within the true trajectory's times");
  Eigen::MatrixXd source(2, map_points.size()), target(2, world_points.size());
  for (size_t k = 0; k < map_points.size(); ++k) {
    source.col(k) = map_points[k];
    target.col(k) = world_points[k];
  }
  const Eigen::VectorXd mean = source.rowwise().mean();
  if ((source.colwise() - mean).colwise().norm().maxCoeff() < 0.1)
    throw common::InputError("trajectory alignment", "the robot did not move (the poses span less than 0.1 m)");
  const Eigen::Matrix3d transform = Eigen::umeyama(source, target, false);
  return {transform(0, 2), transform(1, 2), std::atan2(transform(1, 0), transform(0, 0))};
}

common::Pose2 fitWorldFromMapNear(const std::vector<common::TimedPose>& truth,
                                  const std::vector<common::TimedPose>& estimate, const common::Point2& centre,
                                  double radius) {
  constexpr size_t kMinPoses = 20;
  std::vector<common::TimedPose> near;
  for (const common::TimedPose& entry : estimate) {
    const common::Pose2 world = common::poseAt(truth, entry.time);
    if ((common::Point2(world.x, world.y) - centre).norm() <= radius) near.push_back(entry);
  }
  if (near.size() < kMinPoses) return fitWorldFromMap(truth, estimate);
  try {
    return fitWorldFromMap(truth, near);
  } catch (const common::InputError&) {  // the near poses span no distance
    return fitWorldFromMap(truth, estimate);
  }
}

cv::Mat1w spaceLabelsInMap(const world::RenderedEnvironment& rendered, const common::OccupancyGrid& map,
                           const common::Pose2& world_from_map) {
  cv::Mat1w labels = cv::Mat1w::zeros(map.height(), map.width());
  for (int row = 0; row < map.height(); ++row) {
    for (int col = 0; col < map.width(); ++col) {
      int world_col = 0, world_row = 0;
      if (rendered.map.cellOf(common::transformPoint(world_from_map, map.cellCentre(col, row)), &world_col, &world_row))
        labels(row, col) = rendered.space_labels(world_row, world_col);
    }
  }
  return labels;
}

cv::Mat1w trueRoomsInMap(const world::Environment& environment, const std::vector<int>& door_indices,
                         const cv::Mat1w& space_labels_in_map) {
  cv::Mat1w rooms = cv::Mat1w::zeros(space_labels_in_map.size());
  for (size_t k = 0; k < door_indices.size(); ++k) {
    const int room = world::roomBehindDoor(environment, door_indices[k]);
    if (room < 0)
      throw common::InputError("true rooms", "door " + std::to_string(environment.doors.at(door_indices[k]).number) +
                                                 " is not closable: no single room lies behind it");
    rooms.setTo(static_cast<uint16_t>(k + 1), space_labels_in_map == room + 1);
  }
  return rooms;
}

cv::Mat1b reachableFreeArea(const common::OccupancyGrid& rendered, const common::Point2& start, double clearance) {
  if (!(clearance >= 0.0)) throw common::InputError("reachable area", "the clearance must be zero or positive");
  int start_col = 0, start_row = 0;
  if (!rendered.cellOf(start, &start_col, &start_row))
    throw common::InputError("reachable area", "the start position lies outside the world's grid");
  const cv::Mat1b free_cells = rendered.cells == common::OccupancyGrid::kFree;
  // The cells a robot centre may take: all free ones, or those `clearance` away from every non-free cell.
  cv::Mat1b centres;
  if (clearance > 0.0) {
    cv::Mat1f distance;
    cv::distanceTransform(free_cells, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    centres = distance * rendered.resolution >= clearance;
  } else {
    centres = free_cells;
  }
  // The nearest centre cell near the start (a start pose drawn on a wall's edge, or closer to it than the clearance).
  const int search = clearance > 0.0 ? std::max(kStartSearchCells, static_cast<int>(std::ceil(1.0 / rendered.resolution)))
                                     : kStartSearchCells;
  cv::Point seed(-1, -1);
  int best = std::numeric_limits<int>::max();
  for (int dr = -search; dr <= search; ++dr) {
    for (int dc = -search; dc <= search; ++dc) {
      const int row = start_row + dr, col = start_col + dc;
      if (row < 0 || col < 0 || row >= rendered.height() || col >= rendered.width() || !centres(row, col) ||
          dr * dr + dc * dc >= best)
        continue;
      best = dr * dr + dc * dc;
      seed = cv::Point(col, row);
    }
  }
  if (seed.x < 0) throw common::InputError("reachable area", "the start position is not in free space");
  if (clearance <= 0.0) return common::reachableFreeCells(rendered, seed.x, seed.y);
  cv::Mat1b mask = cv::Mat1b::zeros(rendered.height() + 2, rendered.width() + 2);
  cv::floodFill(centres, mask, seed, 255, nullptr, 0, 0, 4 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
  cv::Mat1b body = mask(cv::Rect(1, 1, rendered.width(), rendered.height())).clone();
  const int radius = static_cast<int>(std::ceil(clearance / rendered.resolution - 1e-9));
  cv::dilate(body, body, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1)));
  return body & free_cells;
}

cv::Mat1b reachableFreeArea(const common::OccupancyGrid& rendered, const common::OccupancyGrid& fine,
                            const common::Point2& start, double clearance) {
  const cv::Mat1b fine_reached = reachableFreeArea(fine, start, clearance);
  cv::Mat1b reached = cv::Mat1b::zeros(rendered.height(), rendered.width());
  for (int row = 0; row < rendered.height(); ++row)
    for (int col = 0; col < rendered.width(); ++col) {
      int fine_col = 0, fine_row = 0;
      if (rendered.cells(row, col) == common::OccupancyGrid::kFree &&
          fine.cellOf(rendered.cellCentre(col, row), &fine_col, &fine_row) && fine_reached(fine_row, fine_col))
        reached(row, col) = 255;
    }
  return reached;
}

}  // namespace hidden_rooms::evaluation
