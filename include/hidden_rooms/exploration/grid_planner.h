#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/options.h"

namespace hidden_rooms::exploration {

struct GridPlannerOptions {
  int free_threshold = 19;        // cells with 0 <= value <= this are free (map_saver's 0.196)
  int occupied_threshold = 65;    // cells with value >= this are obstacles (map_saver's 0.65)
  double robot_radius = 0.38;     // metres: the clearance paths keep where they can; goals keep it always
  double min_clearance = 0.30;    // metres: cells closer than this to an obstacle cannot hold the robot's centre;
                                  // between this and robot_radius only paths pass (no goals), at narrow_cost_factor
                                  // times the highest proximity cost, so that a door the map draws narrower than
                                  // 2 robot_radius stays passable
  double narrow_cost_factor = 3.0;  // >= 1
  double cost_radius = 1.0;       // metres: within this distance of an obstacle a cell costs extra ...
  double cost_weight = 10.0;      // ... up to 1 + cost_weight times its length at robot_radius, falling linearly
  double start_escape_radius = 0.5;  // metres: a start cell in the inflated zone is replaced by the nearest
                                     // traversable cell within this distance
  double smoothing_window = 0.3;  // metres: half-width of the moving average applied to a path (0 = none)
};

// Throws InputError("explorer options", ...) naming a non-finite, negative or inconsistent option.
void validate(const GridPlannerOptions& options);
// The explorer's parameters of the planner (docs/ros_api.md).
const common::OptionTable<GridPlannerOptions>& gridPlannerOptionTable();

// Wavefront (Dijkstra) planner on an occupancy grid. Obstacles (value >= occupied_threshold) are inflated by
// min_clearance with a distance transform; the robot's centre may stand on free cells outside the inflation
// (unknown cells are neither obstacle nor traversable), and on the free cells of its trail (setTrail); cells at least
// robot_radius from obstacles are roomy (goals go there). Moving between 8-neighbours costs the step's length
// (metres) times the mean of the two cells' proximity factors, so paths keep away from walls where they can.
class GridPlanner {
 public:
  explicit GridPlanner(const GridPlannerOptions& options = GridPlannerOptions());

  // Builds the inflated cost map; an empty map gives a planner where nothing is reachable.
  void setMap(const common::OccupancyGrid& map);
  // Cells within `radius` (metres) of these points (map frame) are neither traversable nor roomy, in this map and
  // the next ones, until set again (an empty list unblocks). Applies at once; the next computeCostsFrom uses it.
  void setBlockedPoints(const std::vector<common::Point2>& points, double radius);
  // The robot's latest path (map frame, in driving order): the free cells along it are traversable even closer to
  // obstacles than min_clearance, since the robot's centre was there (a way in that the map then drew narrower),
  // in this map and the next ones, until set again; blocked points still win. Steps longer than a metre (a
  // localisation jump) are not drawn. Applies at once.
  void setTrail(const std::vector<common::Point2>& trail);
  const common::OccupancyGrid& map() const { return map_; }

  // Costs from `start` (map frame) to every traversable cell. False (and nothing reachable) when the start lies
  // outside the map or no traversable cell is within start_escape_radius of it. With `targets` (255 on the cells a
  // search is for; the map's size), the search stops once every cell left costs more than the cheapest target
  // reached plus `margin`: the costs up to that bound are exact, those beyond it stay infinite (the whole map when
  // no target is reachable).
  bool computeCostsFrom(const common::Point2& start, const cv::Mat1b& targets = cv::Mat1b(), double margin = 0.0);

  // Path cost (metres weighted by proximity) from the last start to the cell; +infinity when unreachable or
  // outside the grid.
  double costTo(int col, int row) const;
  double costTo(const common::Point2& point) const;
  // 255 where the robot's centre may stand (free and at least min_clearance from obstacles), else 0.
  const cv::Mat1b& traversable() const { return traversable_; }
  // 255 where it stands with room to spare (traversable and at least robot_radius from obstacles), else 0.
  const cv::Mat1b& roomy() const { return roomy_; }
  // Distance (metres) from each cell to the nearest obstacle cell.
  const cv::Mat1f& obstacleDistance() const { return obstacle_distance_; }
  // The last search stopped at its targets' bound (some reachable cells were left at infinite cost).
  bool searchWasBounded() const { return search_bounded_; }
  // Cell where the last search started (the start or the cell it escaped to); (-1, -1) before any.
  cv::Point startCell() const { return start_cell_; }

  // Cell-centre path (map frame) from the start to a reachable cell, smoothed with a moving average that keeps
  // every point on a traversable cell; the first point is the start cell's centre, the last the goal cell's.
  // Empty when the cell is unreachable.
  std::vector<common::Point2> pathTo(int col, int row) const;

 private:
  GridPlannerOptions options_;
  common::OccupancyGrid map_;
  cv::Mat1b traversable_;
  cv::Mat1b roomy_;
  cv::Mat1f obstacle_distance_;
  cv::Mat1f step_factor_;  // proximity factor of each cell (>= 1)
  cv::Mat1d cost_;         // path cost from the start (infinity where unreachable)
  cv::Mat1i parent_;       // index (row * width + col) of the predecessor, -1 at the start / unreached
  cv::Point start_cell_{-1, -1};
  bool search_bounded_ = false;
  std::vector<common::Point2> blocked_points_;
  double blocked_radius_ = 0.0;
  std::vector<common::Point2> trail_;
};

// Length (metres) of a polyline.
double pathLength(const std::vector<common::Point2>& path);

}  // namespace hidden_rooms::exploration
