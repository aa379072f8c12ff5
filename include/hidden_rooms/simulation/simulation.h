#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/options.h"
#include "hidden_rooms/common/velocity_command.h"
#include "hidden_rooms/simulation/laser_caster.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

class b2World;
class b2Body;

namespace hidden_rooms::simulation {

// The static part of a simulated world (world frame = environment / map frame, metres): solid convex polygons
// and doors whose leaves can be opened and closed at run time.
struct SimulationWorld {
  struct DoorLeaf {
    std::string id;                // PORTAL id of the environment
    int number = 0;                // 1-based door number of the environment
    std::vector<common::Polygon> pieces;  // the wall a closed door puts back; empty: the door cannot open (exterior)
    bool closed = false;
  };
  std::vector<common::Polygon> walls;  // convex (rectangles), collinear pieces merged
  std::vector<DoorLeaf> doors;     // indexed like Environment::doors
  // Where the robot may be: free cells (-1 unknown, 0 free, 100 occupied) and, for environments, the label of
  // the space each free cell belongs to (1 + index; 0 elsewhere); used to choose a default start pose.
  common::OccupancyGrid free_space;
  cv::Mat1w space_labels;
  std::vector<std::string> space_kinds;  // per space: its <label> (CORRIDOR, OFFICE, ...)
  // Grid worlds: the cell size of the source grid (the grid caster uses it); 0 for environments.
  double source_resolution = 0.0;

  // Index of the door with this id or 1-based number (as text); -1 when there is none.
  int findDoor(const std::string& id_or_number) const;
};

// Walls and doors of an environment as renderEnvironment draws them (wallGeometry): every door between two
// spaces becomes an openable leaf, closed when it is in `closed_door_indices` or its status is CLOSED; doors to
// the outside stay wall. Throws InputError for bad render options or door indices.
SimulationWorld worldFromEnvironment(const world::Environment& environment, const std::set<int>& closed_door_indices,
                                     const world::RenderOptions& options = world::RenderOptions());
// A Stage-style bitmap world: occupied cells merged into few axis-aligned boxes (row runs stacked while the
// next row has the same run). Unknown cells are neither solid nor places to start. Throws InputError for an
// empty grid or one without free cells.
SimulationWorld worldFromGrid(const common::OccupancyGrid& grid);

// Merges rectangles (as segmentRectangle-like 4-vertex polygons) lying on one line with the same thickness
// into one rectangle per connected run; other polygons pass unchanged. Keeps the fixture count small: floor
// plans draw shared walls twice and split straight walls into many segments.
std::vector<common::Polygon> mergeCollinearRectangles(const std::vector<common::Polygon>& rectangles);

enum class LaserCasterKind { kBox2d, kGrid };
const char* toString(LaserCasterKind kind);
// "box2d" or "grid"; throws InputError otherwise.
LaserCasterKind laserCasterFromString(const std::string& name);

// The robot: a Pioneer 3-AT (Stage's pioneer3at model), skid steer driven like a differential drive.
struct RobotOptions {
  double length = 0.626;                // footprint along x, metres, centred on base_link
  double width = 0.505;                 // footprint along y, metres
  double max_linear_velocity = 0.7;     // m/s (either direction)
  double max_angular_velocity = 2.44;   // rad/s (140 degrees/s)
  double linear_acceleration = 1.0;     // m/s^2, limit of the change of the commanded speed
  double angular_acceleration = 3.0;    // rad/s^2
  double watchdog_timeout = 0.5;        // s of simulated time without a command after which it stops; 0 = never
};

struct LaserOptions {
  int beams = 1081;
  double field_of_view = 4.71238898038469;  // radians (270 degrees), centred on the laser's x axis
  double min_range = 0.02;                  // metres
  double max_range = 30.0;                  // metres
  double range_noise = 0.01;                // standard deviation of the Gaussian range noise, metres
  double max_range_probability = 0.0;      // chance of a spurious max-range return per beam
  common::Pose2 mount{0.2, 0.0, 0.0};      // base_link -> base_laser_link
  LaserCasterKind caster = LaserCasterKind::kBox2d;
  double grid_resolution = 0.02;            // cell size of the grid caster (environments), metres
};

// Stage's odom_error: per axis, the odometry integrates the true velocity scaled by (1 + e), e drawn once per
// run (and on reset) uniformly in [-E/2, E/2]. That makes the odometry drift as Stage's does.
struct OdometryNoiseOptions {
  double x = 0.03;
  double y = 0.03;
  double yaw = 0.05;
};

struct SimulationOptions {
  double physics_step = 0.01;  // s of simulated time per step
  uint64_t seed = 0;           // same seed, same commands -> same run
  RobotOptions robot;
  LaserOptions laser;
  OdometryNoiseOptions odometry_noise;
  // Unset: the free point farthest from any wall, in a corridor when the environment labels one, yaw 0.
  std::optional<common::Pose2> start_pose;
};

// The simulator's parameters (docs/ros_api.md) with the ranges validate() enforces. Not in a table: seed (uint64),
// start_pose, laser mount and odometry noise (poses), laser caster (enum), field_of_view (degrees as a parameter).
const common::OptionTable<SimulationOptions>& simulationOptionTable();  // physics_step
const common::OptionTable<RobotOptions>& robotOptionTable();
const common::OptionTable<LaserOptions>& laserOptionTable();

// Throws InputError("NAME", ...) for a field outside its table's range, InputError("simulation options", ...) for
// the other rules (field_of_view, min_range < max_range, odometry noise, finite poses).
void validate(const SimulationOptions& options);

// How far the two casters agree on one scan: a beam agrees when both ranges are within `tolerance`, or when both
// hit and the grid's hit lies within 1.5 grid cells of the exact geometry (the same wall, reached at a grazing
// angle where the grid's cell-sized steps move the hit far along the beam).
struct CasterAgreement {
  int beams = 0;
  int within_tolerance = 0;
  int same_surface = 0;                    // agreeing beams beyond the tolerance
  std::vector<float> absolute_differences;  // per beam, metres
};
class Simulation;
void compareCasters(const Simulation& simulation, double tolerance, CasterAgreement* agreement);

// A world with one robot in it, stepped with a fixed physics step (Box2D). Deterministic: the same world,
// options, seed and calls give the same poses and scans.
class Simulation {
 public:
  // Throws InputError for bad options or a start pose inside a wall.
  Simulation(const SimulationWorld& world, const SimulationOptions& options);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // The velocity the robot should reach (clamped to the limits, approached within the acceleration limits).
  // Resets the watchdog. Throws InputError for a non-finite command (the current one stays).
  void setCommand(const common::VelocityCommand& command);
  // Advances one physics step: watchdog, acceleration limits, Box2D step (collisions), odometry.
  void step();

  double time() const { return static_cast<double>(steps_) * options_.physics_step; }
  uint64_t steps() const { return steps_; }
  common::Pose2 truePose() const;      // base_link in the world frame
  common::Pose2 laserPose() const;     // base_laser_link in the world frame
  common::Pose2 odometryPose() const;  // base_link in the odom frame (starts at 0 at the start pose)
  common::VelocityCommand velocity() const { return velocity_; }  // measured over the last step, base_link frame
  common::VelocityCommand odometryVelocity() const;               // the same with the odometry's error
  const common::Pose2& startPose() const { return start_pose_; }

  // A scan at the current pose from the configured caster, with range noise and spurious max-range returns.
  void scan(std::vector<float>* ranges);
  // A noise-free scan from the given caster (for benchmarks and tests).
  void scanWith(LaserCasterKind kind, std::vector<float>* ranges) const;
  const common::LaserGeometry& laserGeometry() const { return laser_; }
  // True when a wall or closed door lies within `radius` of `point` (Box2D geometry, exact).
  bool solidNear(const common::Point2& point, double radius) const;
  // Cell size of the grid caster's grid, metres.
  double gridResolution() const { return wall_grid_.resolution; }

  // The robot back at its start pose, at rest, odometry at zero (new odometry error drawn); time goes on.
  void reset();
  // Opens or closes the door with this id or number. Throws InputError for an unknown door or one that
  // cannot open (to the outside).
  void setDoor(const std::string& id_or_number, bool open);
  const SimulationWorld& world() const { return world_; }
  int staticFixtureCount() const;
  const SimulationOptions& options() const { return options_; }

 private:
  void drawOdometryError();
  void rebuildGrid();
  const LaserCaster& caster(LaserCasterKind kind) const;

  SimulationWorld world_;
  SimulationOptions options_;
  common::LaserGeometry laser_;
  std::unique_ptr<b2World> physics_;
  b2Body* robot_ = nullptr;
  std::vector<b2Body*> door_bodies_;  // per door, null when it has no leaf
  std::unique_ptr<Box2dLaserCaster> box2d_caster_;
  std::unique_ptr<GridLaserCaster> grid_caster_;
  common::OccupancyGrid wall_grid_;  // the walls alone, for the grid caster; closed leaves are added on top
  std::mt19937_64 random_;
  common::Pose2 start_pose_;
  uint64_t steps_ = 0;
  common::VelocityCommand target_;
  common::VelocityCommand commanded_;
  common::VelocityCommand velocity_;
  double last_command_time_ = 0.0;
  common::Pose2 odometry_;
  double odometry_error_[3] = {0.0, 0.0, 0.0};
};

}  // namespace hidden_rooms::simulation
