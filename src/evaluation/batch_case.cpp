#include "hidden_rooms/evaluation/batch_case.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/prediction/prediction_support.h"

namespace hidden_rooms::evaluation {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Door indices of the numbers, checked: existing, not repeated.
std::vector<int> doorIndices(const world::Environment& environment, const std::vector<int>& numbers) {
  std::vector<int> indices;
  std::set<int> seen;
  for (int number : numbers) {
    const int index = environment.findDoor(std::to_string(number));
    if (index < 0 || environment.doors[index].number != number)
      throw common::InputError("closed doors", "door " + std::to_string(number) +
                                                   " does not exist (the environment has " +
                                                   std::to_string(environment.doors.size()) + " doors)");
    if (!seen.insert(number).second)
      throw common::InputError("closed doors", "door " + std::to_string(number) + " is closed twice");
    indices.push_back(index);
  }
  return indices;
}

// Per label k = 1..rooms.size(): the true room's area / the free area of space rooms[k-1] in `rendered`.
std::vector<double> roomCoverage(const cv::Mat1w& true_rooms, double resolution, const std::vector<int>& rooms,
                                 const world::RenderedEnvironment& rendered) {
  std::vector<double> coverage;
  const double rendered_cell = rendered.map.resolution * rendered.map.resolution;
  for (size_t k = 0; k < rooms.size(); ++k) {
    const double free_area = cv::countNonZero(rendered.space_labels == static_cast<uint16_t>(rooms[k] + 1)) * rendered_cell;
    const double area = cv::countNonZero(true_rooms == static_cast<uint16_t>(k + 1)) * resolution * resolution;
    coverage.push_back(free_area > 0.0 ? area / free_area : 0.0);
  }
  return coverage;
}

double hiddenPercent(const cv::Mat1w& true_rooms, const cv::Mat1b& complete_free) {
  const int free_cells = cv::countNonZero(complete_free);
  return free_cells > 0 ? 100.0 * cv::countNonZero(true_rooms) / free_cells : 0.0;
}

}  // namespace

BatchCase makeBatchCase(const world::Environment& environment, const std::vector<int>& closed_door_numbers,
                        const world::RenderOptions& options) {
  const Clock::time_point start = Clock::now();
  BatchCase result;
  result.closed_door_numbers = closed_door_numbers;
  const std::vector<int> indices = doorIndices(environment, closed_door_numbers);
  const world::RenderedEnvironment rendered =
      world::renderEnvironment(environment, std::set<int>(indices.begin(), indices.end()), options);
  const cv::Mat1b complete_free = rendered.map.cells == common::OccupancyGrid::kFree;
  result.input = world::hideClosedRooms(environment, rendered);
  result.hidden_percent = hiddenPercent(result.input.true_rooms, complete_free);
  std::vector<int> rooms;
  for (const common::MapDoor& door : result.input.closed_doors.doors)
    rooms.push_back(world::roomBehindDoor(environment, environment.findDoor(std::to_string(door.id))));
  result.room_coverage = roomCoverage(result.input.true_rooms, rendered.map.resolution, rooms, rendered);
  result.seconds = secondsSince(start);
  return result;
}

BatchCase makeBatchCaseFromMap(const world::Environment& environment, const common::OccupancyGrid& complete_map,
                               const common::DoorsFile& doors_in_map, const std::vector<int>& closed_door_numbers,
                               double door_width, double wall_margin) {
  const Clock::time_point start = Clock::now();
  if (complete_map.empty()) throw common::InputError("map", "the complete map is empty");
  if (!(door_width > 0.0) || !(wall_margin >= 0.0))
    throw common::InputError("batch options", "door width must be positive and wall margin not negative");
  BatchCase result;
  result.closed_door_numbers = closed_door_numbers;
  const std::vector<int> indices = doorIndices(environment, closed_door_numbers);

  // Door centres in both frames -> least-squares rigid transform environment -> map (2-D Kabsch).
  std::map<int, common::Point2> in_map;
  for (const common::MapDoor& door : doors_in_map.doors) in_map[door.id] = door.position;
  std::vector<std::pair<common::Point2, common::Point2>> pairs;
  for (const world::Door& door : environment.doors)
    if (in_map.count(door.number)) pairs.emplace_back(door.centre, in_map[door.number]);
  for (int number : closed_door_numbers)
    if (!in_map.count(number))
      throw common::InputError("doors in map", "closed door " + std::to_string(number) + " has no position in the map");
  if (pairs.size() < 2) throw common::InputError("doors in map", "need the positions of at least two doors");
  common::Point2 mean_env = common::Point2::Zero(), mean_map = common::Point2::Zero();
  for (const auto& [e, m] : pairs) mean_env += e, mean_map += m;
  mean_env /= static_cast<double>(pairs.size());
  mean_map /= static_cast<double>(pairs.size());
  double s_cos = 0.0, s_sin = 0.0;
  for (const auto& [e, m] : pairs) {
    const common::Point2 a = e - mean_env, b = m - mean_map;
    s_cos += a.dot(b);
    s_sin += a.x() * b.y() - a.y() * b.x();
  }
  const double angle = std::atan2(s_sin, s_cos);
  Eigen::Matrix2d rotation;
  rotation << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  const common::Point2 offset = mean_map - rotation * mean_env;
  const common::Pose2 fitted{offset.x(), offset.y(), angle};
  // Each closed room is placed by its door's own transform when the doors file has one (an explored map drifts:
  // the room lies where the map shows its door's surroundings), else by the fit.
  std::map<int, common::Pose2> map_from_world;
  for (const common::MapDoor& door : doors_in_map.doors) map_from_world[door.id] = door.map_from_world.value_or(fitted);
  const auto toCells = [&](const common::Polygon& polygon, const common::Pose2& transform) {
    std::vector<cv::Point> points;
    for (const common::Point2& p : polygon) {
      const common::Point2 image = complete_map.toImage(common::transformPoint(transform, p));
      points.emplace_back(static_cast<int>(std::floor(image.x())), static_cast<int>(std::floor(image.y())));
    }
    return points;
  };

  // True rooms: the map's free cells inside each closed room's outline, in the doors file's order (environment
  // order, as renderEnvironment writes it).
  std::vector<int> ordered = indices;
  std::sort(ordered.begin(), ordered.end());
  const cv::Mat1b complete_free = complete_map.cells == common::OccupancyGrid::kFree;
  world::HiddenRoomsCase& hidden = result.input;
  hidden.map = complete_map;
  hidden.map.cells = complete_map.cells.clone();  // the copy shares the caller's cells
  hidden.closed_doors.frame = doors_in_map.frame.empty() ? "map" : doors_in_map.frame;
  hidden.true_rooms = cv::Mat1w::zeros(complete_map.cells.size());
  cv::Mat1b erase = cv::Mat1b::zeros(complete_map.cells.size());
  const int margin_cells = static_cast<int>(std::ceil(wall_margin / complete_map.resolution));
  const cv::Mat kernel =
      cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin_cells + 1, 2 * margin_cells + 1));
  std::vector<int> rooms;
  for (size_t k = 0; k < ordered.size(); ++k) {
    const world::Door& door = environment.doors[ordered[k]];
    const int room = world::roomBehindDoor(environment, ordered[k]);
    if (room < 0)
      throw common::InputError(
          "closed doors", "door " + std::to_string(door.number) + " is not closable: no room lies behind it alone");
    rooms.push_back(room);
    cv::Mat1b outline = cv::Mat1b::zeros(complete_map.cells.size());
    const common::Pose2& transform = map_from_world[door.number];
    const std::vector<std::vector<cv::Point>> polygons{toCells(environment.spaces[room].outline, transform)};
    cv::fillPoly(outline, polygons, cv::Scalar(255));
    hidden.true_rooms.setTo(static_cast<uint16_t>(k + 1), outline & complete_free);
    cv::Mat1b grown;
    cv::dilate(outline, grown, kernel);
    erase |= grown;
    common::MapDoor closed;
    closed.id = door.number;
    closed.position = in_map[door.number];
    closed.width = door_width;
    const double wall_angle = door.wall_angle + transform.yaw;
    closed.orientation = std::abs(std::cos(wall_angle)) >= std::abs(std::sin(wall_angle))
                             ? common::DoorOrientation::kAlongX
                             : common::DoorOrientation::kAlongY;
    hidden.closed_doors.doors.push_back(closed);
  }
  // Erase the rooms and the walls around them, except the wall cells that explored free space sees (within the
  // margin of a free cell outside the erased rooms).
  const cv::Mat1b visible_free = complete_free & ~(hidden.true_rooms > 0);
  cv::Mat1b near_visible;
  cv::dilate(visible_free, near_visible, kernel);
  hidden.map.cells.setTo(common::OccupancyGrid::kUnknown, hidden.true_rooms > 0);
  hidden.map.cells.setTo(common::OccupancyGrid::kUnknown, erase & ~near_visible & ~complete_free);
  // Paint each closed door as a wall across its width.
  const int thickness = std::max(2, 2 * margin_cells);
  for (const common::MapDoor& door : hidden.closed_doors.doors) {
    const common::Point2 along =
        door.orientation == common::DoorOrientation::kAlongX ? common::Point2(1, 0) : common::Point2(0, 1);
    const common::Point2 a = complete_map.toImage(door.position - 0.5 * door.width * along);
    const common::Point2 b = complete_map.toImage(door.position + 0.5 * door.width * along);
    cv::line(hidden.map.cells, cv::Point(static_cast<int>(a.x()), static_cast<int>(a.y())),
             cv::Point(static_cast<int>(b.x()), static_cast<int>(b.y())), cv::Scalar(common::OccupancyGrid::kOccupied),
             thickness, cv::LINE_8);
  }
  hidden.true_rooms.setTo(0, hidden.map.cells == common::OccupancyGrid::kOccupied);  // the doors' walls
  result.hidden_percent = hiddenPercent(hidden.true_rooms, complete_free);
  world::RenderOptions render_options;
  render_options.resolution = complete_map.resolution;
  render_options.door_width = door_width;
  result.room_coverage =
      roomCoverage(hidden.true_rooms, complete_map.resolution, rooms, world::renderEnvironment(environment, {}, render_options));
  result.seconds = secondsSince(start);
  return result;
}

MethodOutcome runMethodOnCase(const prediction::RoomPredictor& method, const BatchCase& batch_case,
                              const std::map<std::string, double>& parameters) {
  const Clock::time_point start = Clock::now();
  MethodOutcome outcome;
  outcome.method = method.name();
  const int doors = static_cast<int>(batch_case.input.closed_doors.doors.size());
  try {
    prediction::PredictionRequest request;
    request.map = batch_case.input.map;
    request.doors = batch_case.input.closed_doors;
    request.parameters = parameters;
    const prediction::PredictionResult result = method.predict(request);
    for (const prediction::RoomPrediction& room : result.rooms) outcome.not_placed += room.placed ? 0 : 1;
    outcome.scores = scoreRooms(prediction::roomLabels(request.map, request.doors, result.rooms),
                                batch_case.input.true_rooms, doors);
  } catch (const std::exception& error) {
    outcome.problem = error.what();
    outcome.scores = RoomScores();
    outcome.scores.iou.assign(doors, 0.0);
  }
  outcome.seconds = secondsSince(start);
  return outcome;
}

}  // namespace hidden_rooms::evaluation
