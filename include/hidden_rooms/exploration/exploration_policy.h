#pragma once

#include <cstddef>
#include <future>
#include <optional>
#include <string>
#include <vector>

#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/options.h"
#include "hidden_rooms/common/velocity_command.h"
#include "hidden_rooms/exploration/frontier.h"
#include "hidden_rooms/exploration/grid_planner.h"
#include "hidden_rooms/exploration/path_follower.h"

namespace hidden_rooms::exploration {

// What the exploration policy needs (the explorer node's parameters of the same names; docs/ros_api.md).
struct ExplorationPolicyOptions {
  GridPlannerOptions planner;    // inflation, proximity cost, smoothing
  FrontierOptions frontiers;     // frontier filtering, goal reach
  PathFollowerOptions follower;  // pure pursuit, laser speed limit, recovery
  BlockedPassagesOptions passages;  // gaps the robot failed to pass, blocked for the planner
  double replan_interval = 2.0;     // seconds between replans without a new map (0 = only on new maps)
  double goal_hysteresis = 1.0;     // metres of path cost the current goal may exceed the best before switching
  double blacklist_radius = 0.8;    // metres around a failed or reached goal where no goal is chosen again
  int done_confirmations = 3;       // plans on new maps in a row without a reachable frontier before done
  double search_angular_velocity = 0.4;  // rad/s turned in place while there is no goal (and not done)
  double obstacle_memory = 1.5;     // seconds laser points are remembered (for the robot's blind rear)
  double trail_length = 20.0;       // metres of the robot's latest path made passable when nothing else is (0 = never)
  // The costly part of a plan (the map's cost map, the frontiers, the costs from the robot) on a thread of its
  // own, so that update() keeps steering along the current path meanwhile; the goal is chosen at the first update
  // after it finished. Off: update() plans in place (deterministic: the same inputs give the same commands).
  bool background_planning = false;
};

// The explorer's parameters of the policy itself (docs/ros_api.md); the nested options have tables of their own.
const common::OptionTable<ExplorationPolicyOptions>& explorationPolicyOptionTable();

// Something the policy did or found, for the log; in the order it happened.
enum class ExplorationEventType {
  kMapUnusable,       // the map set last could not be used (`message`): the plan did nothing, the old map stays
  kStartBlocked,      // the robot (`position`) is not within start_escape_radius of a traversable cell: no plan
  kGoalChosen,        // a new goal at `position` (`cost`, `path_length`, `look`); replanning the same goal is
                      // no new goal
  kGoalReached,       // the goal at `position` was reached; blacklisted
  kGoalFailed,        // not reached at `position` after `recoveries` while the robot moved; blacklisted, with a
                      // second try later when `retry_later`
  kGoalFailedStuck,   // not reached at `position`: its `recoveries` did not move the robot; blacklisted until
                      // no other goal is left
  kPassageBlocked,    // failed goals from the robot's `position` in one direction: the path ahead is blocked
  kPassageOpened,     // failed goals from the robot's `position` in different directions: opened again there
  kStuckReleased,     // no other goal: `count` places of goals failed with the robot stuck are tried again
  kPassagesReleased,  // no other goal: `count` blocked points opened again (once per run)
  kFailedReleased,    // no other goal: `count` failed places get their second try
  kTrailOpened,       // no other goal: the robot's latest `path_length` metres of path are passable until the goal
                      // they give ends
  kNoGoal,            // no reachable frontier (`count` frontiers, `blacklisted` places), not done yet
  kDone,              // done_confirmations plans on new maps in a row found no goal (`blacklisted` places)
  kResumed,           // after done, a reachable frontier appeared
};

struct ExplorationEvent {
  ExplorationEventType type = ExplorationEventType::kNoGoal;
  common::Point2 position =
      common::Point2::Zero();        // the goal's (goal events) or the robot's (passages, kStartBlocked)
  size_t count = 0;                  // places or points released; frontiers (kNoGoal)
  size_t blacklisted = 0;            // blacklisted places (kNoGoal, kDone)
  int recoveries = 0;                // of the failed goal
  bool retry_later = false;          // kGoalFailed: it gets a second try when nothing else is left
  double cost = 0.0;                 // kGoalChosen: path cost
  double path_length = 0.0;          // kGoalChosen, kTrailOpened: metres
  bool look = false;                 // kGoalChosen: a look goal (nearestLookGoal): no frontier is reachable
  std::string message;               // kMapUnusable: why
};

// One control step's outcome.
struct ExplorationStep {
  common::VelocityCommand command;
  bool planned = false;  // a plan computed frontiers (frontiers(), goal(), the path and the blacklist are new)
  std::vector<ExplorationEvent> events;
};

// Nearest-frontier exploration without ROS: on each new map (and every replan_interval, not during a recovery
// manoeuvre) the frontiers, the nearest goal by path cost (the current one kept within goal_hysteresis) and a
// path to it; pure pursuit along it with the laser points of the last obstacle_memory seconds. A reached goal is
// blacklisted; a failed one too, and its failures may block the passage ahead. When no goal is left, blocked
// goals are released in this order, each only when the ones before gave no goal: the places where the robot was
// stuck, the blocked passages (once), the failed places (their one second try); then the way the robot came
// (its latest trail_length metres of path become passable until the goal they gave ends); with still none, a
// place to look past a frontier from (nearestLookGoal). Done after done_confirmations plans on new maps in a row
// without a goal; until then, and without a goal, it turns in place. Times are seconds of a monotonic clock (the
// node uses ROS time); differences within half a nanosecond count as equal. With
// background_planning, a plan started at one update is used at the first update after it finished (the robot
// keeps following its path meanwhile, stands still when its goal ended, and turns in place when it had none);
// one plan runs at a time.
class ExplorationPolicy {
 public:
  explicit ExplorationPolicy(const ExplorationPolicyOptions& options = ExplorationPolicyOptions());
  ~ExplorationPolicy();  // waits for a plan running in the background
  ExplorationPolicy(const ExplorationPolicy&) = delete;
  ExplorationPolicy& operator=(const ExplorationPolicy&) = delete;

  // A new map (map frame): the next step plans with it.
  void setMap(const common::OccupancyGrid& map);
  // A new map that could not be read (`reason`): the next step's plan reports it (kMapUnusable) and keeps the
  // old map.
  void setUnusableMap(const std::string& reason);
  // The returns (base_link) of a new scan, with the robot at `pose` (map frame) at `time`.
  void addScan(const std::vector<common::Point2>& points, const common::Pose2& pose, double time);
  // The robot is held still from outside at `time` (map, pose or scan stale); see PathFollower::hold.
  void hold(double time);
  // The command for the robot at `pose` (map frame) at `time`, planning when due.
  ExplorationStep update(const common::Pose2& pose, double time);

  bool done() const { return done_; }
  const std::optional<FrontierGoal>& goal() const { return goal_; }
  // Of the last plan that got that far.
  const FrontierMap& frontiers() const { return frontiers_; }
  const GridPlanner& planner() const { return planner_; }
  const PathFollower& follower() const { return follower_; }
  const Blacklist& blacklist() const { return blacklist_; }
  const BlockedPassages& passages() const { return passages_; }
  const ExplorationPolicyOptions& options() const { return options_; }

 private:
  enum class PendingMap { kNone, kUsable, kUnusable };
  // The costly part of a plan, on a planner of its own (safe on another thread).
  struct CostMap {
    GridPlanner planner;
    FrontierMap frontiers;
    bool start_reachable = false;
    bool new_map = false;
  };
  // The wavefront stops past the cheapest goal candidate plus goal_hysteresis (goalCandidates): the nearest goal
  // and the kept one are the same as with costs everywhere.
  static CostMap computeCostMap(const ExplorationPolicyOptions& options, const Blacklist& blacklist,
                                const std::vector<common::Point2>& blocked_points,
                                const std::vector<common::Point2>& trail, const common::OccupancyGrid& map,
                                const cv::Mat1b& seen_walls, const common::Point2& robot, bool new_map);
  // Starts a plan from `pose` (in the background or in place): takes the pending map, if any.
  void plan(const common::Pose2& pose, double time, ExplorationStep* step);
  // Takes a finished cost map, chooses a goal and a path from `pose`, releasing blocked goals when none is left;
  // counts towards done.
  void choose(CostMap cost_map, const common::Pose2& pose, double time, ExplorationStep* step);
  // Adds the robot's position to the trail (every 5 cm) and drops what lies beyond trail_length.
  void recordTrail(const common::Point2& position);
  // The trail while it is open (plans use it), else none.
  std::vector<common::Point2> openTrail() const { return trail_open_ ? trail_ : std::vector<common::Point2>(); }
  // Blacklists the goal that just ended (reached or failed) and records failed passages.
  void finishGoal(const common::Pose2& pose, FollowerState outcome, ExplorationStep* step);

  ExplorationPolicyOptions options_;
  GridPlanner planner_;
  PathFollower follower_;
  Blacklist blacklist_;
  BlockedPassages passages_;
  ObstacleMemory obstacle_memory_;
  SeenWalls seen_walls_;
  std::vector<common::Point2> trail_;  // the robot's latest trail_length metres of path, oldest first
  double trail_metres_ = 0.0;           // its length
  bool trail_open_ = false;             // plans use the trail (from kTrailOpened until the next goal ends)
  double map_time_ = 0.0;  // time of the update that took the last usable map
  PendingMap pending_map_ = PendingMap::kNone;
  common::OccupancyGrid next_map_;
  std::string unusable_reason_;
  FrontierMap frontiers_;
  std::optional<FrontierGoal> goal_;
  double last_plan_ = 0.0;  // time of the last plan (0 before the first, as ROS time starts)
  std::future<CostMap> background_plan_;  // valid while a plan runs in the background
  bool goal_ended_ = false;  // the goal ended and the plan for the next one is still running
  int plans_without_goal_ = 0;
  bool done_ = false;
};

}  // namespace hidden_rooms::exploration
