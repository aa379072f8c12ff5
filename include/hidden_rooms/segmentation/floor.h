#pragma once

// A floor as rooms: every free cell's room, each room's properties, and the topological map (rooms as nodes,
// doorways and doors as edges), with the predicted rooms behind closed doors as nodes of their own. Made by
// segmentFloor (room_graph.h).

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/geometry.h"

namespace hidden_rooms::segmentation {

enum class RoomKind { kRoom, kCorridor };
const char* toString(RoomKind kind);  // "room" or "corridor"

struct Room {
  int label = 0;                  // its cells' value in SegmentedFloor::labels (1-based)
  double area = 0.0;              // square metres
  common::Point2 centroid = common::Point2::Zero();  // map frame, metres
  common::Polygon outline;        // outer border of its cells, map frame, metres, counter-clockwise
  double width = 0.0;             // metres: twice the largest distance from a cell to the room's border
  double mean_width = 0.0;        // metres: twice the mean distance from its cells to its border
  RoomKind kind = RoomKind::kRoom;  // corridor: its type is corridor
  std::string type;               // one of roomTypeNames() (room_types.h); "" when not classified
  bool predicted = false;         // a predicted room behind a closed door (not explored)
};

// open: a doorway the segmentation found between two explored rooms; closed: a door of the doors file; predicted:
// a closed door with a predicted room behind it.
enum class PassageKind { kOpen, kClosed, kPredicted };
const char* toString(PassageKind kind);  // "open", "closed" or "predicted"

struct Passage {
  int room_a = 0;                 // labels; room_b = 0: the door's far side is neither explored nor predicted
  int room_b = 0;
  PassageKind kind = PassageKind::kOpen;
  common::Point2 centre = common::Point2::Zero();  // map frame, metres
  double width = 0.0;             // metres
  int door_id = 0;                // the doors file's id (closed and predicted passages), else 0
};

struct SegmentedFloor {
  cv::Mat1w labels;               // the map's size: k on the cells of room k, 0 elsewhere
  std::vector<Room> rooms;        // label order (rooms[k - 1].label == k); explored rooms first, then predicted
  std::vector<Passage> passages;  // open ones first, then the doors in the doors file's order
};

}  // namespace hidden_rooms::segmentation
