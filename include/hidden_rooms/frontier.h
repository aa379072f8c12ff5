#pragma once

#include <limits>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/geometry.h"
#include "hidden_rooms/grid_planner.h"
#include "hidden_rooms/occupancy_grid.h"

namespace hidden_rooms {

struct FrontierOptions {
  int free_threshold = 19;       // cells with 0 <= value <= this are free ...
  int occupied_threshold = 65;   // ... with value >= this occupied; the rest (and -1) count as unknown
  int min_frontier_cells = 8;    // frontiers (8-connected groups) with fewer cells are dropped
  int min_unknown_cells = 20;    // unknown areas (4-connected) with fewer cells are specks, not frontier material
  double goal_reach = 0.6;       // metres: a goal is a traversable cell within this distance of the frontier ...
  double min_goal_distance = 0.5;  // ... and at least this far from the robot (a goal at the robot teaches nothing)
};

// A frontier: a connected group of free cells that border unknown space.
struct Frontier {
  int label = 0;                 // 1-based, its value in FrontierMap::labels
  std::vector<cv::Point> cells;  // (col, row) in the map's image order
  Point2 centroid = Point2::Zero();  // map frame, metres
};

struct FrontierMap {
  std::vector<Frontier> frontiers;  // sorted by size, largest first (labels 1..n in that order)
  cv::Mat1i labels;                 // per cell: label of its frontier, 0 elsewhere (map's size)
};

// Frontier cells are free cells with a 4-neighbour that is unknown (-1, or neither free nor occupied, or outside
// the grid) and belongs to an unknown area of at least min_unknown_cells; they are grouped 8-connected (OpenCV connected components) and
// groups under min_frontier_cells dropped. An empty map has none.
FrontierMap findFrontiers(const OccupancyGrid& map, const FrontierOptions& options = FrontierOptions());

// Places the robot should not be sent to again (map frame): a candidate goal within `radius` of any is skipped.
struct Blacklist {
  std::vector<Point2> points;
  double radius = 0.8;  // metres
  // Of `points`, the goals that failed while the robot could not move at all (its recoveries produced no
  // motion): the robot was stuck, the place may be fine.
  std::vector<Point2> stuck_points;
  bool contains(const Point2& point) const;
  // Adds a failed or reached goal; `robot_stuck` also lists it in stuck_points.
  void add(const Point2& point, bool robot_stuck = false);
  // Takes the stuck places off the list, so that they are tried again; returns how many there were.
  size_t releaseStuck();
};

struct FrontierGoal {
  int frontier_label = 0;  // label in the FrontierMap
  cv::Point cell;          // the goal cell (traversable, reachable)
  Point2 position = Point2::Zero();  // its centre, map frame
  double cost = std::numeric_limits<double>::infinity();  // the planner's path cost to it
};

// The frontier nearest by path cost: over every roomy cell (planner.roomy(): at least robot_radius from obstacles)
// reachable in `planner`'s last search that lies within options.goal_reach of a frontier cell, at least options.min_goal_distance from the search's start cell
// and not in `blacklist`, the cheapest. With `previous` (the goal
// being driven to; min_goal_distance does not apply to it), that goal is kept while some frontier is still within goal_reach of it and it costs at most
// `hysteresis` metres more than the best (so replanning on every map does not make the robot dither). Nothing
// when no frontier is reachable.
std::optional<FrontierGoal> nearestFrontierGoal(const FrontierMap& frontiers, const GridPlanner& planner,
                                                const Blacklist& blacklist, const FrontierOptions& options,
                                                const std::optional<Point2>& previous = std::nullopt,
                                                double hysteresis = 1.0);

}  // namespace hidden_rooms
