#pragma once
// Closed-door cases from a map of one's own (a SLAM map of a real building; the tool: hide_rooms, docs/tools.md):
// the rooms that a single doorway joins to the rest of the floor are hidden as a closed door would hide them, so
// that a prediction on the map can be scored against what the map showed behind the door.
#include <vector>

#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/segmentation/floor.h"
#include "hidden_rooms/world/render.h"

namespace hidden_rooms::evaluation {

struct ClosableRoomOptions {
  double max_door_width = 1.5;  // metres: a doorway wider than this is an opening, not a door
  double min_area = 4.0;        // square metres: smaller rooms (niches, cupboards) stay
  double wall_reach = 0.3;      // metres: walls this near the free space left in view stay seen
  int max_rooms = 0;            // hide the largest this many closable rooms; 0: all
};

// The closable rooms of `floor` (segmentFloor of `map`): the leaves of its room graph, rooms (not corridors) of at
// least min_area with exactly one passage, an open doorway at most max_door_width wide to a room that has other
// passages. Largest first; returns labels.
std::vector<int> closableRooms(const segmentation::SegmentedFloor& floor, const ClosableRoomOptions& options);

// `map` with the rooms `labels` hidden: each room's cells unknown, and its walls too except within wall_reach of
// the free space left in view; a closed door (doors file order = `labels` order, ids 1, 2, ...) across each
// doorway, drawn as a wall there. `true_rooms`: k on the free cells of the k-th room as the map showed them.
// Throws InputError for a label that is not a closable room of `floor`.
world::HiddenRoomsCase hideRooms(const common::OccupancyGrid& map, const segmentation::SegmentedFloor& floor,
                                 const std::vector<int>& labels, const ClosableRoomOptions& options);

}  // namespace hidden_rooms::evaluation
