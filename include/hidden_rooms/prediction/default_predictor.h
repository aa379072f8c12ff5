#pragma once

// The project's own prediction method, "default": per closed door, one of three candidate rooms, a rectangle fitted to
// the walls the robot saw around the door, the room grown on the layout's cell grid by the thesis's method
// (thesis_predictor.h, with its default constants, on a layout that keeps four choices of its own: the flat angular
// window, bounded walls, unknown-pixel IN/OUT and DBSCAN on 1 - L; see config/layout.yaml) and the room the learned
// room model sees behind the door (room_network.h): the one that agrees most (IoU) with the other two
// (mostAgreedCandidate; default_network 3). Other choices: default_network 1 keeps the rectangle or the grown room,
// whichever agrees more with the model's room; 2 the model's rooms; 0 (and every choice on maps too fine for the model:
// networkReads) the grown room when it is at least default_grown_area_ratio times the rectangle (the rectangle stopped
// short, e.g. of an L-shaped room). A missing candidate is never chosen. A rectangle gives up the pixels of the grown
// rooms kept for the other doors. The growth runs on a second thread while the rectangles are fitted (predict() is
// still safe to call from several threads).
//
// Turned maps: when the dominant wall direction (dominantWallAngle, modulo 90 degrees) is at least
// default_min_rotation, the whole prediction runs on the map turned straight (walls along x and y, as the
// layout's cells and the rectangles need) with its doors, and the rooms are turned back onto the map. The angle is
// measured per door too, on the map within default_local_frame_radius of it: doors whose angle differs from the
// map's (and from each other's) by more than default_local_frame_tolerance degrees are predicted apart, each
// group in its own frame (a wing built at another angle, a map bent by drift).
//
// The rectangles, per door, in the door's frame (u along the door's wall, v into the unknown side):
// 1. - the wall: the occupied pixels across the door; the room starts at the first unknown row behind it;
//    - lateral extent: along the wall from the door in both directions while the wall continues (gaps up to
//      default_wall_gap, e.g. open doorways) and the space just behind it is still unknown (a known pixel
//      there is a perpendicular wall of an explored room);
//    - doors on the same wall and the same side split their shared extent at the midpoint between them;
//    - depth: per column of the extent, the unknown run behind the wall (past the column's own wall pixels
//      within 0.15 m: a ragged or slightly tilted SLAM wall) up to the first known pixel; the
//      median when enough columns end on a known pixel inside the known map's bounding box and it is at most
//      default_max_aspect times the width (farther known space is no evidence of the room's back wall: a door
//      into a large unknown region), else a prior: the
//      depth of the explored rooms on the same side of the same wall, else of the other hidden rooms on that
//      side, else (default_model_depth, with default_network 1 or 3) the depth of the learned model's room (per
//      column of the extent its farthest row, the median; when it reaches half of the columns), else the room's
//      width (a square, as the thesis does); either at least default_min_depth.
// 2. Overlapping rectangles of doors on perpendicular walls: the overlap goes to the door nearer to it (along
//    that door's normal) and the other room ends where the overlap begins, if it keeps default_min_depth;
//    other overlaps are cut halfway between the doors.
// 3. The rectangle's unknown pixels connected to the door; pixels claimed by several rooms go to the nearest
//    door.
// Lateral extent and wall stubs: a stub ends the extent unless the wall goes on past it at another row (the side
// wall of a door niche or of a step in the wall: no free space beyond it and wall pixels within its length). With
// the learned model (default_stub_by_model), the rectangles are also laid out with stubs ignored, and a door takes
// that rectangle when most of the cells it adds to the stubbed one are in the model's room.
//
// Every room, grown or rectangle, is then clipped to the known map's outline beside it (clipToKnownOutline,
// default_outline_reach): a room does not stick out of the building past the outer walls its neighbours show; a
// side where nothing is known beyond the door is left open. Last, every room leaves out the unknown cells within default_wall_margin of a wall cell: a wall the robot saw
// from one side shows only its near face in a SLAM map, and the rest of its thickness is no room's. A negative
// margin (the default) is estimated from the map as given (unseenWallThickness), once for all its frames: 0 on maps
// that draw whole walls.
//
// Parameters: start_search_radius and the default_* keys (config/prediction.yaml), and the layout's
// (config/layout.yaml) for the grown rooms; --debug-dir receives the layout's images (of the map turned
// straight, on a turned map).
// terms: "rectangle" (1 when the rectangle was chosen), "model_room" (1 when the learned model's room was chosen;
// it has no terms of its own); a grown room has the thesis's terms, a
// rectangle "width", "depth" (metres), "depth_bounded" (1 when the depth came from the map, 0 from a prior),
// "depth_source" (0 measured, 1 explored neighbours, 2 the other hidden rooms, 3 the square, 4 the model's room);
// every room "rotation" (the wall angle its door was predicted at, degrees; the map was turned when it is at least
// default_min_rotation), "outline_clipped" (m^2 removed by the outline clip) and, with a margin, "wall_margin"
// (metres) and "wall_margin_cut" (m^2 removed by it).

#include <array>
#include <map>
#include <string>

#include "hidden_rooms/common/options.h"
#include "hidden_rooms/prediction/room_predictor.h"

namespace hidden_rooms::prediction {

// The method's own parameters (config/prediction.yaml documents each one).
struct DefaultOptions {
  double start_search_radius = 1.0;  // m: a door's nearest unknown cell lies within this (as the baselines')
  double wall_gap = 1.5;             // m: longest gap in the door's wall still followed
  double max_extent = 25.0;          // m: longest lateral extent and depth searched
  double bounded_fraction = 0.5;     // share of columns ending on a known pixel for a measured depth
  double neighbour_reach = 15.0;     // m: how far along the wall explored neighbours are looked for
  double min_depth = 2.0;            // m: smallest depth taken from the square prior or the model's room
  bool model_depth = true;  // network 1 and 3: no depth on the map, the rectangle takes the model's room's depth
  double model_min_probability = 0.41;  // a cell is in the model's room above this probability (J / (1 + J))
  double max_aspect = 2.0;           // a depth measured on known space counts up to this many times the width
  double local_frame_radius = 10.0;  // m: the walls within this of a door give its frame; 0: the map's frame
  double local_frame_tolerance = 2.0;  // degrees: doors whose wall angles differ less share one frame
  double min_rotation = 1.0;         // degrees: maps turned less are not predicted turned straight
  double grown_area_ratio = 1.25;    // network 0: grown rooms less than this many times the rectangle give way
  double stub_length = 0.3;          // m: wall stubs this long into the explored side end a room's extent
  bool stub_by_model = true;  // network 1, 3: stubs give way where the cells past them are mostly the model's room
  double outline_reach = 15.0;       // m: band beside a room within which the known map's extent bounds it
  double wall_margin = -1.0;         // m: unseen wall thickness left out of rooms; < 0: estimated from the map
  int network = 3;  // the learned room model: 0 unused; 1 chooses rectangle or grown room; 2 its rooms; 3 the
                    // candidate room agreeing most with the other two
};

// A door's candidate rooms under default_network 3, and their pairwise IoUs (0 where one is missing).
enum class RoomCandidate { kRectangle = 0, kGrown = 1, kModel = 2 };
struct CandidateAgreement {
  double rectangle_grown = 0.0;
  double rectangle_model = 0.0;
  double grown_model = 0.0;
};

// The candidate that agrees most with the other two: the highest sum of its IoUs with them, among those present
// (indexed by RoomCandidate); ties go to the grown room, then the rectangle. kGrown when none is present.
RoomCandidate mostAgreedCandidate(const CandidateAgreement& iou, const std::array<bool, 3>& present);

// Every DefaultOptions field as a parameter (start_search_radius, default_wall_gap, ...) with its range.
const common::OptionTable<DefaultOptions>& defaultOptionTable();

class DefaultPredictor : public RoomPredictor {
 public:
  DefaultPredictor() = default;
  std::string name() const override { return "default"; }
  std::map<std::string, double> defaultParameters() const override;
  PredictionResult predict(const PredictionRequest& request) const override;
};

// Dominant wall direction of a map, radians in [-pi/4, pi/4): the walls run along this angle and the one
// perpendicular to it (image frame: x = column, y = row). The angle whose projection profiles of the occupied
// cells (along it and across it) are sharpest, searched to 0.02 degrees, on about `max_points` of them at most
// (beyond, each kept by a hash of its position). 0 when the map has no occupied cells.
double dominantWallAngle(const common::OccupancyGrid& map, size_t max_points = 20000);

// How much of the thickness of walls seen from one side a map does not show, metres: the most common length
// (3 pixels to 1 m) of the runs across the walls that cross a wall seen from both sides (from a free cell, starting
// and ending on an occupied cell, to the next free cell; the wall's inside may be unknown) less the median
// occupied run between a free and an unknown cell (a wall seen from one side), less one cell (the cell a SLAM map
// draws a wall face in reaches past the face, and a wall seen from both sides has one such face more). The runs
// follow the rows and columns of the map turned straight by its dominantWallAngle by nearest cell, which thickens
// no wall. 0 when the map draws whole walls, or has fewer than 20 runs of either kind.
double unseenWallThickness(const common::OccupancyGrid& map);
// The same, given the map's dominantWallAngle (radians).
double unseenWallThickness(const common::OccupancyGrid& map, double wall_angle);

// Clips a room (mask, image frame) to the known map's extent beside it: x to the known pixels of the rows within
// `reach` pixels of the room's rows, y likewise from its columns, so that a room does not stick out of the
// building past the outer walls its neighbours show. A limit is applied only when it lies at least `min_depth`
// pixels beyond the door pixel (otherwise nothing is known on that side).
void clipToKnownOutline(const cv::Mat1b& known, const cv::Point& door, int reach, int min_depth, cv::Mat1b* mask);

}  // namespace hidden_rooms::prediction
