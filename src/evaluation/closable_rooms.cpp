#include "hidden_rooms/evaluation/closable_rooms.h"

#include <algorithm>
#include <string>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/segmentation/room_segmenter.h"

namespace hidden_rooms::evaluation {

namespace {

// The passages of room `label`.
std::vector<const segmentation::Passage*> passagesOf(const segmentation::SegmentedFloor& floor, int label) {
  std::vector<const segmentation::Passage*> passages;
  for (const segmentation::Passage& passage : floor.passages)
    if (passage.room_a == label || passage.room_b == label) passages.push_back(&passage);
  return passages;
}

bool isClosable(const segmentation::SegmentedFloor& floor, int label, const ClosableRoomOptions& options) {
  if (label < 1 || label > static_cast<int>(floor.rooms.size())) return false;
  const segmentation::Room& room = floor.rooms[label - 1];
  if (room.kind != segmentation::RoomKind::kRoom || room.predicted || room.area < options.min_area) return false;
  // A leaf of the room graph: one doorway, door-wide, to a room that has other passages (the rest of the floor,
  // which stays in view; of two rooms joined only to each other, neither is behind the other's door).
  const std::vector<const segmentation::Passage*> passages = passagesOf(floor, label);
  if (passages.size() != 1) return false;
  const segmentation::Passage& doorway = *passages[0];
  const int other = doorway.room_a == label ? doorway.room_b : doorway.room_a;
  return doorway.kind == segmentation::PassageKind::kOpen && other != 0 && doorway.width <= options.max_door_width &&
         passagesOf(floor, other).size() > 1;
}

// The door across the doorway between rooms `room` and `other`: the room's cells that touch the other room,
// their bounding box giving the door's line (along its longer side) and width.
common::MapDoor doorway(const common::OccupancyGrid& map, const cv::Mat1w& labels, int room, int other, int id,
                        std::vector<cv::Point>* border) {
  border->clear();
  for (int row = 0; row < labels.rows; ++row)
    for (int col = 0; col < labels.cols; ++col) {
      const cv::Point cell(col, row);
      if (labels(cell) != room) continue;
      for (const cv::Point& step : segmentation::kNeighbours8)
        if (segmentation::insideImage(labels, cell + step) && labels(cell + step) == other) {
          border->push_back(cell);
          break;
        }
    }
  const cv::Rect box = cv::boundingRect(*border);
  common::MapDoor door;
  door.id = id;
  door.orientation = box.width >= box.height ? common::DoorOrientation::kAlongX : common::DoorOrientation::kAlongY;
  door.width = std::max(box.width, box.height) * map.resolution;
  const common::Point2 first = map.cellCentre(box.x, box.y);
  const common::Point2 last = map.cellCentre(box.x + box.width - 1, box.y + box.height - 1);
  door.position = 0.5 * (first + last);
  return door;
}

}  // namespace

std::vector<int> closableRooms(const segmentation::SegmentedFloor& floor, const ClosableRoomOptions& options) {
  std::vector<int> labels;
  for (const segmentation::Room& room : floor.rooms)
    if (isClosable(floor, room.label, options)) labels.push_back(room.label);
  std::stable_sort(labels.begin(), labels.end(),
                   [&](int a, int b) { return floor.rooms[a - 1].area > floor.rooms[b - 1].area; });
  if (options.max_rooms > 0 && static_cast<int>(labels.size()) > options.max_rooms) labels.resize(options.max_rooms);
  return labels;
}

world::HiddenRoomsCase hideRooms(const common::OccupancyGrid& map, const segmentation::SegmentedFloor& floor,
                                 const std::vector<int>& labels, const ClosableRoomOptions& options) {
  if (floor.labels.size() != map.cells.size())
    throw common::InputError("segmentation", "is not of the map's size");
  world::HiddenRoomsCase hidden;
  hidden.map = map;
  hidden.map.cells = map.cells.clone();  // the caller's map stays as it is
  hidden.true_rooms = cv::Mat1w::zeros(map.cells.size());
  const cv::Mat1b free = common::trinary(map).cells == common::OccupancyGrid::kFree;
  cv::Mat1b hidden_cells = cv::Mat1b::zeros(map.cells.size());
  std::vector<std::vector<cv::Point>> borders;
  for (size_t k = 0; k < labels.size(); ++k) {
    const int label = labels[k];
    if (!isClosable(floor, label, options))
      throw common::InputError("room " + std::to_string(label), "is not a closable room of the segmentation");
    if (std::find(labels.begin(), labels.begin() + k, label) != labels.begin() + k)
      throw common::InputError("room " + std::to_string(label), "is given twice");
    const cv::Mat1b cells = floor.labels == label;
    hidden.true_rooms.setTo(static_cast<uint16_t>(k + 1), cells & free);
    hidden_cells |= cells;
    const segmentation::Passage& passage = *passagesOf(floor, label)[0];
    const int other = passage.room_a == label ? passage.room_b : passage.room_a;
    borders.emplace_back();
    hidden.closed_doors.doors.push_back(
        doorway(map, floor.labels, label, other, static_cast<int>(k + 1), &borders.back()));
  }
  world::hideUnseenRooms(hidden_cells, options.wall_reach / map.resolution, &hidden.map);
  // The closed doors: a wall along each doorway's border cells, where the room met the rest of the floor.
  for (const std::vector<cv::Point>& border : borders)
    for (const cv::Point& cell : border) hidden.map.cells(cell) = common::OccupancyGrid::kOccupied;
  return hidden;
}

}  // namespace hidden_rooms::evaluation
