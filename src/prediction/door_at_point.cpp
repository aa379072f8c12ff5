#include "hidden_rooms/prediction/door_at_point.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::prediction {

namespace {

using common::OccupancyGrid;

// Cell steps of a door's line: `along` runs along the door line, `across` from one side to the other.
struct Axes {
  common::DoorOrientation orientation;
  cv::Point along, across;
};

// A door line along x is a row of cells; along y, a column.
const Axes kAxes[2] = {{common::DoorOrientation::kAlongX, {1, 0}, {0, 1}},
                       {common::DoorOrientation::kAlongY, {0, 1}, {1, 0}}};

bool inside(const OccupancyGrid& map, const cv::Point& cell) {
  return cell.x >= 0 && cell.y >= 0 && cell.x < map.width() && cell.y < map.height();
}

int8_t valueAt(const OccupancyGrid& map, const cv::Point& cell) { return map.cells(cell.y, cell.x); }
bool isFree(int8_t value) { return value >= 0 && value < 50; }
bool isOccupied(int8_t value) { return value >= 50; }

// Fractions of free and of unknown cells on one side of a line through `centre` (across offsets 1..depth
// towards `side`, along offsets -half..half).
struct SideCounts {
  double free = 0.0, unknown = 0.0;
};
SideCounts sideCounts(const OccupancyGrid& map, const cv::Point& centre, const Axes& axes, int side, int half,
                      int depth) {
  int free = 0, unknown = 0, total = 0;
  for (int t = 1; t <= depth; ++t)
    for (int a = -half; a <= half; ++a) {
      const cv::Point cell = centre + a * axes.along + side * t * axes.across;
      if (!inside(map, cell)) continue;
      ++total;
      const int8_t value = valueAt(map, cell);
      free += isFree(value);
      unknown += value == OccupancyGrid::kUnknown;
    }
  if (total == 0) return {};
  return {static_cast<double>(free) / total, static_cast<double>(unknown) / total};
}

}  // namespace

std::optional<common::MapDoor> doorAtPoint(const OccupancyGrid& map, const common::Point2& point,
                                           const DoorAtPointOptions& options, std::string* problem) {
  int col = 0, row = 0;
  if (!std::isfinite(point.x()) || !std::isfinite(point.y()) || !map.cellOf(point, &col, &row)) {
    *problem = "the point is outside the map";
    return std::nullopt;
  }
  const cv::Point click(col, row);
  const int radius = std::max(1, static_cast<int>(std::lround(options.search_radius / map.resolution)));
  const int half_door = std::max(1, static_cast<int>(std::lround(0.5 * options.default_width / map.resolution)));

  // Orientation: the axis across which one side is free and the other unknown.
  double best_score = 0.0;
  const Axes* axes = nullptr;
  int unknown_side = 1;
  for (const Axes& candidate : kAxes)
    for (int side : {1, -1}) {
      const SideCounts towards = sideCounts(map, click, candidate, side, half_door, radius);
      const SideCounts away = sideCounts(map, click, candidate, -side, half_door, radius);
      const double score = towards.unknown * away.free;
      if (score > best_score) {
        best_score = score;
        axes = &candidate;
        unknown_side = side;
      }
    }
  constexpr double kMinScore = 0.2;  // e.g. 60 % unknown on one side and a third free on the other
  if (axes == nullptr || best_score < kMinScore) {
    *problem = "no door there: a closed door lies between explored free space and unexplored space, and within " +
               common::formatNumber(options.search_radius) + " m of the point neither axis shows both";
    return std::nullopt;
  }

  // The door's line: the wall's (most occupied cells along it, among lines with mostly unknown space just
  // behind them: not a wall across the corridor), else where free space ends towards the unknown.
  std::vector<int> occupied_of(2 * radius + 1, -1);  // per across offset t + radius; -1: not a candidate
  for (int t = -radius; t <= radius; ++t) {
    int occupied = 0, behind_unknown = 0, behind_total = 0;
    for (int a = -radius; a <= radius; ++a) {
      const cv::Point cell = click + a * axes->along + t * axes->across;
      occupied += inside(map, cell) && isOccupied(valueAt(map, cell));
      const cv::Point behind = cell + 2 * unknown_side * axes->across;
      if (!inside(map, behind)) continue;
      ++behind_total;
      behind_unknown += valueAt(map, behind) == OccupancyGrid::kUnknown;
    }
    if (2 * behind_unknown >= behind_total) occupied_of[t + radius] = occupied;
  }
  const int most_occupied = *std::max_element(occupied_of.begin(), occupied_of.end());
  int line = 0;
  if (most_occupied > 0) {
    // A wall several cells thick: the middle of the run of its most occupied lines nearest to the point.
    int nearest = -1;
    for (int i = 0; i < static_cast<int>(occupied_of.size()); ++i)
      if (occupied_of[i] == most_occupied && (nearest < 0 || std::abs(i - radius) < std::abs(nearest - radius)))
        nearest = i;
    int first = nearest, last = nearest;
    while (first > 0 && occupied_of[first - 1] == most_occupied) --first;
    while (last + 1 < static_cast<int>(occupied_of.size()) && occupied_of[last + 1] == most_occupied) ++last;
    line = (first + last) / 2 - radius;
  } else {
    for (int t = -radius; t <= radius; ++t) {
      const cv::Point cell = click + unknown_side * t * axes->across;
      const cv::Point before = cell - unknown_side * axes->across;
      if (inside(map, cell) && inside(map, before) && valueAt(map, cell) == OccupancyGrid::kUnknown &&
          isFree(valueAt(map, before))) {
        line = unknown_side * t;
        break;
      }
    }
  }
  const cv::Point on_line = click + line * axes->across;

  // Width and centre: the gap between the jambs through the point, when the map shows one.
  common::MapDoor door;
  door.orientation = axes->orientation;
  door.width = options.default_width;
  double centre_offset = 0.0;  // along the line, cells from on_line
  const int max_cells = static_cast<int>(std::ceil(options.max_width / map.resolution));
  auto openRun = [&](int direction) {  // cells from on_line to the first occupied one; -1 when none within reach
    for (int a = 1; a <= max_cells; ++a) {
      const cv::Point cell = on_line + direction * a * axes->along;
      if (!inside(map, cell)) return -1;
      if (isOccupied(valueAt(map, cell))) return a;
    }
    return -1;
  };
  if (inside(map, on_line) && !isOccupied(valueAt(map, on_line))) {
    const int forward = openRun(1), backward = openRun(-1);
    const double gap = (forward + backward - 1) * map.resolution;
    if (forward > 0 && backward > 0 && gap >= options.min_width && gap <= options.max_width) {
      door.width = gap;
      centre_offset = 0.5 * (forward - backward);
    }
  }
  const common::Point2 along(axes->along.x, -axes->along.y);  // image rows run down, map y up
  door.position = map.cellCentre(on_line.x, on_line.y) + centre_offset * map.resolution * along;
  return door;
}

}  // namespace hidden_rooms::prediction
