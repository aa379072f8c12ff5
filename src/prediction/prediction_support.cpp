#include "hidden_rooms/prediction/prediction_support.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/input_limits.h"
#include "hidden_rooms/common/label_image.h"

namespace hidden_rooms::prediction {

cv::Rect knownBoundingBox(const common::OccupancyGrid& map) {
  return cv::boundingRect(map.cells != common::OccupancyGrid::kUnknown);
}

bool nearestUnknownCell(const common::OccupancyGrid& map, const common::Point2& position, double max_distance,
                        cv::Point* cell, std::string* problem) {
  int col = 0, row = 0;
  if (!map.cellOf(position, &col, &row)) {
    *problem = "door position (" + common::formatNumber(position.x()) + ", " + common::formatNumber(position.y()) +
               ") is outside the map";
    return false;
  }
  const int radius = static_cast<int>(std::ceil(max_distance / map.resolution));
  double best = std::numeric_limits<double>::infinity();
  for (int r = std::max(0, row - radius); r <= std::min(map.height() - 1, row + radius); ++r)
    for (int c = std::max(0, col - radius); c <= std::min(map.width() - 1, col + radius); ++c) {
      if (map.cells(r, c) != common::OccupancyGrid::kUnknown) continue;
      const double distance = (map.cellCentre(c, r) - position).norm();
      if (distance < best && distance <= max_distance) {
        best = distance;
        *cell = cv::Point(c, r);
      }
    }
  if (!std::isfinite(best)) {
    *problem = "no unknown space within " + std::to_string(max_distance) + " m of the door";
    return false;
  }
  return true;
}

void finishPrediction(const common::OccupancyGrid& map, RoomPrediction* room,
                      const std::optional<cv::Rect>& cells_within) {
  // The room's bounding box and one more pixel around it (where it is inside the image): all the work below.
  cv::Rect box;
  if (!room->mask.empty()) {
    const cv::Rect within = cells_within ? *cells_within & cv::Rect(0, 0, room->mask.cols, room->mask.rows)
                                         : cv::Rect(0, 0, room->mask.cols, room->mask.rows);
    box = cv::boundingRect(room->mask(within)) + within.tl();
  }
  const cv::Rect roi = cv::Rect(box.x - 1, box.y - 1, box.width + 2, box.height + 2) &
                       cv::Rect(0, 0, room->mask.cols, room->mask.rows);
  const int cells = box.area() == 0 ? 0 : cv::countNonZero(room->mask(roi));
  if (cells == 0) {
    room->placed = false;
    if (room->problem.empty()) room->problem = "no room predicted";
    room->polygon.clear();
    room->area = 0.0;
    return;
  }
  room->placed = true;
  room->problem.clear();
  room->area = cells * map.resolution * map.resolution;
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(room->mask(roi).clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE, roi.tl());
  const auto largest = std::max_element(contours.begin(), contours.end(), [](const auto& a, const auto& b) {
    return cv::contourArea(a) < cv::contourArea(b);
  });
  room->polygon.clear();
  for (const cv::Point& p : *largest) room->polygon.push_back(map.cellCentre(p.x, p.y));
}

RoomPrediction unplacedRoom(const common::OccupancyGrid& map, int door_id, const std::string& problem) {
  RoomPrediction room;
  room.door_id = door_id;
  room.mask = cv::Mat1b::zeros(map.cells.size());
  room.problem = problem;
  finishPrediction(map, &room);
  return room;
}

void checkUsableMap(const common::OccupancyGrid& map) {
  if (map.empty()) throw common::InputError("map", "the map is empty");
  if (cv::countNonZero(map.cells != common::OccupancyGrid::kUnknown) == 0)
    throw common::InputError("map", "the map has no known cell");
  if (cv::countNonZero(map.cells == common::OccupancyGrid::kFree) == 0)
    throw common::InputError("map", "the map has no free cell (nothing was explored)");
  if (!(map.resolution > 0.0) || !std::isfinite(map.resolution))
    throw common::InputError("map", "resolution must be positive");
}

void checkUsableRequest(const PredictionRequest& request) {
  const double cells = static_cast<double>(request.map.width()) * request.map.height();
  common::checkLimit("map", "the number of cells", cells, common::kMaxMapCells, ": coarsen or crop the map");
  const double doors = static_cast<double>(request.doors.doors.size());
  common::checkLimit("doors", "the number of doors", doors, common::kMaxDoors, ": predict them in several requests");
  common::checkLimit("doors", "doors x map cells", doors * cells, common::kMaxDoorCells,
                     ": each door's room is a mask of the map's size; predict fewer doors per request");
  checkUsableMap(request.map);
}

common::OccupancyGrid insertRooms(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                                  const std::vector<RoomPrediction>& rooms) {
  common::OccupancyGrid completed = map;
  completed.cells = map.cells.clone();  // the input map stays as it is
  cv::Mat1b all_rooms = cv::Mat1b::zeros(map.cells.size());
  for (const RoomPrediction& room : rooms)
    if (room.placed) all_rooms |= room.mask;
  completed.cells.setTo(common::OccupancyGrid::kFree, all_rooms);
  // Walls: unknown cells touching a room.
  cv::Mat1b around;
  cv::dilate(all_rooms, around, cv::Mat1b::ones(3, 3));
  completed.cells.setTo(common::OccupancyGrid::kOccupied,
                        around & ~all_rooms & (map.cells == common::OccupancyGrid::kUnknown));

  // Doors: a free rectangle of the door's width across the door line, from the explored side to the room.
  const double max_depth = 1.0;  // metres on each side of the door line
  for (size_t k = 0; k < rooms.size() && k < doors.doors.size(); ++k) {
    if (!rooms[k].placed) continue;
    const common::MapDoor& door = doors.doors[k];
    const common::Point2 along =
        door.orientation == common::DoorOrientation::kAlongX ? common::Point2(1, 0) : common::Point2(0, 1);
    const common::Point2 across(-along.y(), along.x());
    const int half_width = static_cast<int>(std::floor(0.5 * door.width / map.resolution));
    const int depth = static_cast<int>(std::ceil(max_depth / map.resolution));
    for (int s = -half_width; s <= half_width; ++s) {
      // Walk across the door line in both directions until free space (explored side or room) is reached.
      for (int side : {1, -1}) {
        std::vector<cv::Point> path;
        bool reached = false;
        for (int t = 0; t <= depth && !reached; ++t) {
          int col = 0, row = 0;
          const common::Point2 p = door.position + map.resolution * (s * along + side * t * across);
          if (!completed.cellOf(p, &col, &row)) break;
          if (t > 0 && completed.cells(row, col) == common::OccupancyGrid::kFree &&
              map.cells(row, col) != common::OccupancyGrid::kOccupied) {
            reached = true;
            break;
          }
          path.emplace_back(col, row);
        }
        if (!reached) continue;
        for (const cv::Point& cell : path) completed.cells(cell) = common::OccupancyGrid::kFree;
      }
    }
  }
  return completed;
}

cv::Mat1w roomLabels(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                     const std::vector<RoomPrediction>& rooms) {
  cv::Mat1w labels = cv::Mat1w::zeros(map.cells.size());
  const auto door_distance = [&](const cv::Point& cell, size_t k) {
    return static_cast<float>((map.cellCentre(cell.x, cell.y) - doors.doors[k].position).norm());
  };
  for (size_t k = 0; k < rooms.size() && k < doors.doors.size(); ++k) {
    if (!rooms[k].placed) continue;
    // Only the mask's bounding box is scanned: rooms are small against the map. Distances are needed only
    // where an earlier room already claimed the cell.
    const cv::Rect box = cv::boundingRect(rooms[k].mask);
    for (int row = box.y; row < box.br().y; ++row) {
      const uint8_t* in_room = rooms[k].mask.ptr<uint8_t>(row);
      uint16_t* label = labels.ptr<uint16_t>(row);
      for (int col = box.x; col < box.br().x; ++col) {
        if (!in_room[col]) continue;
        if (label[col] == 0 || door_distance({col, row}, k) < door_distance({col, row}, label[col] - 1))
          label[col] = static_cast<uint16_t>(k + 1);
      }
    }
  }
  return labels;
}

cv::Mat3b renderPredictionOverlay(const common::OccupancyGrid& map, const cv::Mat1w& predicted_labels,
                                  const cv::Mat& true_labels) {
  cv::Mat3b overlay;
  cv::cvtColor(map.toGreyImage(), overlay, cv::COLOR_GRAY2BGR);
  // Rooms tinted in one pass: 40 % map grey, 60 % the room's colour.
  double max_label = 0.0;
  cv::minMaxLoc(predicted_labels, nullptr, &max_label);
  std::vector<cv::Vec3b> colours(static_cast<size_t>(max_label) + 1);
  for (size_t label = 1; label < colours.size(); ++label) colours[label] = common::roomColour(static_cast<int>(label));
  for (int row = 0; row < overlay.rows; ++row) {
    const uint16_t* label = predicted_labels.ptr<uint16_t>(row);
    cv::Vec3b* pixel = overlay.ptr<cv::Vec3b>(row);
    for (int col = 0; col < overlay.cols; ++col) {
      if (label[col] == 0) continue;
      for (int channel = 0; channel < 3; ++channel)
        pixel[col][channel] = cv::saturate_cast<uchar>(0.4 * pixel[col][channel] + 0.6 * colours[label[col]][channel]);
    }
  }
  if (!true_labels.empty()) {
    cv::Mat1i truth;
    true_labels.convertTo(truth, CV_32S);
    // Each true room outlined within its own bounding box (one pixel wider, so that the contour is closed).
    double max_truth = 0.0;
    cv::minMaxLoc(truth, nullptr, &max_truth);
    std::vector<cv::Rect> boxes(static_cast<size_t>(std::max(0.0, max_truth)) + 1);
    for (int row = 0; row < truth.rows; ++row) {
      const int* label = truth.ptr<int>(row);
      for (int col = 0; col < truth.cols; ++col)
        if (label[col] > 0) boxes[static_cast<size_t>(label[col])] |= cv::Rect(col, row, 1, 1);
    }
    const cv::Rect image(0, 0, truth.cols, truth.rows);
    for (int label = 1; label < static_cast<int>(boxes.size()); ++label) {
      const cv::Rect& box = boxes[static_cast<size_t>(label)];
      if (box.empty()) continue;
      const cv::Rect roi = cv::Rect(box.x - 1, box.y - 1, box.width + 2, box.height + 2) & image;
      std::vector<std::vector<cv::Point>> contours;
      cv::findContours(cv::Mat1b(truth(roi) == label), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE, roi.tl());
      cv::drawContours(overlay, contours, -1, cv::Scalar(0, 160, 0), 2);
    }
  }
  return overlay;
}

}  // namespace hidden_rooms::prediction
