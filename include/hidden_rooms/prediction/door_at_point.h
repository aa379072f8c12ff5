#pragma once

#include <optional>
#include <string>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/occupancy_grid.h"

namespace hidden_rooms::prediction {

// The closed door a user points at on a map (rviz's "Publish Point" tool): a door lies in a wall between
// explored free space on one side and unexplored space on the other.
struct DoorAtPointOptions {
  double search_radius = 1.0;  // metres around the point where the wall and the two sides are looked for
  double default_width = 0.9;  // metres, when the map does not show the doorway's jambs (a door seen as a wall)
  double min_width = 0.5;      // metres: a gap between jambs narrower or wider than these is not a doorway
  double max_width = 2.5;
};

// The door at `point` (map frame): its orientation is that of the axis across which the map changes from free
// (one side) to unknown (the other side); its line is the wall's (the row or column with the most occupied
// cells near the point, else the last free cell towards the unknown side); its width and centre are those of
// the gap between the wall's jambs through the point when the map shows one, else `default_width` at the
// point. Returns nullopt with `problem` set when no free/unknown boundary lies near the point or the point is
// outside the map. The door's id is 0: the caller numbers it.
std::optional<common::MapDoor> doorAtPoint(const common::OccupancyGrid& map, const common::Point2& point,
                                           const DoorAtPointOptions& options, std::string* problem);

}  // namespace hidden_rooms::prediction
