#include "hidden_rooms/simulation/simulation.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

#include <box2d/box2d.h>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/range_scan.h"

namespace hidden_rooms::simulation {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMinPieceSize = 0.01;  // metres: thinner or shorter pieces are dropped (Box2D welds vertices)
constexpr int8_t kOccupiedThreshold = 65;  // map_saver's: cells at or above are solid

bool finite(const common::Pose2& pose) {
  return std::isfinite(pose.x) && std::isfinite(pose.y) && std::isfinite(pose.yaw);
}

// A 4-vertex polygon with perpendicular sides, as centre line [start, end] and half width.
struct Rectangle {
  common::Point2 start, end;
  double half_width = 0.0;
};

bool asRectangle(const common::Polygon& polygon, Rectangle* rectangle) {
  if (polygon.size() != 4) return false;
  const common::Point2 side = polygon[1] - polygon[0], across = polygon[0] - polygon[3];
  if (side.norm() < 1e-9 || across.norm() < 1e-9) return false;
  if (std::abs(side.dot(across)) > 1e-6 * side.norm() * across.norm()) return false;
  if ((polygon[2] - polygon[1] + across).norm() > 1e-6 || (polygon[3] - polygon[2] + side).norm() > 1e-6) return false;
  rectangle->start = 0.5 * (polygon[0] + polygon[3]);
  rectangle->end = 0.5 * (polygon[1] + polygon[2]);
  rectangle->half_width = 0.5 * across.norm();
  return true;
}

common::Polygon rectanglePolygon(const common::Point2& start, const common::Point2& end, double half_width) {
  const common::Point2 along = (end - start).normalized();
  const common::Point2 across(-along.y(), along.x());
  return {start + half_width * across, end + half_width * across, end - half_width * across,
          start - half_width * across};
}

bool usablePiece(const common::Polygon& polygon) {
  if (polygon.size() < 3 || common::area(polygon) < kMinPieceSize * kMinPieceSize) return false;
  for (size_t k = 0; k < polygon.size(); ++k)
    if ((polygon[(k + 1) % polygon.size()] - polygon[k]).norm() < kMinPieceSize) return false;
  return true;
}

b2PolygonShape toShape(const common::Polygon& polygon) {
  std::vector<b2Vec2> points;
  for (const common::Point2& p : polygon) points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
  b2PolygonShape shape;
  shape.Set(points.data(), static_cast<int32>(points.size()));
  return shape;
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// Marks the cells of `grid` whose centres lie inside the convex polygon `polygon` (exact, so that the grid's
// walls are neither fatter nor thinner than the polygons on average; OpenCV's fillPoly also takes cells the
// outline merely touches).
void fillConvexPolygon(common::OccupancyGrid* grid, const common::Polygon& polygon, int8_t value) {
  if (polygon.size() < 3) return;
  double y_low = polygon[0].y(), y_high = y_low;
  for (const common::Point2& p : polygon) {
    y_low = std::min(y_low, p.y());
    y_high = std::max(y_high, p.y());
  }
  const double r = grid->resolution;
  // Rows counted from the bottom: cell centre y = origin.y + (j + 0.5) r.
  const int j0 = std::max(0, static_cast<int>(std::ceil((y_low - grid->origin.y()) / r - 0.5)));
  const int j1 = std::min(grid->height() - 1, static_cast<int>(std::floor((y_high - grid->origin.y()) / r - 0.5)));
  for (int j = j0; j <= j1; ++j) {
    const double y = grid->origin.y() + (j + 0.5) * r;
    double x_low = std::numeric_limits<double>::infinity(), x_high = -x_low;
    for (size_t k = 0; k < polygon.size(); ++k) {
      const common::Point2& a = polygon[k];
      const common::Point2& b = polygon[(k + 1) % polygon.size()];
      if ((a.y() > y) == (b.y() > y) && a.y() != y) continue;
      if (a.y() == b.y()) {
        x_low = std::min({x_low, a.x(), b.x()});
        x_high = std::max({x_high, a.x(), b.x()});
        continue;
      }
      const double x = a.x() + (y - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
      x_low = std::min(x_low, x);
      x_high = std::max(x_high, x);
    }
    if (x_low > x_high) continue;
    const int i0 = std::max(0, static_cast<int>(std::ceil((x_low - grid->origin.x()) / r - 0.5)));
    const int i1 = std::min(grid->width() - 1, static_cast<int>(std::floor((x_high - grid->origin.x()) / r - 0.5)));
    int8_t* row = grid->cells.ptr<int8_t>(grid->height() - 1 - j);
    for (int i = i0; i <= i1; ++i) row[i] = value;
  }
}

// Collects the fixtures of other bodies whose shapes overlap `shape` at `transform`.
class OverlapQuery : public b2QueryCallback {
 public:
  OverlapQuery(const b2Shape* shape, const b2Transform& transform, const b2Body* ignored)
      : shape_(shape), transform_(transform), ignored_(ignored) {}
  bool ReportFixture(b2Fixture* fixture) override {
    if (fixture->GetBody() == ignored_ || !fixture->GetBody()->IsEnabled()) return true;
    if (b2TestOverlap(shape_, 0, fixture->GetShape(), 0, transform_, fixture->GetBody()->GetTransform())) {
      overlaps_ = true;
      return false;
    }
    return true;
  }
  bool overlaps() const { return overlaps_; }

 private:
  const b2Shape* shape_;
  b2Transform transform_;
  const b2Body* ignored_;
  bool overlaps_ = false;
};

}  // namespace

int SimulationWorld::findDoor(const std::string& id_or_number) const {
  for (size_t d = 0; d < doors.size(); ++d)
    if (doors[d].id == id_or_number) return static_cast<int>(d);
  if (!id_or_number.empty() && std::all_of(id_or_number.begin(), id_or_number.end(), ::isdigit) &&
      id_or_number.size() < 9) {
    const int number = std::stoi(id_or_number);
    for (size_t d = 0; d < doors.size(); ++d)
      if (doors[d].number == number) return static_cast<int>(d);
  }
  return -1;
}

std::vector<common::Polygon> mergeCollinearRectangles(const std::vector<common::Polygon>& rectangles) {
  struct Run {
    common::Point2 direction, normal;
    double offset = 0.0, half_width = 0.0;
    std::vector<std::pair<double, double>> intervals;
  };
  std::map<std::tuple<long long, long long, long long>, Run> runs;
  std::vector<common::Polygon> merged;
  for (const common::Polygon& polygon : rectangles) {
    Rectangle rectangle;
    if (!asRectangle(polygon, &rectangle)) {
      merged.push_back(polygon);
      continue;
    }
    common::Point2 direction = (rectangle.end - rectangle.start).normalized();
    if (direction.y() < -1e-12 || (std::abs(direction.y()) <= 1e-12 && direction.x() < 0)) direction = -direction;
    const common::Point2 normal(-direction.y(), direction.x());
    const double angle = std::atan2(direction.y(), direction.x());
    const double offset = normal.dot(rectangle.start);
    const auto key = std::make_tuple(std::llround(angle * 1e6), std::llround(offset * 1e4),
                                     std::llround(rectangle.half_width * 1e5));
    auto [it, inserted] = runs.try_emplace(key);
    if (inserted) {
      it->second.direction = direction;
      it->second.normal = normal;
      it->second.offset = offset;
      it->second.half_width = rectangle.half_width;
    }
    const double s0 = direction.dot(rectangle.start), s1 = direction.dot(rectangle.end);
    it->second.intervals.emplace_back(std::min(s0, s1), std::max(s0, s1));
  }
  for (auto& [key, run] : runs) {
    std::sort(run.intervals.begin(), run.intervals.end());
    std::vector<std::pair<double, double>> joined;
    for (const auto& interval : run.intervals) {
      if (!joined.empty() && interval.first <= joined.back().second + 1e-6)
        joined.back().second = std::max(joined.back().second, interval.second);
      else
        joined.push_back(interval);
    }
    for (const auto& [s0, s1] : joined)
      merged.push_back(rectanglePolygon(run.offset * run.normal + s0 * run.direction,
                                        run.offset * run.normal + s1 * run.direction, run.half_width));
  }
  return merged;
}

SimulationWorld worldFromEnvironment(const world::Environment& environment, const std::set<int>& closed_door_indices,
                                     const world::RenderOptions& options) {
  for (int index : closed_door_indices)
    if (index < 0 || index >= static_cast<int>(environment.doors.size()))
      throw common::InputError("simulation world", "closed door index " + std::to_string(index) + " does not exist");
  std::set<int> openable;
  for (size_t d = 0; d < environment.doors.size(); ++d)
    if (environment.doors[d].space_indices.size() >= 2) openable.insert(static_cast<int>(d));
  const world::WallGeometry geometry = world::wallGeometry(environment, openable, options);

  SimulationWorld world;
  for (const common::Polygon& wall : mergeCollinearRectangles(geometry.walls))
    if (usablePiece(wall)) world.walls.push_back(wall);
  for (size_t d = 0; d < environment.doors.size(); ++d) {
    const world::Door& door = environment.doors[d];
    SimulationWorld::DoorLeaf leaf;
    leaf.id = door.id;
    leaf.number = door.number;
    for (const common::Polygon& piece : geometry.door_leaves[d])
      if (usablePiece(piece)) leaf.pieces.push_back(piece);
    leaf.closed = openable.count(static_cast<int>(d)) == 0 || door.status == world::DoorStatus::kClosed ||
                  closed_door_indices.count(static_cast<int>(d)) > 0;
    world.doors.push_back(leaf);
  }
  // The ground truth with every door closed: the robot starts in a space, not in a doorway.
  std::set<int> all_doors;
  for (size_t d = 0; d < environment.doors.size(); ++d) all_doors.insert(static_cast<int>(d));
  const world::RenderedEnvironment rendered = world::renderEnvironment(environment, all_doors, options);
  world.free_space = rendered.map;
  world.space_labels = rendered.space_labels;
  for (const world::Space& space : environment.spaces) world.space_kinds.push_back(space.label);
  return world;
}

SimulationWorld worldFromGrid(const common::OccupancyGrid& grid) {
  if (grid.empty()) throw common::InputError("simulation world", "the map is empty");
  if (cv::countNonZero(grid.cells == common::OccupancyGrid::kFree) == 0)
    throw common::InputError("simulation world", "the map has no free cell to put the robot on");
  SimulationWorld world;
  world.free_space = grid;
  world.source_resolution = grid.resolution;
  const cv::Mat1b solid = grid.cells >= kOccupiedThreshold;
  // Row runs of solid cells, stacked into boxes while the next row has exactly the same run.
  std::map<std::pair<int, int>, int> open;  // [begin, end) columns -> first row
  auto box = [&](int c0, int c1, int r0, int r1) {
    const double x0 = grid.origin.x() + c0 * grid.resolution, x1 = grid.origin.x() + c1 * grid.resolution;
    const double y0 = grid.origin.y() + (grid.height() - r1) * grid.resolution;
    const double y1 = grid.origin.y() + (grid.height() - r0) * grid.resolution;
    world.walls.push_back(
        {common::Point2(x0, y0), common::Point2(x1, y0), common::Point2(x1, y1), common::Point2(x0, y1)});
  };
  for (int row = 0; row <= grid.height(); ++row) {
    std::set<std::pair<int, int>> runs;
    if (row < grid.height()) {
      const uchar* line = solid.ptr<uchar>(row);
      for (int col = 0; col < grid.width();) {
        if (line[col] == 0) {
          ++col;
          continue;
        }
        const int begin = col;
        while (col < grid.width() && line[col] != 0) ++col;
        runs.insert({begin, col});
      }
    }
    for (auto it = open.begin(); it != open.end();) {
      if (runs.count(it->first) == 0) {
        box(it->first.first, it->first.second, it->second, row);
        it = open.erase(it);
      } else {
        ++it;
      }
    }
    for (const auto& run : runs) open.emplace(run, row);
  }
  return world;
}

const char* toString(LaserCasterKind kind) { return kind == LaserCasterKind::kBox2d ? "box2d" : "grid"; }

LaserCasterKind laserCasterFromString(const std::string& name) {
  if (name == "box2d") return LaserCasterKind::kBox2d;
  if (name == "grid") return LaserCasterKind::kGrid;
  throw common::InputError("simulation options", "laser caster must be 'box2d' or 'grid', not '" + name + "'");
}

const common::OptionTable<SimulationOptions>& simulationOptionTable() {
  using O = SimulationOptions;
  static const common::OptionTable<O> table{
      {"physics_step", &O::physics_step, "fixed Box2D step, simulated seconds", common::ParameterRange{0, 0.1, true}},
  };
  return table;
}

const common::OptionTable<RobotOptions>& robotOptionTable() {
  using O = RobotOptions;
  static const common::OptionTable<O> table{
      {"footprint_length", &O::length, "robot box along x, metres, centred on base_link", common::above(0)},
      {"footprint_width", &O::width, "robot box along y, metres", common::above(0)},
      {"max_linear_velocity", &O::max_linear_velocity, "m/s", common::above(0)},
      {"max_angular_velocity", &O::max_angular_velocity, "rad/s", common::above(0)},
      {"linear_acceleration", &O::linear_acceleration, "m/s^2", common::above(0)},
      {"angular_acceleration", &O::angular_acceleration, "rad/s^2", common::above(0)},
      {"watchdog_timeout", &O::watchdog_timeout, "simulated seconds without a command before stopping; 0 = never",
       common::atLeast(0)},
  };
  return table;
}

const common::OptionTable<LaserOptions>& laserOptionTable() {
  using O = LaserOptions;
  static const common::OptionTable<O> table{
      {"laser_beams", &O::beams, "beams", common::between(1, 100000)},
      {"laser_min_range", &O::min_range, "metres", common::atLeast(0)},
      {"laser_max_range", &O::max_range, "metres", common::above(0)},
      {"laser_range_noise", &O::range_noise, "standard deviation of the Gaussian range noise, metres",
       common::atLeast(0)},
      {"laser_max_range_probability", &O::max_range_probability, "chance of a spurious max-range return per beam",
       common::between(0, 1)},
      {"laser_grid_resolution", &O::grid_resolution, "cell size of the grid caster, metres", common::above(0)},
  };
  return table;
}

void validate(const SimulationOptions& options) {
  common::validateOptions(simulationOptionTable(), options);
  common::validateOptions(robotOptionTable(), options.robot);
  common::validateOptions(laserOptionTable(), options.laser);
  auto require = [](bool ok, const std::string& problem) {
    if (!ok) throw common::InputError("simulation options", problem);
  };
  auto non_negative = [](double value) { return std::isfinite(value) && value >= 0.0; };
  const LaserOptions& laser = options.laser;
  require(std::isfinite(laser.field_of_view) && laser.field_of_view > 0.0 && laser.field_of_view <= 2.0 * kPi,
          "laser field of view must be in (0, 2 pi]");
  require(laser.min_range < laser.max_range, "need laser_min_range < laser_max_range");
  require(finite(laser.mount), "laser mount pose must be finite");
  const OdometryNoiseOptions& noise = options.odometry_noise;
  require(non_negative(noise.x) && non_negative(noise.y) && non_negative(noise.yaw) && noise.x < 2.0 &&
              noise.y < 2.0 && noise.yaw < 2.0,
          "odometry noise fractions must be in [0, 2)");
  require(!options.start_pose || finite(*options.start_pose), "start pose must be finite");
}

Simulation::Simulation(const SimulationWorld& world, const SimulationOptions& options)
    : world_(world), options_(options), random_(options.seed) {
  validate(options_);
  const LaserOptions& laser = options_.laser;
  laser_.beams = laser.beams;
  laser_.max_range = laser.max_range;
  laser_.angle_min = -0.5 * laser.field_of_view;
  laser_.angle_increment = laser.beams > 1 ? laser.field_of_view / (laser.beams - 1) : 0.0;

  physics_ = std::make_unique<b2World>(b2Vec2(0.0f, 0.0f));
  physics_->SetAllowSleeping(false);
  b2BodyDef wall_def;
  b2Body* walls = physics_->CreateBody(&wall_def);
  for (const common::Polygon& wall : world_.walls) {
    if (!usablePiece(wall) || wall.size() > static_cast<size_t>(b2_maxPolygonVertices))
      throw common::InputError("simulation world", "a wall is not a convex polygon of 3 to 8 usable vertices");
    const b2PolygonShape shape = toShape(wall);
    walls->CreateFixture(&shape, 0.0f);
  }
  for (const SimulationWorld::DoorLeaf& door : world_.doors) {
    b2Body* body = nullptr;
    if (!door.pieces.empty()) {
      body = physics_->CreateBody(&wall_def);
      for (const common::Polygon& piece : door.pieces) {
        const b2PolygonShape shape = toShape(piece);
        body->CreateFixture(&shape, 0.0f);
      }
      body->SetEnabled(door.closed);
    }
    door_bodies_.push_back(body);
  }

  const common::OccupancyGrid& free_space = world_.free_space;
  if (options_.start_pose) {
    start_pose_ = *options_.start_pose;
    int col = 0, row = 0;
    if (!free_space.empty() && !(free_space.cellOf(common::Point2(start_pose_.x, start_pose_.y), &col, &row) &&
                                 free_space.cells(row, col) == common::OccupancyGrid::kFree))
      throw common::InputError("simulation options", "the start pose (" + common::formatNumber(start_pose_.x) +
                                                         ", " + common::formatNumber(start_pose_.y) +
                                                         ") is not in the world's free space");
  } else {
    // The free point farthest from anything else, in a corridor when the world has one.
    if (free_space.empty()) throw common::InputError("simulation world", "no free space to start in: set a start pose");
    const cv::Mat1b free_cells = free_space.cells == common::OccupancyGrid::kFree;
    cv::Mat1b candidates = free_cells.clone();
    if (!world_.space_labels.empty()) {
      cv::Mat1b corridors = cv::Mat1b::zeros(free_cells.size());
      for (size_t s = 0; s < world_.space_kinds.size(); ++s)
        if (lower(world_.space_kinds[s]) == "corridor") corridors |= world_.space_labels == static_cast<int>(s + 1);
      corridors &= free_cells;
      if (cv::countNonZero(corridors) > 0) candidates = corridors;
    }
    if (cv::countNonZero(candidates) == 0) throw common::InputError("simulation world", "no free space to start in");
    cv::Mat1b padded;
    cv::copyMakeBorder(free_cells, padded, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(0));
    cv::Mat1f distance;
    cv::distanceTransform(padded, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    cv::Point best;
    cv::minMaxLoc(distance(cv::Rect(1, 1, free_cells.cols, free_cells.rows)), nullptr, nullptr, nullptr, &best,
                  candidates);
    const common::Point2 centre = free_space.cellCentre(best.x, best.y);
    start_pose_ = {centre.x(), centre.y(), 0.0};
  }

  b2BodyDef robot_def;
  robot_def.type = b2_dynamicBody;
  robot_def.bullet = true;
  robot_def.position.Set(static_cast<float>(start_pose_.x), static_cast<float>(start_pose_.y));
  robot_def.angle = static_cast<float>(start_pose_.yaw);
  robot_ = physics_->CreateBody(&robot_def);
  b2PolygonShape footprint;
  footprint.SetAsBox(static_cast<float>(0.5 * options_.robot.length), static_cast<float>(0.5 * options_.robot.width));
  b2FixtureDef fixture;
  fixture.shape = &footprint;
  fixture.density = 1.0f;
  fixture.friction = 0.3f;
  robot_->CreateFixture(&fixture);
  b2AABB box;
  footprint.ComputeAABB(&box, robot_->GetTransform(), 0);
  OverlapQuery query(&footprint, robot_->GetTransform(), robot_);
  physics_->QueryAABB(&query, box);
  if (query.overlaps())
    throw common::InputError("simulation options", "the robot's footprint at the start pose (" +
                                                       std::to_string(start_pose_.x) + ", " +
                                                       std::to_string(start_pose_.y) + ") overlaps a wall");

  box2d_caster_ = std::make_unique<Box2dLaserCaster>(physics_.get(), robot_);
  // The grid caster's walls: the source grid itself for grid worlds, else the walls rasterized.
  if (world_.source_resolution > 0.0) {
    wall_grid_ = world_.free_space;
    wall_grid_.cells = cv::Mat_<int8_t>(world_.free_space.cells.size(), common::OccupancyGrid::kFree);
    wall_grid_.cells.setTo(common::OccupancyGrid::kOccupied, world_.free_space.cells >= kOccupiedThreshold);
  } else {
    common::Point2 low = common::Point2::Constant(std::numeric_limits<double>::infinity()), high = -low;
    auto extend = [&](const common::Polygon& polygon) {
      for (const common::Point2& p : polygon) {
        low = low.cwiseMin(p);
        high = high.cwiseMax(p);
      }
    };
    for (const common::Polygon& wall : world_.walls) extend(wall);
    for (const SimulationWorld::DoorLeaf& door : world_.doors)
      for (const common::Polygon& piece : door.pieces) extend(piece);
    if (low.x() > high.x()) low = high = common::Point2(start_pose_.x, start_pose_.y);
    const double resolution = laser.grid_resolution;
    wall_grid_.resolution = resolution;
    wall_grid_.origin = ((low.array() - 1.0) / resolution).floor() * resolution;
    const Eigen::Array2d cells = ((high - wall_grid_.origin).array() + 1.0) / resolution;
    if (cells.x() * cells.y() > 4e8)
      throw common::InputError("simulation options",
                               "the grid caster's grid would exceed 4e8 cells: raise grid_resolution");
    wall_grid_.cells = cv::Mat_<int8_t>(static_cast<int>(std::ceil(cells.y())), static_cast<int>(std::ceil(cells.x())),
                                        common::OccupancyGrid::kFree);
    for (const common::Polygon& wall : world_.walls)
      fillConvexPolygon(&wall_grid_, wall, common::OccupancyGrid::kOccupied);
  }
  rebuildGrid();
  drawOdometryError();
}

Simulation::~Simulation() = default;

void Simulation::rebuildGrid() {
  common::OccupancyGrid grid = wall_grid_;
  grid.cells = wall_grid_.cells.clone();
  for (const SimulationWorld::DoorLeaf& door : world_.doors)
    if (door.closed)
      for (const common::Polygon& piece : door.pieces)
        fillConvexPolygon(&grid, piece, common::OccupancyGrid::kOccupied);
  grid_caster_ =
      std::make_unique<GridLaserCaster>(grid.cells == common::OccupancyGrid::kOccupied, grid.resolution, grid.origin);
}

void Simulation::drawOdometryError() {
  const OdometryNoiseOptions& noise = options_.odometry_noise;
  const double limits[3] = {noise.x, noise.y, noise.yaw};
  for (int axis = 0; axis < 3; ++axis) {
    std::uniform_real_distribution<double> error(-0.5 * limits[axis], 0.5 * limits[axis]);
    odometry_error_[axis] = limits[axis] > 0.0 ? error(random_) : 0.0;
  }
}

void Simulation::setCommand(const common::VelocityCommand& command) {
  if (!std::isfinite(command.linear) || !std::isfinite(command.angular))
    throw common::InputError("cmd_vel", "velocity command is not finite (linear " + std::to_string(command.linear) +
                                            ", angular " + std::to_string(command.angular) + ")");
  const RobotOptions& robot = options_.robot;
  target_.linear = std::clamp(command.linear, -robot.max_linear_velocity, robot.max_linear_velocity);
  target_.angular = std::clamp(command.angular, -robot.max_angular_velocity, robot.max_angular_velocity);
  last_command_time_ = time();
}

void Simulation::step() {
  const double dt = options_.physics_step;
  const RobotOptions& robot = options_.robot;
  if (robot.watchdog_timeout > 0.0 && time() - last_command_time_ > robot.watchdog_timeout + 1e-9) target_ = {};
  const double dv = robot.linear_acceleration * dt, dw = robot.angular_acceleration * dt;
  commanded_.linear += std::clamp(target_.linear - commanded_.linear, -dv, dv);
  commanded_.angular += std::clamp(target_.angular - commanded_.angular, -dw, dw);

  const common::Pose2 before = truePose();
  const float angle = robot_->GetAngle();
  robot_->SetLinearVelocity(b2Vec2(static_cast<float>(commanded_.linear * std::cos(angle)),
                                   static_cast<float>(commanded_.linear * std::sin(angle))));
  robot_->SetAngularVelocity(static_cast<float>(commanded_.angular));
  physics_->Step(static_cast<float>(dt), 8, 3);
  ++steps_;

  // The motion of this step in the frame of the pose before it, measured, then integrated with the error.
  const common::Pose2 after = truePose();
  const double c = std::cos(before.yaw), s = std::sin(before.yaw);
  const double dx = after.x - before.x, dy = after.y - before.y;
  const common::Pose2 motion{c * dx + s * dy, -s * dx + c * dy, common::wrapAngle(after.yaw - before.yaw)};
  velocity_ = {motion.x / dt, motion.yaw / dt};
  odometry_ =
      common::composePoses(odometry_, {motion.x * (1.0 + odometry_error_[0]), motion.y * (1.0 + odometry_error_[1]),
                                       motion.yaw * (1.0 + odometry_error_[2])});
}

common::VelocityCommand Simulation::odometryVelocity() const {
  return {velocity_.linear * (1.0 + odometry_error_[0]), velocity_.angular * (1.0 + odometry_error_[2])};
}

common::Pose2 Simulation::truePose() const {
  const b2Vec2 position = robot_->GetPosition();
  return {position.x, position.y, common::wrapAngle(robot_->GetAngle())};
}

common::Pose2 Simulation::laserPose() const { return common::composePoses(truePose(), options_.laser.mount); }

common::Pose2 Simulation::odometryPose() const { return odometry_; }

const LaserCaster& Simulation::caster(LaserCasterKind kind) const {
  if (kind == LaserCasterKind::kBox2d) return *box2d_caster_;
  return *grid_caster_;
}

void Simulation::scanWith(LaserCasterKind kind, std::vector<float>* ranges) const {
  caster(kind).cast(laserPose(), laser_, ranges);
}

void Simulation::scan(std::vector<float>* ranges) {
  scanWith(options_.laser.caster, ranges);
  const LaserOptions& laser = options_.laser;
  std::normal_distribution<float> noise(0.0f, static_cast<float>(laser.range_noise));
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  const float min_range = static_cast<float>(laser.min_range), max_range = static_cast<float>(laser.max_range);
  for (float& range : *ranges) {
    if (range < max_range && laser.range_noise > 0.0) range = std::clamp(range + noise(random_), min_range, max_range);
    if (laser.max_range_probability > 0.0 && chance(random_) < laser.max_range_probability) range = max_range;
  }
}

void Simulation::reset() {
  robot_->SetTransform(b2Vec2(static_cast<float>(start_pose_.x), static_cast<float>(start_pose_.y)),
                       static_cast<float>(start_pose_.yaw));
  robot_->SetLinearVelocity(b2Vec2(0.0f, 0.0f));
  robot_->SetAngularVelocity(0.0f);
  target_ = commanded_ = velocity_ = {};
  odometry_ = {};
  drawOdometryError();
}

void Simulation::setDoor(const std::string& id_or_number, bool open) {
  const int index = world_.findDoor(id_or_number);
  if (index < 0) throw common::InputError("set_door", "no door '" + id_or_number + "' in this world");
  if (door_bodies_[index] == nullptr)
    throw common::InputError("set_door", "door '" + id_or_number + "' leads outside (or has no leaf) and cannot open");
  SimulationWorld::DoorLeaf& door = world_.doors[index];
  if (door.closed == !open) return;
  door.closed = !open;
  door_bodies_[index]->SetEnabled(door.closed);
  rebuildGrid();
}

bool Simulation::solidNear(const common::Point2& point, double radius) const {
  b2CircleShape circle;
  circle.m_radius = static_cast<float>(radius);
  b2Transform transform;
  transform.Set(b2Vec2(static_cast<float>(point.x()), static_cast<float>(point.y())), 0.0f);
  b2AABB box;
  circle.ComputeAABB(&box, transform, 0);
  OverlapQuery query(&circle, transform, robot_);
  physics_->QueryAABB(&query, box);
  return query.overlaps();
}

void compareCasters(const Simulation& simulation, double tolerance, CasterAgreement* agreement) {
  std::vector<float> exact, grid;
  simulation.scanWith(LaserCasterKind::kBox2d, &exact);
  simulation.scanWith(LaserCasterKind::kGrid, &grid);
  const common::LaserGeometry& laser = simulation.laserGeometry();
  const common::Pose2 pose = simulation.laserPose();
  const float max_range = static_cast<float>(laser.max_range);
  for (size_t k = 0; k < exact.size(); ++k) {
    const float difference = std::abs(exact[k] - grid[k]);
    agreement->absolute_differences.push_back(difference);
    ++agreement->beams;
    if (difference <= tolerance) {
      ++agreement->within_tolerance;
      continue;
    }
    if (exact[k] >= max_range || grid[k] >= max_range) continue;
    const double angle = pose.yaw + laser.angle_min + static_cast<double>(k) * laser.angle_increment;
    const common::Point2 hit(pose.x + grid[k] * std::cos(angle), pose.y + grid[k] * std::sin(angle));
    if (simulation.solidNear(hit, 1.5 * simulation.gridResolution())) ++agreement->same_surface;
  }
}

int Simulation::staticFixtureCount() const {
  int count = 0;
  for (const b2Body* body = physics_->GetBodyList(); body != nullptr; body = body->GetNext())
    if (body != robot_)
      for (const b2Fixture* fixture = body->GetFixtureList(); fixture != nullptr; fixture = fixture->GetNext()) ++count;
  return count;
}

}  // namespace hidden_rooms::simulation
