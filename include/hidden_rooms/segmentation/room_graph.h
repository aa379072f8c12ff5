#pragma once

// A floor as rooms: the segmentation of an occupancy grid with its closed doors as borders, each room's
// properties, and the topological map (rooms as nodes, doorways and doors as edges), with the predicted rooms
// behind closed doors as nodes of their own.

#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/segmentation/room_segmenter.h"

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

struct FloorSegmentationOptions {
  std::string method = "default";
  std::map<std::string, double> parameters;  // overrides of the method's defaults
  // Give every room a type and its kind with the shipped room type model (room_types.h); false: every room is of
  // kind room, without a type (for training that model).
  bool classify_rooms = true;
};

// Segments the free cells of `map` (cells <= 19 after map_saver's rule) with the closed doors of `doors` drawn as
// borders. `predicted_rooms` (the map's size or empty): label k > 0 on the cells of a predicted room (a
// prediction's rooms.png); each becomes a predicted room, linked by its door. Throws InputError for an empty map or
// one without free cells, a door outside the map, a label image of another size, or an unknown method or
// parameter.
SegmentedFloor segmentFloor(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                            const cv::Mat1w& predicted_rooms, const FloorSegmentationOptions& options);

}  // namespace hidden_rooms::segmentation
