#include "hidden_rooms/world/render.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/input_limits.h"

namespace hidden_rooms::world {

namespace {

constexpr int kSubpixelBits = 8;  // cv::fillPoly shift: polygon vertices with 1/256 cell precision
constexpr double kSameLineAngle = 10.0 * 3.14159265358979323846 / 180.0;
// Largest distance (metres) between the two drawings of one wall by the two spaces it separates.
constexpr double kMaxDoubleWallOffset = 0.5;

// Map-frame polygon -> OpenCV integer vertices (cell centres at integer coordinates, fixed point).
std::vector<cv::Point> toCvPolygon(const common::OccupancyGrid& grid, const common::Polygon& polygon) {
  std::vector<cv::Point> points;
  for (const common::Point2& p : polygon) {
    const common::Point2 image = grid.toImage(p) - common::Point2(0.5, 0.5);
    points.emplace_back(static_cast<int>(std::lround(image.x() * (1 << kSubpixelBits))),
                        static_cast<int>(std::lround(image.y() * (1 << kSubpixelBits))));
  }
  return points;
}

// Rectangle centred on segment [a, b] with half-width `half_across`, extended by `cap` beyond both ends.
common::Polygon segmentRectangle(const common::Point2& a, const common::Point2& b, double half_across, double cap) {
  const common::Point2 along = (b - a).norm() > 0 ? common::Point2((b - a).normalized()) : common::Point2(1, 0);
  const common::Point2 across(-along.y(), along.x());
  const common::Point2 start = a - cap * along, end = b + cap * along;
  return {start + half_across * across, end + half_across * across, end - half_across * across,
          start - half_across * across};
}

template <typename T>
void fillPolygon(cv::Mat_<T>* image, const common::OccupancyGrid& grid, const common::Polygon& polygon, T value) {
  if (polygon.size() < 3) return;
  const std::vector<std::vector<cv::Point>> polygons{toCvPolygon(grid, polygon)};
  cv::fillPoly(*image, polygons, cv::Scalar(value), cv::LINE_8, kSubpixelBits);
}

double angleBetweenLines(double a, double b) {
  const double difference = std::fmod(std::abs(a - b), 3.14159265358979323846);
  return std::min(difference, 3.14159265358979323846 - difference);
}

bool isOpen(const Door& door, int index, const std::set<int>& closed) {
  return door.space_indices.size() >= 2 && door.status != DoorStatus::kClosed && closed.count(index) == 0;
}

void validate(const RenderOptions& options, double wall_thickness) {
  auto positive = [](double value) { return std::isfinite(value) && value > 0.0; };
  if (!positive(options.resolution)) throw common::InputError("render options", "resolution must be positive");
  if (!positive(options.door_width)) throw common::InputError("render options", "door width must be positive");
  if (!positive(wall_thickness)) throw common::InputError("render options", "wall thickness must be positive");
  if (wall_thickness > RenderOptions::kMaxWallThickness)
    throw common::InputError("render options", "wall thickness " + common::formatNumber(wall_thickness) +
                                                   " m is more than " +
                                                   common::formatNumber(RenderOptions::kMaxWallThickness) +
                                                   " m (a length in pixels? the thickness is in metres)");
  if (!std::isfinite(options.margin) || options.margin < 0.0)
    throw common::InputError("render options", "margin must be zero or positive");
}

}  // namespace

const common::OptionTable<RenderOptions>& renderOptionTable() {
  using O = RenderOptions;
  static const common::OptionTable<O> table{
      {"resolution", &O::resolution, "rendering: metres per cell", common::above(0)},
      {"door_width", &O::door_width, "rendering: gap at open doors, metres", common::above(0)},
      {"margin", &O::margin, "rendering: unknown border, metres", common::atLeast(0)},
  };
  return table;
}

WallGeometry wallGeometry(const Environment& environment, const std::set<int>& open_door_indices,
                          const RenderOptions& options) {
  const double thickness =
      options.wall_thickness.value_or(environment.wall_thickness.value_or(RenderOptions::kDefaultWallThickness));
  validate(options, thickness);
  for (int index : open_door_indices)
    if (index < 0 || index >= static_cast<int>(environment.doors.size()))
      throw common::InputError("render options", "open door index " + std::to_string(index) + " does not exist");
  WallGeometry geometry;
  geometry.thickness = thickness;
  geometry.door_leaves.resize(environment.doors.size());
  geometry.door_openings.resize(environment.doors.size());

  // Open doors. Real floor plans often draw the wall between two spaces twice, once per space and up to
  // kMaxDoubleWallOffset apart, with the portal on one of the two lines: the gap is cut through every wall of
  // the joined spaces parallel to the door within that offset, and through any other wall the door lies on.
  const std::vector<int> open_doors(open_door_indices.begin(), open_door_indices.end());
  const double on_wall_tolerance = std::max(thickness, 2.0 * options.resolution);
  const double cap = 0.5 * thickness;
  std::vector<double> door_half_depth(environment.doors.size(), 0.5 * thickness + options.resolution);
  for (size_t s = 0; s < environment.spaces.size(); ++s) {
    for (const LineSegment& segment : environment.spaces[s].segments) {
      const double length = (segment.b - segment.a).norm();
      if (segment.segment_class != SegmentClass::kWall || length <= 1e-9) continue;
      const common::Point2 a = segment.a, b = segment.b;
      std::vector<std::pair<double, double>> solid{{0.0, 1.0}};  // parameter intervals along a -> b left standing
      const common::Point2 direction = (b - a) / length;
      const double wall_angle = std::atan2(direction.y(), direction.x());
      for (int d : open_doors) {
        const Door& door = environment.doors[d];
        if (angleBetweenLines(wall_angle, door.wall_angle) > kSameLineAngle) continue;
        const double t = common::projectionParameter(door.centre, a, b);
        const double offset = std::abs(direction.x() * (door.centre.y() - a.y()) -
                                       direction.y() * (door.centre.x() - a.x()));
        const double half_cut = (0.5 * options.door_width + 0.5 * thickness) / length;
        const bool joins_space = std::find(door.space_indices.begin(), door.space_indices.end(),
                                           static_cast<int>(s)) != door.space_indices.end();
        const bool on_this_wall = common::distanceToSegment(door.centre, a, b) <= on_wall_tolerance;
        const bool double_wall = joins_space && offset <= kMaxDoubleWallOffset && t > -half_cut && t < 1.0 + half_cut;
        if (!on_this_wall && !double_wall) continue;
        door_half_depth[d] = std::max(door_half_depth[d], offset + 0.5 * thickness + options.resolution);
        std::vector<std::pair<double, double>> remaining;
        for (const auto& [t0, t1] : solid) {
          if (t - half_cut > t0) remaining.emplace_back(t0, std::min(t1, t - half_cut));
          if (t + half_cut < t1) remaining.emplace_back(std::max(t0, t + half_cut), t1);
        }
        solid.swap(remaining);
        // The wall cut away (the visible gap is door_width wide: the pieces left keep their caps).
        const double s0 = std::max(-cap, t * length - 0.5 * options.door_width);
        const double s1 = std::min(length + cap, t * length + 0.5 * options.door_width);
        if (s1 > s0)
          geometry.door_leaves[d].push_back(segmentRectangle(a + s0 * direction, a + s1 * direction, cap, 0.0));
      }
      for (const auto& [t0, t1] : solid)
        if (t1 > t0) geometry.walls.push_back(segmentRectangle(a + t0 * (b - a), a + t1 * (b - a), cap, cap));
    }
  }
  for (int d : open_doors) {
    const Door& door = environment.doors[d];
    const common::Point2 along(std::cos(door.wall_angle), std::sin(door.wall_angle));
    const double half = 0.5 * options.door_width;
    geometry.door_openings[d] =
        segmentRectangle(door.centre - half * along, door.centre + half * along, door_half_depth[d], 0.0);
  }
  return geometry;
}

RenderedEnvironment renderEnvironment(const Environment& environment, const std::set<int>& closed_door_indices,
                                      const RenderOptions& options) {
  const double thickness =
      options.wall_thickness.value_or(environment.wall_thickness.value_or(RenderOptions::kDefaultWallThickness));
  validate(options, thickness);
  for (int index : closed_door_indices)
    if (index < 0 || index >= static_cast<int>(environment.doors.size()))
      throw common::InputError("render options", "closed door index " + std::to_string(index) + " does not exist");

  const auto [low, high] = environment.bounds();
  const double resolution = options.resolution;
  RenderedEnvironment result;
  result.wall_thickness = thickness;
  common::OccupancyGrid& grid = result.map;
  grid.resolution = resolution;
  grid.origin = ((low.array() - options.margin) / resolution).floor() * resolution;
  const Eigen::Array2d cells = ((high - grid.origin).array() + options.margin) / resolution;
  common::checkLimit("render options", "the map's number of cells", cells.x() * cells.y(), common::kMaxMapCells,
                     ": raise the resolution");
  grid.cells.create(static_cast<int>(std::ceil(cells.y())), static_cast<int>(std::ceil(cells.x())));
  grid.cells.setTo(common::OccupancyGrid::kUnknown);
  result.space_labels = cv::Mat1w::zeros(grid.cells.size());

  for (size_t s = 0; s < environment.spaces.size(); ++s) {
    fillPolygon<int8_t>(&grid.cells, grid, environment.spaces[s].outline, common::OccupancyGrid::kFree);
    fillPolygon<uint16_t>(&result.space_labels, grid, environment.spaces[s].outline, static_cast<uint16_t>(s + 1));
  }

  std::set<int> open_doors;
  for (size_t d = 0; d < environment.doors.size(); ++d)
    if (isOpen(environment.doors[d], static_cast<int>(d), closed_door_indices)) open_doors.insert(static_cast<int>(d));
  const WallGeometry geometry = wallGeometry(environment, open_doors, options);
  for (const common::Polygon& opening : geometry.door_openings)
    fillPolygon<int8_t>(&grid.cells, grid, opening, common::OccupancyGrid::kFree);
  for (const common::Polygon& wall : geometry.walls)
    fillPolygon<int8_t>(&grid.cells, grid, wall, common::OccupancyGrid::kOccupied);
  result.space_labels.setTo(0, grid.cells != common::OccupancyGrid::kFree);

  result.closed_doors.frame = "map";
  for (size_t d = 0; d < environment.doors.size(); ++d) {
    const Door& door = environment.doors[d];
    if (closed_door_indices.count(static_cast<int>(d)) == 0 && door.status != DoorStatus::kClosed) continue;
    common::MapDoor closed;
    closed.id = door.number;
    closed.position = door.centre;
    closed.width = options.door_width;
    closed.orientation = door.orientation;
    result.closed_doors.doors.push_back(closed);
  }
  return result;
}

HiddenRoomsCase hideClosedRooms(const Environment& environment, const RenderedEnvironment& rendered) {
  HiddenRoomsCase hidden;
  hidden.map = rendered.map;
  hidden.map.cells = rendered.map.cells.clone();  // the caller's map stays as it is
  hidden.closed_doors = rendered.closed_doors;
  hidden.true_rooms = cv::Mat1w::zeros(rendered.map.cells.size());
  cv::Mat1b hidden_free = cv::Mat1b::zeros(rendered.map.cells.size());
  for (size_t k = 0; k < rendered.closed_doors.doors.size(); ++k) {
    const int door = environment.findDoor(std::to_string(rendered.closed_doors.doors[k].id));
    const int room = door >= 0 ? roomBehindDoor(environment, door) : -1;
    if (room < 0)
      throw common::InputError("closed doors", "door " + std::to_string(rendered.closed_doors.doors[k].id) +
                                                   " is not closable: no room lies behind it alone");
    const cv::Mat1b cells = rendered.space_labels == room + 1;
    hidden.true_rooms.setTo(static_cast<uint16_t>(k + 1), cells);
    hidden_free |= cells;
  }
  // A wall cell is seen when it lies within the wall's full thickness of explored free space.
  hideUnseenRooms(hidden_free, rendered.wall_thickness / rendered.map.resolution + 1.0, &hidden.map);
  return hidden;
}

void hideUnseenRooms(const cv::Mat1b& hidden, double seen_reach, common::OccupancyGrid* map) {
  const cv::Mat1b visible_free = (common::trinary(*map).cells == common::OccupancyGrid::kFree) & ~hidden;
  cv::Mat1f to_visible, to_hidden;
  cv::distanceTransform(~visible_free, to_visible, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(~hidden, to_hidden, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  map->cells.setTo(common::OccupancyGrid::kUnknown, hidden);
  map->cells.setTo(common::OccupancyGrid::kUnknown,
                   (to_hidden < to_visible) & (to_visible > static_cast<float>(seen_reach)));
}

cv::Mat3b renderPreview(const Environment& environment, const RenderedEnvironment& rendered) {
  const common::OccupancyGrid& grid = rendered.map;
  cv::Mat3b preview;
  cv::cvtColor(grid.toGreyImage(), preview, cv::COLOR_GRAY2BGR);
  // Pastel tint per space, from a fixed hue sequence (golden-angle steps).
  for (int row = 0; row < preview.rows; ++row)
    for (int col = 0; col < preview.cols; ++col) {
      const int label = rendered.space_labels(row, col);
      if (label == 0) continue;
      const double hue = std::fmod(label * 137.508, 360.0);
      cv::Mat3b hsv(1, 1, cv::Vec3b(static_cast<uchar>(hue / 2), 60, 245)), bgr;
      cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
      preview(row, col) = bgr(0, 0);
    }
  const int radius = std::max(3, static_cast<int>(std::lround(0.3 / grid.resolution)));
  std::set<int> closed_numbers;
  for (const common::MapDoor& door : rendered.closed_doors.doors) closed_numbers.insert(door.id);
  for (const Door& door : environment.doors) {
    const common::Point2 image = grid.toImage(door.centre);
    const cv::Point centre(static_cast<int>(image.x()), static_cast<int>(image.y()));
    const bool closed = closed_numbers.count(door.number) > 0;
    if (door.space_indices.size() < 2 && !closed) continue;
    const cv::Scalar colour = closed ? cv::Scalar(0, 0, 220) : cv::Scalar(0, 170, 0);
    cv::circle(preview, centre, radius, colour, closed ? cv::FILLED : 2, cv::LINE_AA);
    if (closed)
      cv::putText(preview, std::to_string(door.number), centre + cv::Point(radius + 2, -radius - 2),
                  cv::FONT_HERSHEY_SIMPLEX, 0.45, colour, 1, cv::LINE_AA);
  }
  return preview;
}

}  // namespace hidden_rooms::world
