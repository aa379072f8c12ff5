#pragma once

#include <limits>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/options.h"
#include "hidden_rooms/exploration/grid_planner.h"

namespace hidden_rooms::exploration {

struct FrontierOptions {
  int free_threshold = 19;       // cells with 0 <= value <= this are free ...
  int occupied_threshold = 65;   // ... with value >= this occupied; the rest (and -1) count as unknown
  int min_frontier_cells = 8;    // frontiers (8-connected groups) with fewer cells are dropped
  int min_unknown_cells = 20;    // unknown areas (4-connected) with fewer cells are specks, not frontier material
  double goal_reach = 0.6;       // metres: a goal is a traversable cell within this distance of the frontier ...
  double min_goal_distance = 0.5;  // ... and at least this far from the robot (a goal at the robot teaches nothing)
  // When no frontier can be reached, the robot looks at them from where it can: a look goal is a roomy reachable
  // cell at most look_range from a frontier cell, with a line of free cells to it that would go on into the
  // unknown space beside that cell (rooms behind gaps the robot does not fit through). 0 = off.
  double look_range = 3.0;  // metres
  // A free cell where a laser beam at most seen_wall_range long ended, or up to seen_wall_margin behind that end,
  // lies in a wall the laser sees; when a map made seen_wall_delay seconds later still shows it next to unknown
  // space, that space is the wall's inside (a wall the map draws a few cm off, with holes), not unexplored: no
  // frontier cell.
  double seen_wall_range = 2.0;   // metres (0 = off)
  double seen_wall_margin = 0.15;  // metres behind the beam's end
  double seen_wall_delay = 4.0;   // seconds: more than the mapper's lag (scan insertion, map publication)
};

// A frontier: a connected group of free cells that border unknown space.
struct Frontier {
  int label = 0;                 // 1-based, its value in FrontierMap::labels
  std::vector<cv::Point> cells;  // (col, row) in the map's image order
  common::Point2 centroid = common::Point2::Zero();  // map frame, metres
};

struct FrontierMap {
  std::vector<Frontier> frontiers;  // sorted by size, largest first (labels 1..n in that order)
  cv::Mat1i labels;                 // per cell: label of its frontier, 0 elsewhere (map's size)
};

// Frontier cells are free cells with a 4-neighbour that is unknown (-1, or neither free nor occupied, or outside
// the grid) and belongs to an unknown area of at least min_unknown_cells, and that are not set in `seen_walls`
// (empty, or of the map's size); they are grouped 8-connected (OpenCV connected components) and groups under
// min_frontier_cells dropped. An empty map has none.
FrontierMap findFrontiers(const common::OccupancyGrid& map, const FrontierOptions& options = FrontierOptions(),
                          const cv::Mat1b& seen_walls = cv::Mat1b());

// Where the laser has seen walls from close by: per cell, the first time a beam at most `range` long ended in the
// cell or up to `margin` before it (the cell lies that far behind the beam's end). The cells are those of the last
// map given to setGrid (kept across maps whose grid grows or moves; a new resolution starts afresh); scans before
// the first map are not kept.
class SeenWalls {
 public:
  SeenWalls(double range, double margin) : range_(range), margin_(margin) {}
  void setGrid(const common::OccupancyGrid& map);
  // The returns (base_link) of a scan taken with the robot at `pose` (map frame) at `time`; beams start at the
  // robot's centre.
  void addScan(const std::vector<common::Point2>& points, const common::Pose2& pose, double time);
  // 255 on the cells first seen as wall no later than `time` (the last setGrid's size; empty before it).
  cv::Mat1b seenBy(double time) const;

 private:
  double range_, margin_;
  common::OccupancyGrid grid_;  // the last map (for its grid)
  cv::Mat1d first_time_;        // per cell of grid_; +infinity: never
};

// How a goal ended, for the blacklist.
enum class GoalOutcome {
  kReached,     // reached, but its frontier is still there: it cannot be seen from there
  kFailed,      // not reached although the robot moved (no progress, or out of recoveries)
  kRobotStuck,  // not reached because the robot could not move at all (its recoveries produced no motion)
};

// Places the robot should not be sent to again (map frame): a candidate goal within `radius` of any is skipped.
// Failed places get one more try when nothing else is left: a failure can have a passing cause (a mapping glitch,
// a late control loop), and a blacklisted doorway hides everything behind it.
struct Blacklist {
  std::vector<common::Point2> points;
  double radius = 0.8;  // metres
  // Of `points`, the goals that failed while the robot could not move at all: the robot was stuck, the place may
  // be fine.
  std::vector<common::Point2> stuck_points;
  // Of `points`, the goals that failed while the robot moved and are not within `radius` of a place that already
  // had its second try.
  std::vector<common::Point2> failed_points;
  // Places released by releaseFailed(); failures near them stay blacklisted.
  std::vector<common::Point2> retried_points;
  bool contains(const common::Point2& point) const;
  // Lists the place; true when it is kept for a later release (robot stuck, or a first failure there).
  bool add(const common::Point2& point, GoalOutcome outcome);
  // Takes the stuck places off the list, so that they are tried again; returns how many there were.
  size_t releaseStuck();
  // Takes failed_points off the list for their second try (they become retried_points); returns how many.
  size_t releaseFailed();
};

// Passages the robot failed to get through. A goal that fails while the robot moves (it made no progress along
// its path) leaves the stretch of path just ahead of the robot, where the robot could not pass; once `failures`
// goals have failed from the same place in the same direction, their stretches are blocked for the planner
// (GridPlanner::setBlockedPoints), so the frontiers behind a gap the robot cannot pass are not tried over and over.
// Failures from one place in different directions mean the robot itself is stuck there: nothing is blocked from
// that place (what was is opened again).
struct BlockedPassagesOptions {
  int failures = 2;          // goals failed from one place in one direction that block their stretches (0 = never)
  double same_place = 0.5;   // metres: failures with the robot this close count as one place
  double same_direction = 0.8;  // radians: stretches whose directions from the robot differ less agree
  double skip = 0.25;        // metres of the path ahead of the robot left open (the robot stands there) ...
  double length = 1.0;       // ... up to this many metres ahead are the stretch
  double radius = 0.15;      // metres around each stretch point that are blocked
};

// Throws InputError("explorer options", ...) naming a negative, non-finite or inconsistent option.
void validate(const BlockedPassagesOptions& options);
// The explorer's parameters of the frontiers and of the blocked passages (docs/ros_api.md); the thresholds of free
// and occupied cells are the planner's.
const common::OptionTable<FrontierOptions>& frontierOptionTable();
const common::OptionTable<BlockedPassagesOptions>& blockedPassagesOptionTable();

class BlockedPassages {
 public:
  explicit BlockedPassages(const BlockedPassagesOptions& options = BlockedPassagesOptions());
  // A goal failed with the robot at `robot` following `path` (map frame, from where it started). True when
  // blockedPoints() changed.
  bool addFailure(const common::Point2& robot, const std::vector<common::Point2>& path);
  // Points whose disc of options().radius the planner must not cross.
  const std::vector<common::Point2>& blockedPoints() const { return blocked_; }
  // Opens every blocked passage again, once per explorer run (when no other goal is left, in case a passage was
  // blocked by failures that had another cause); returns how many points were unblocked (0 after the first time).
  size_t releaseOnce();
  const BlockedPassagesOptions& options() const { return options_; }

 private:
  struct Failure {
    common::Point2 robot;
    common::Point2 direction;  // unit vector from the robot to the stretch's end
    std::vector<common::Point2> stretch;
    bool blocking = false;
  };
  void collectBlocked();
  BlockedPassagesOptions options_;
  std::vector<Failure> failures_;
  std::vector<common::Point2> wedged_;  // places the robot failed from in different directions
  std::vector<common::Point2> blocked_;
  bool released_ = false;
};

struct FrontierGoal {
  int frontier_label = 0;  // label in the FrontierMap
  cv::Point cell;          // the goal cell (traversable, reachable)
  common::Point2 position = common::Point2::Zero();       // its centre, map frame
  double cost = std::numeric_limits<double>::infinity();  // the planner's path cost to it
  bool look = false;       // a place to look past a frontier from (nearestLookGoal), not to reach it
};

// The frontier nearest by path cost: over every roomy cell (planner.roomy(): at least robot_radius from obstacles)
// reachable in `planner`'s last search that lies within options.goal_reach of a frontier cell, at least options.min_goal_distance from the search's start cell
// and not in `blacklist`, the cheapest. With `previous` (the goal
// being driven to; min_goal_distance does not apply to it), that goal is kept while some frontier is still within goal_reach of it and it costs at most
// `hysteresis` metres more than the best (so replanning on every map does not make the robot dither). Nothing
// when no frontier is reachable.
std::optional<FrontierGoal> nearestFrontierGoal(const FrontierMap& frontiers, const GridPlanner& planner,
                                                const Blacklist& blacklist, const FrontierOptions& options,
                                                const std::optional<common::Point2>& previous = std::nullopt,
                                                double hysteresis = 1.0);

// The nearest look goal (FrontierOptions::look_range; nothing when it is 0): over every roomy cell reachable in
// `planner`'s last search from which a straight line of free cells, at most look_range long, reaches a frontier
// cell whose cell just beyond along that line is unknown, that is at least min_goal_distance from the search's
// start cell and not in `blacklist`, the cheapest. `previous` and `hysteresis` as for nearestFrontierGoal (the
// previous goal is kept while it is still such a cell). Meant for when nearestFrontierGoal finds nothing: the
// search must then have costs everywhere (not bounded by goal candidates).
std::optional<FrontierGoal> nearestLookGoal(const FrontierMap& frontiers, const GridPlanner& planner,
                                            const Blacklist& blacklist, const FrontierOptions& options,
                                            const std::optional<common::Point2>& previous = std::nullopt,
                                            double hysteresis = 1.0);

// Cells that nearestFrontierGoal surely accepts as goals: roomy cells within options.goal_reach of a frontier cell,
// not in `blacklist`, and at least options.min_goal_distance + `extra_distance` from `robot` (the search's start
// cell may lie up to start_escape_radius from the robot). A search bounded by them (GridPlanner::computeCostsFrom
// with the hysteresis as margin) gives nearestFrontierGoal the same goal as a full one.
cv::Mat1b goalCandidates(const FrontierMap& frontiers, const GridPlanner& planner, const Blacklist& blacklist,
                         const FrontierOptions& options, const common::Point2& robot, double extra_distance);

}  // namespace hidden_rooms::exploration
