#pragma once

#include <optional>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/options.h"
#include "hidden_rooms/world/environment.h"

namespace hidden_rooms::world {

struct RenderOptions {
  double resolution = 0.05;  // metres per cell
  // Wall thickness in metres; unset: the environment's <wall_thickness>, else kDefaultWallThickness.
  std::optional<double> wall_thickness;
  double door_width = 0.9;   // width of the gap cut at every open door, metres
  double margin = 1.0;       // unknown border around the environment, metres
  static constexpr double kDefaultWallThickness = 0.15;
  static constexpr double kMaxWallThickness = 1.0;  // metres: the thickest walls of real buildings, and more
};

// resolution, door_width and margin with the ranges renderEnvironment accepts; the optional wall_thickness is
// not in it.
const common::OptionTable<RenderOptions>& renderOptionTable();

// Ground truth of an environment in the map frame (the map frame is the environment frame: the grid's
// origin is its lower-left corner in environment coordinates).
struct RenderedEnvironment {
  common::OccupancyGrid map;  // free inside spaces, walls occupied, unknown outside
  cv::Mat1w space_labels;   // per cell: 1 + index of the space whose free cells it belongs to, 0 elsewhere
  common::DoorsFile closed_doors;  // the closed doors, frame "map"
  double wall_thickness = 0.0;  // metres, as drawn
};

// Renders the environment. Doors in `closed_door_indices`, doors whose status is CLOSED and exterior doors
// (joining fewer than two spaces) are drawn as wall; every other door gets a gap of `door_width`.
RenderedEnvironment renderEnvironment(const Environment& environment, const std::set<int>& closed_door_indices,
                                      const RenderOptions& options = RenderOptions());

// The walls renderEnvironment draws, as solid rectangles (metres, environment frame): every WALL segment
// thickened to the wall thickness and extended by half of it at both ends, with a gap of `door_width` cut
// through every wall a door in `open_door_indices` opens (both drawings of a double wall). Per door index:
// `door_leaves` holds the wall pieces cut away for it (adding them back closes the door exactly as a closed door
// is drawn), `door_openings` the free rectangle across its gap (both empty for doors not in the set). Throws
// InputError for bad options or a door index that does not exist.
struct WallGeometry {
  double thickness = 0.0;  // metres, as drawn
  std::vector<common::Polygon> walls;
  std::vector<std::vector<common::Polygon>> door_leaves;
  std::vector<common::Polygon> door_openings;
};
WallGeometry wallGeometry(const Environment& environment, const std::set<int>& open_door_indices,
                          const RenderOptions& options = RenderOptions());

// What a robot maps when the closed doors stay shut: the rendering with the room behind each closed door made
// unknown, its walls too except where they face explored free space. `true_rooms` holds k on the free cells
// of the room behind the k-th closed door (the order of `closed_doors`). Throws InputError for a closed door
// that is not closable (its room has other doors, so nothing would be hidden behind it).
struct HiddenRoomsCase {
  common::OccupancyGrid map;
  common::DoorsFile closed_doors;
  cv::Mat1w true_rooms;
};
HiddenRoomsCase hideClosedRooms(const Environment& environment, const RenderedEnvironment& rendered);

// What a closed door hides of the rooms `hidden` (their cells, non-zero) in `map`: those cells become unknown, and
// so does every cell nearer to them than to the free space left in view and more than `seen_reach` cells from it
// (the rooms' far walls, and what a SLAM map left uncertain inside them). Free: as map_saver saves it (trinary).
void hideUnseenRooms(const cv::Mat1b& hidden, double seen_reach, common::OccupancyGrid* map);

// Colour preview for people: spaces tinted, walls black, open doors green, closed doors red with their
// numbers.
cv::Mat3b renderPreview(const Environment& environment, const RenderedEnvironment& rendered);

}  // namespace hidden_rooms::world
