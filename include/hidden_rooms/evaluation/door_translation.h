#pragma once

#include <set>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/pose_log.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

namespace hidden_rooms::evaluation {

// Where a door of the world lies in the map a robot built (docs/method.md#closed-doors-in-the-map). `truth` is the
// robot's true trajectory (world frame), `estimate` its SLAM trajectory (map frame), both timed on the same clock.
struct DoorInMap {
  common::Point2 position = common::Point2::Zero();  // map frame, metres
  double wall_angle = 0.0;           // direction of the door's wall in the map frame, radians in [0, pi)
  double time = 0.0;                 // when the robot was closest to the door
  double robot_distance = 0.0;       // that closest distance, metres
  // The rigid transform that carried the door over, M_r(t_min) * GT_r(t_min)^-1: the world placed in the map as
  // the map shows the door's surroundings.
  common::Pose2 map_from_world;
};

// The thesis's translation made rigid: the robot pose closest to the door (t_min) is looked up in both
// trajectories and the door is carried over in the robot's frame, M_d = M_r(t_min) * GT_r(t_min)^-1 * GT_d, so a
// map frame rotated against the world (the map starts at the robot's first pose) is handled; with equal headings
// this is the thesis's M_r(t_min) + (GT_d - GT_r(t_min)). Both trajectories must not be empty.
DoorInMap translateDoor(const common::Point2& door_world, double wall_angle_world,
                        const std::vector<common::TimedPose>& truth, const std::vector<common::TimedPose>& estimate);

// The given doors of `environment` (indices) as a doors.yaml in the map frame: id = the door's number, width
// `door_width`, orientation from the translated wall direction (O when it runs closer to x than to y), and with
// `with_map_from_world` the transform that carried each door over.
common::DoorsFile translateDoors(const world::Environment& environment, const std::vector<int>& door_indices,
                                 const std::vector<common::TimedPose>& truth,
                                 const std::vector<common::TimedPose>& estimate, double door_width,
                                 bool with_map_from_world = false);

// The rigid transform world <- map that best overlays the estimated positions on the true ones at the same
// times (least squares over the estimate's poses, Umeyama without scale). Used to score a map against its
// world, never by the prediction. Throws InputError when fewer than two poses overlap in time or they do not
// span any distance.
common::Pose2 fitWorldFromMap(const std::vector<common::TimedPose>& truth,
                              const std::vector<common::TimedPose>& estimate);

// The same fit over the poses whose true position lies within `radius` of `centre` (world frame): where the map
// shows a place, free of the drift a long run accumulates elsewhere. The whole run when too few poses (< 20) are
// near.
common::Pose2 fitWorldFromMapNear(const std::vector<common::TimedPose>& truth,
                                  const std::vector<common::TimedPose>& estimate, const common::Point2& centre,
                                  double radius);

// The world's ground truth moved into the grid of `map`: `labels` (map's size) holds 1 + space index on the
// free cells of each space (nearest cell of `rendered` after the transform), 0 elsewhere.
cv::Mat1w spaceLabelsInMap(const world::RenderedEnvironment& rendered, const common::OccupancyGrid& map,
                           const common::Pose2& world_from_map);

// Label image of the rooms behind `door_indices` in the map's grid (k = room behind the k-th door, 1-based), as
// predict_rooms_offline --gt-rooms reads it. Throws InputError for a door that is not closable.
cv::Mat1w trueRoomsInMap(const world::Environment& environment, const std::vector<int>& door_indices,
                         const cv::Mat1w& space_labels_in_map);

// Free cells of `rendered` a robot starting at `start` (world frame) can reach. With `clearance` 0 every free cell
// 4-connected to the free cell nearest the start (within a few cells); with a clearance (metres, the robot's
// half width) the free cells its body can cover: within `clearance` of a centre position that keeps `clearance`
// from every non-free cell and is connected to the start through such positions (a room behind a gap narrower
// than the robot is not reachable). Throws InputError when `start` is outside the grid or not near free space
// (with a clearance: no centre position within 1 m of it).
cv::Mat1b reachableFreeArea(const common::OccupancyGrid& rendered, const common::Point2& start, double clearance = 0.0);

// The same for the cells of `rendered`, decided on `fine`, the same world rendered at a finer resolution: a cell
// counts when the fine cell at its centre is reached. A map's 5 cm grid cannot tell a door a few centimetres
// narrower than the robot from one it passes (on it a 0.48 m door lets a 0.50 m body through); a 1 or 2 cm one can.
cv::Mat1b reachableFreeArea(const common::OccupancyGrid& rendered, const common::OccupancyGrid& fine,
                            const common::Point2& start, double clearance);

}  // namespace hidden_rooms::evaluation
