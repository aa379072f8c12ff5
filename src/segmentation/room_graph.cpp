#include "hidden_rooms/segmentation/room_graph.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/segmentation/room_types.h"

namespace hidden_rooms::segmentation {

namespace {

// Direction of a door's line (the wall it sits in), map frame.
common::Point2 doorLine(const common::MapDoor& door) {
  return door.orientation == common::DoorOrientation::kAlongX ? common::Point2(1.0, 0.0) : common::Point2(0.0, 1.0);
}

cv::Point cellAt(const common::OccupancyGrid& map, const common::Point2& point) {
  const common::Point2 image = map.toImage(point);
  return {static_cast<int>(std::floor(image.x())), static_cast<int>(std::floor(image.y()))};
}

// The cells of a closed door's leaf: its line, one cell beyond each jamb, as a border between its two sides.
void drawDoorLeaf(const common::OccupancyGrid& map, const common::MapDoor& door, cv::Mat1b* free) {
  const common::Point2 half = doorLine(door) * (0.5 * door.width + map.resolution);
  cv::line(*free, cellAt(map, door.position - half), cellAt(map, door.position + half), cv::Scalar(0), 2);
}

// The label most cells show on one side of a door (side = +1 or -1 along the door's normal), 0 when none.
int labelBehind(const common::OccupancyGrid& map, const common::MapDoor& door, const cv::Mat1w& labels, int side) {
  const common::Point2 along = doorLine(door);
  const common::Point2 normal(-along.y(), along.x());
  std::map<int, int> votes;
  for (double depth = 2.0 * map.resolution; depth <= 0.6; depth += map.resolution)
    for (double offset = -0.25 * door.width; offset <= 0.25 * door.width; offset += map.resolution) {
      const cv::Point cell = cellAt(map, door.position + normal * (side * depth) + along * offset);
      if (cell.x < 0 || cell.y < 0 || cell.x >= labels.cols || cell.y >= labels.rows) continue;
      if (labels(cell) != 0) ++votes[labels(cell)];
    }
  int best = 0;
  for (const auto& [label, count] : votes)
    if (best == 0 || count > votes[best]) best = label;
  return best;
}

// Per label 1..count, the bounding box of its cells.
std::vector<cv::Rect> labelBoxes(const cv::Mat1w& labels, int count) {
  std::vector<cv::Rect> boxes(count + 1);
  for (int row = 0; row < labels.rows; ++row)
    for (int col = 0; col < labels.cols; ++col) {
      const int label = labels(row, col);
      if (label == 0) continue;
      const cv::Rect cell(col, row, 1, 1);
      boxes[label] = boxes[label].empty() ? cell : (boxes[label] | cell);
    }
  return boxes;
}

// `box`: the bounding box of the room's cells.
Room describeRoom(const common::OccupancyGrid& map, const cv::Mat1w& labels, int label, const cv::Rect& box) {
  Room room;
  room.label = label;
  // The room's cells with a one-cell empty frame, so that its border is found on every side.
  cv::Mat1b local(box.height + 2, box.width + 2, uchar(0));
  cv::Mat1b(labels(box) == label).copyTo(local(cv::Rect(1, 1, box.width, box.height)));
  const cv::Moments moments = cv::moments(local, true);
  room.area = moments.m00 * map.resolution * map.resolution;
  if (moments.m00 > 0)
    room.centroid = map.cellCentre(box.x - 1 + static_cast<int>(std::lround(moments.m10 / moments.m00)),
                                   box.y - 1 + static_cast<int>(std::lround(moments.m01 / moments.m00)));
  cv::Mat1f distance;
  cv::distanceTransform(local, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  double max_distance = 0.0;
  cv::minMaxLoc(distance, nullptr, &max_distance);
  room.width = 2.0 * max_distance * map.resolution;
  room.mean_width = 2.0 * cv::mean(distance, local)[0] * map.resolution;

  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(local, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  const auto largest = std::max_element(contours.begin(), contours.end(), [](const auto& a, const auto& b) {
    return cv::contourArea(a) < cv::contourArea(b);
  });
  if (largest != contours.end()) {
    // Simplified by up to a cell, unless that makes the outline cross itself.
    std::vector<cv::Point> simplified;
    cv::approxPolyDP(*largest, simplified, 1.0, true);
    for (const std::vector<cv::Point>* vertices : {&simplified, &*largest}) {
      room.outline.clear();
      for (const cv::Point& vertex : *vertices)
        room.outline.push_back(map.cellCentre(box.x - 1 + vertex.x, box.y - 1 + vertex.y));
      if (!common::hasCrossing(room.outline, 1e-9)) break;
    }
    if (common::signedArea(room.outline) < 0.0) std::reverse(room.outline.begin(), room.outline.end());
  }
  return room;
}

// Doorways: the pairs of explored rooms whose cells touch (8-neighbourhood), with the touching cells' centre and
// extent.
std::vector<Passage> openPassages(const common::OccupancyGrid& map, const cv::Mat1w& labels, int explored_rooms) {
  struct Border {
    cv::Point2d sum{0.0, 0.0};
    int cells = 0;
    cv::Rect box;
  };
  std::map<std::pair<int, int>, Border> borders;
  for (int row = 0; row < labels.rows; ++row)
    for (int col = 0; col < labels.cols; ++col) {
      const int label = labels(row, col);
      if (label == 0 || label > explored_rooms) continue;
      for (const cv::Point& step : kForwardNeighbours) {
        const cv::Point next(col + step.x, row + step.y);
        if (next.x < 0 || next.x >= labels.cols || next.y >= labels.rows) continue;
        const int other = labels(next);
        if (other == 0 || other == label || other > explored_rooms) continue;
        Border& border = borders[{std::min(label, other), std::max(label, other)}];
        const cv::Rect cell(col, row, 1, 1);
        border.box = border.cells == 0 ? cell : (border.box | cell);
        border.sum += cv::Point2d(col, row);
        ++border.cells;
      }
    }
  std::vector<Passage> passages;
  for (const auto& [pair, border] : borders) {
    Passage passage;
    passage.room_a = pair.first;
    passage.room_b = pair.second;
    passage.kind = PassageKind::kOpen;
    const cv::Point2d mean = border.sum / border.cells;
    passage.centre = map.cellCentre(static_cast<int>(std::lround(mean.x)), static_cast<int>(std::lround(mean.y)));
    passage.width = std::hypot(border.box.width, border.box.height) * map.resolution;
    passages.push_back(passage);
  }
  return passages;
}

}  // namespace

SegmentedFloor segmentFloor(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                            const cv::Mat1w& predicted_rooms, const FloorSegmentationOptions& options) {
  if (map.empty()) throw common::InputError("map", "is empty");
  if (!predicted_rooms.empty() && predicted_rooms.size() != map.cells.size())
    throw common::InputError("predicted rooms", "are " + std::to_string(predicted_rooms.cols) + "x" +
                                                    std::to_string(predicted_rooms.rows) + " cells, the map " +
                                                    std::to_string(map.width()) + "x" + std::to_string(map.height()));
  SegmentationInput input;
  input.resolution = map.resolution;
  input.free = common::trinary(map).cells == common::OccupancyGrid::kFree;
  common::checkDoorsInsideMap(map, doors);
  for (const common::MapDoor& door : doors.doors) drawDoorLeaf(map, door, &input.free);
  const std::unique_ptr<RoomSegmenter> method = makeRoomSegmenter(options.method);

  SegmentedFloor floor;
  floor.labels = segmentRooms(*method, input, options.parameters);
  double explored_max = 0.0;
  cv::minMaxLoc(floor.labels, nullptr, &explored_max);
  const int explored = static_cast<int>(explored_max);

  // Predicted rooms on the cells the segmentation left unlabelled, numbered after the explored ones in the order of
  // their labels.
  int next_label = explored;
  if (!predicted_rooms.empty()) {
    std::vector<int> label_of(65536, 0);  // predicted label -> floor label; -1: on unlabelled cells
    for (int row = 0; row < map.height(); ++row)
      for (int col = 0; col < map.width(); ++col)
        if (predicted_rooms(row, col) != 0 && floor.labels(row, col) == 0) label_of[predicted_rooms(row, col)] = -1;
    for (int& label : label_of) {
      if (label == 0) continue;
      if (next_label == 65535) throw common::InputError("predicted rooms", "are too many to label");
      label = ++next_label;
    }
    for (int row = 0; row < map.height(); ++row)
      for (int col = 0; col < map.width(); ++col)
        if (predicted_rooms(row, col) != 0 && floor.labels(row, col) == 0)
          floor.labels(row, col) = static_cast<uint16_t>(label_of[predicted_rooms(row, col)]);
  }
  const std::vector<cv::Rect> boxes = labelBoxes(floor.labels, next_label);
  for (int label = 1; label <= next_label; ++label) {
    floor.rooms.push_back(describeRoom(map, floor.labels, label, boxes[label]));
    floor.rooms.back().predicted = label > explored;
  }

  floor.passages = openPassages(map, floor.labels, explored);
  for (const common::MapDoor& door : doors.doors) {
    Passage passage;
    passage.door_id = door.id;
    passage.centre = door.position;
    passage.width = door.width;
    int a = labelBehind(map, door, floor.labels, +1), b = labelBehind(map, door, floor.labels, -1);
    if (a > explored) std::swap(a, b);  // the explored side first
    if (a == 0) std::swap(a, b);
    passage.room_a = a;
    passage.room_b = b;
    passage.kind = b > explored ? PassageKind::kPredicted : PassageKind::kClosed;
    floor.passages.push_back(passage);
  }
  if (options.classify_rooms) classifyRooms(RoomTypeClassifier::shipped(), &floor);
  return floor;
}

}  // namespace hidden_rooms::segmentation
