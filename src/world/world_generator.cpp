#include "hidden_rooms/world/world_generator.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::world {

namespace {

// The generator works on an integer grid of 0.05 m units, so geometry is exact and every coordinate is an
// integer XML pixel (metres_per_pixel = 0.05).
constexpr int kUnitsPerMetre = 20;
constexpr double kMetresPerUnit = 0.05;

// Room and corridor dimensions, units.
constexpr int kMinRoomWidth = 50;       // 2.5 m along the corridor
constexpr int kMaxRoomWidth = 120;      // 6 m
constexpr int kMaxWidenedRoom = 140;    // a room may grow to 7 m to use up the end of a corridor wall
constexpr int kMinRoomDepth = 60;       // 3 m away from the corridor
constexpr int kMaxRoomDepth = 140;      // 7 m
constexpr int kMaxEndRoomDepth = 80;    // 4 m for a room at a corridor's end
constexpr int kDoorCornerClearance = 16;   // a door centre stays 0.8 m from the corners of its wall
constexpr int kMinSharedWallForDoor = 40;  // 2 m of shared wall before two rooms get a door between them
constexpr int kMinWidthForTwoDoors = 64;   // 3.2 m: two corridor doors 1.6 m apart, both clear of corners

// Percent chances.
constexpr int kTwoCorridorDoorsPercent = 8;
constexpr int kRoomToRoomDoorPercent = 5;
constexpr int kEndRoomPercent = 50;         // a room at a corridor's end wall
constexpr int kSameDepthPercent = 60;       // a room keeps its corridor side's usual depth

// Small worlds below this many closable doors are too dull to explore.
constexpr int kMinSmallClosableDoors = 4;
constexpr int kMaxAttempts = 1000;

struct GridPoint {
  int x = 0;
  int y = 0;
  bool operator==(const GridPoint& other) const { return x == other.x && y == other.y; }
  bool operator!=(const GridPoint& other) const { return !(*this == other); }
  bool operator<(const GridPoint& other) const { return y != other.y ? y < other.y : x < other.x; }
};

// Axis-aligned rectangle [x0, x1] x [y0, y1], units.
struct Rect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;

  // True when the interiors intersect (touching rectangles do not overlap).
  bool overlaps(const Rect& other) const {
    return x0 < other.x1 && other.x0 < x1 && y0 < other.y1 && other.y0 < y1;
  }
  bool containsCell(int cx0, int cy0, int cx1, int cy1) const {
    return x0 <= cx0 && cx1 <= x1 && y0 <= cy0 && cy1 <= y1;
  }
  long long area() const { return static_cast<long long>(x1 - x0) * (y1 - y0); }
  // Corners counter-clockwise (x right, y up), starting at the lower left.
  std::vector<GridPoint> corners() const { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }
};

// Portable seeded randomness: std::mt19937 (fully specified) with integer rejection sampling, so the same
// seeds give the same worlds with every standard library.
class Random {
 public:
  explicit Random(std::initializer_list<std::uint32_t> seeds) {
    std::seed_seq sequence(seeds);
    engine_.seed(sequence);
  }

  // Uniform integer in [low, high].
  int uniform(int low, int high) {
    if (high <= low) return low;
    const std::uint64_t span = static_cast<std::uint64_t>(static_cast<std::int64_t>(high) - low) + 1;
    const std::uint64_t range = std::uint64_t{1} << 32;
    const std::uint64_t accepted = range - range % span;
    std::uint64_t draw = 0;
    do {
      draw = static_cast<std::uint32_t>(engine_());
    } while (draw >= accepted);
    return low + static_cast<int>(draw % span);
  }

  bool percent(int chance) { return uniform(0, 99) < chance; }

  template <typename T>
  T pick(const std::vector<T>& items) {
    return items.at(static_cast<size_t>(uniform(0, static_cast<int>(items.size()) - 1)));
  }

  std::uint32_t bits() { return static_cast<std::uint32_t>(engine_()); }

 private:
  std::mt19937 engine_;
};

// A planned door: its centre on the wall between two spaces (space 0 = the corridor, room i = space i + 1).
struct PlannedDoor {
  GridPoint centre;
  int space_a = 0;
  int space_b = 0;
};

struct FloorPlan {
  std::vector<Rect> corridor_parts;        // the corridor is the union of these
  std::vector<GridPoint> corridor_outline;  // counter-clockwise, no repeated or collinear vertices
  std::vector<Rect> rooms;
  std::vector<std::string> room_labels;
  std::vector<PlannedDoor> doors;
};

// ---------------------------------------------------------------------------------------------------------
// Corridor layouts.

// Mirrors and/or transposes the layout at random so corridors run in every direction.
void reorient(std::vector<Rect>* parts, Random* random) {
  const bool transpose = random->percent(50), mirror_x = random->percent(50), mirror_y = random->percent(50);
  for (Rect& r : *parts) {
    if (transpose) r = {r.y0, r.x0, r.y1, r.x1};
    if (mirror_x) r = {-r.x1, r.y0, -r.x0, r.y1};
    if (mirror_y) r = {r.x0, -r.y1, r.x1, -r.y0};
  }
}

// Rectangles whose union is the corridor, before reorientation. Horizontal parts lie along x from 0.
std::vector<Rect> corridorLayout(SizeClass size_class, Random* random) {
  std::vector<Rect> parts;
  switch (size_class) {
    case SizeClass::kSmall: {
      const int length = random->uniform(10 * kUnitsPerMetre, 20 * kUnitsPerMetre);
      const int width = random->uniform(36, 60);
      parts.push_back({0, 0, length, width});
      break;
    }
    case SizeClass::kMedium: {
      const int width = random->uniform(36, 60);
      if (random->percent(40)) {  // one long straight corridor
        parts.push_back({0, 0, random->uniform(24 * kUnitsPerMetre, 32 * kUnitsPerMetre), width});
      } else {  // an L: a horizontal arm and a vertical arm rising from its right end
        const int arm_length = random->uniform(15 * kUnitsPerMetre, 22 * kUnitsPerMetre);
        const int second_width = random->percent(50) ? width : random->uniform(36, 60);
        const int rise = random->uniform(9 * kUnitsPerMetre, 15 * kUnitsPerMetre);
        parts.push_back({0, 0, arm_length, width});
        parts.push_back({arm_length - second_width, 0, arm_length, width + rise});
      }
      break;
    }
    case SizeClass::kLarge: {
      const int length = random->uniform(26 * kUnitsPerMetre, 38 * kUnitsPerMetre);
      const int width = random->uniform(40, 60);
      parts.push_back({0, 0, length, width});
      // One or two perpendicular branches, each up or down (a branch both ways makes a crossing).
      std::vector<int> branch_positions;
      if (random->percent(35)) {
        branch_positions.push_back(random->uniform(length * 3 / 10, length * 7 / 10));
      } else {
        branch_positions.push_back(random->uniform(length * 2 / 10, length * 4 / 10));
        branch_positions.push_back(random->uniform(length * 6 / 10, length * 8 / 10));
      }
      for (int position : branch_positions) {
        const int branch_width = random->uniform(36, 56);
        const int branch_length = random->uniform(8 * kUnitsPerMetre, 15 * kUnitsPerMetre);
        const int x0 = position - branch_width / 2, x1 = x0 + branch_width;
        const int direction = random->uniform(0, 3);  // 0, 1: up; 2: down; 3: both
        if (direction <= 1 || direction == 3) parts.push_back({x0, width, x1, width + branch_length});
        if (direction >= 2) parts.push_back({x0, -branch_length, x1, 0});
      }
      break;
    }
  }
  reorient(&parts, random);
  return parts;
}

// Outline of the union of axis-aligned rectangles (one simply connected region): counter-clockwise vertices,
// collinear vertices removed, starting at the lowest-leftmost corner.
std::vector<GridPoint> unionOutline(const std::vector<Rect>& parts) {
  std::vector<int> xs, ys;
  for (const Rect& r : parts) {
    xs.insert(xs.end(), {r.x0, r.x1});
    ys.insert(ys.end(), {r.y0, r.y1});
  }
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
  std::sort(ys.begin(), ys.end());
  ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
  const int columns = static_cast<int>(xs.size()) - 1, rows = static_cast<int>(ys.size()) - 1;
  auto filled = [&](int i, int j) {
    if (i < 0 || j < 0 || i >= columns || j >= rows) return false;
    return std::any_of(parts.begin(), parts.end(),
                       [&](const Rect& r) { return r.containsCell(xs[i], ys[j], xs[i + 1], ys[j + 1]); });
  };

  // Directed boundary edges with the region on their left; each corner has exactly one outgoing edge.
  std::map<GridPoint, GridPoint> next;
  auto addEdge = [&](GridPoint from, GridPoint to) {
    if (!next.emplace(from, to).second) throw std::logic_error("corridor outline touches itself");
  };
  for (int i = 0; i < columns; ++i)
    for (int j = 0; j < rows; ++j) {
      if (!filled(i, j)) continue;
      const GridPoint lower_left{xs[i], ys[j]}, lower_right{xs[i + 1], ys[j]};
      const GridPoint upper_right{xs[i + 1], ys[j + 1]}, upper_left{xs[i], ys[j + 1]};
      if (!filled(i, j - 1)) addEdge(lower_left, lower_right);
      if (!filled(i + 1, j)) addEdge(lower_right, upper_right);
      if (!filled(i, j + 1)) addEdge(upper_right, upper_left);
      if (!filled(i - 1, j)) addEdge(upper_left, lower_left);
    }
  if (next.empty()) throw std::logic_error("empty corridor");

  std::vector<GridPoint> loop;
  const GridPoint start = next.begin()->first;  // lowest, then leftmost
  GridPoint current = start;
  do {
    loop.push_back(current);
    current = next.at(current);
  } while (current != start && loop.size() <= next.size());
  if (loop.size() != next.size()) throw std::logic_error("corridor is not one simply connected region");

  std::vector<GridPoint> outline;
  const size_t n = loop.size();
  for (size_t k = 0; k < n; ++k) {
    const GridPoint& before = loop[(k + n - 1) % n];
    const GridPoint& here = loop[k];
    const GridPoint& after = loop[(k + 1) % n];
    const long long turn = static_cast<long long>(here.x - before.x) * (after.y - here.y) -
                           static_cast<long long>(here.y - before.y) * (after.x - here.x);
    if (turn != 0) outline.push_back(here);
  }
  return outline;
}

// ---------------------------------------------------------------------------------------------------------
// Rooms along the corridor.

// Frame of one corridor wall: `along` runs from `origin` to the wall's end, `outward` points away from the
// corridor (right of `along` for a counter-clockwise outline).
struct WallFrame {
  GridPoint origin;
  int along_x = 0, along_y = 0;
  int outward_x = 0, outward_y = 0;
  int length = 0;

  int alongOf(int x, int y) const { return (x - origin.x) * along_x + (y - origin.y) * along_y; }
  int outwardOf(int x, int y) const { return (x - origin.x) * outward_x + (y - origin.y) * outward_y; }
  GridPoint at(int along, int outward) const {
    return {origin.x + along * along_x + outward * outward_x, origin.y + along * along_y + outward * outward_y};
  }
  // The rectangle spanning [along0, along1] x [0, depth] in this frame.
  Rect rect(int along0, int along1, int depth) const {
    const GridPoint a = at(along0, 0), b = at(along1, depth);
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y)};
  }
};

// A rectangle's extent in a wall frame: [along_low, along_high] x [out_low, out_high].
struct FrameExtent {
  int along_low, along_high, out_low, out_high;
};

FrameExtent extentIn(const WallFrame& frame, const Rect& r) {
  FrameExtent extent{std::numeric_limits<int>::max(), std::numeric_limits<int>::min(),
                     std::numeric_limits<int>::max(), std::numeric_limits<int>::min()};
  for (const GridPoint& p : r.corners()) {
    const int along = frame.alongOf(p.x, p.y), outward = frame.outwardOf(p.x, p.y);
    extent.along_low = std::min(extent.along_low, along);
    extent.along_high = std::max(extent.along_high, along);
    extent.out_low = std::min(extent.out_low, outward);
    extent.out_high = std::max(extent.out_high, outward);
  }
  return extent;
}

// Door offset in [low, high] along a room's corridor wall: often near one end, as in real buildings.
int doorOffset(int low, int high, Random* random) {
  const int near_corner = std::min(high, low + 8);
  switch (random->uniform(0, 3)) {
    case 0: return random->uniform(low, near_corner);
    case 1: return random->uniform(std::max(low, high - 8), high);
    default: return random->uniform(low, high);
  }
}

// Fills the outward side of one corridor wall with rooms, flush with each other and with anything already
// placed (rooms never overlap the corridor or each other). Adds one door per room on this wall, two for some.
// Rooms are at most `max_depth` deep.
void placeRoomsAlongWall(const WallFrame& frame, int max_depth, FloorPlan* plan, Random* random) {
  const int usual_depth = random->uniform(std::min(70, max_depth), max_depth);
  auto obstacles = [&]() {
    std::vector<Rect> all = plan->corridor_parts;
    all.insert(all.end(), plan->rooms.begin(), plan->rooms.end());
    return all;
  };
  int position = 0;
  while (frame.length - position >= kMinRoomWidth) {
    const std::vector<Rect> placed = obstacles();
    // Anything within the smallest possible room here forces us to move past it.
    int skip_to = std::numeric_limits<int>::max();
    for (const Rect& r : placed) {
      const FrameExtent e = extentIn(frame, r);
      if (e.along_low < position + kMinRoomWidth && e.along_high > position && e.out_low < kMinRoomDepth &&
          e.out_high > 0)
        skip_to = std::min(skip_to, e.along_high);
    }
    if (skip_to != std::numeric_limits<int>::max()) {
      position = skip_to;
      continue;
    }

    const int remaining = frame.length - position;
    int width = random->uniform(kMinRoomWidth, kMaxRoomWidth);
    if (remaining - width < kMinRoomWidth)  // the rest would be too narrow for another room
      width = remaining <= kMaxWidenedRoom ? remaining : remaining - kMinRoomWidth;
    width = std::min(width, remaining);
    // Stop at the first obstacle too close to the corridor for a room behind it.
    for (const Rect& r : placed) {
      const FrameExtent e = extentIn(frame, r);
      if (e.along_low < position + width && e.along_high > position && e.out_low < kMinRoomDepth &&
          e.out_high > 0)
        width = std::min(width, e.along_low - position);
    }
    int depth = random->percent(kSameDepthPercent) ? usual_depth : random->uniform(kMinRoomDepth, max_depth);
    for (const Rect& r : placed) {
      const FrameExtent e = extentIn(frame, r);
      if (e.along_low < position + width && e.along_high > position && e.out_low < depth && e.out_high > 0)
        depth = std::min(depth, e.out_low);
    }

    const int room_space = static_cast<int>(plan->rooms.size()) + 1;
    plan->rooms.push_back(frame.rect(position, position + width, depth));
    const int low = kDoorCornerClearance, high = width - kDoorCornerClearance;
    if (width >= kMinWidthForTwoDoors && random->percent(kTwoCorridorDoorsPercent)) {
      const int middle = width / 2;
      plan->doors.push_back({frame.at(position + random->uniform(low, middle - kDoorCornerClearance), 0), 0,
                             room_space});
      plan->doors.push_back({frame.at(position + random->uniform(middle + kDoorCornerClearance, high), 0), 0,
                             room_space});
    } else {
      plan->doors.push_back({frame.at(position + doorOffset(low, high, random), 0), 0, room_space});
    }
    position += width;
  }
}

// Walls of the corridor outline as frames, longest first (ties: outline order), so the main corridor's
// long sides get their rooms before branches and end walls.
std::vector<WallFrame> corridorWalls(const std::vector<GridPoint>& outline) {
  std::vector<WallFrame> walls;
  for (size_t k = 0; k < outline.size(); ++k) {
    const GridPoint& a = outline[k];
    const GridPoint& b = outline[(k + 1) % outline.size()];
    WallFrame frame;
    frame.origin = a;
    frame.length = std::abs(b.x - a.x) + std::abs(b.y - a.y);
    frame.along_x = (b.x > a.x) - (b.x < a.x);
    frame.along_y = (b.y > a.y) - (b.y < a.y);
    frame.outward_x = frame.along_y;  // right of `along`
    frame.outward_y = -frame.along_x;
    walls.push_back(frame);
  }
  std::stable_sort(walls.begin(), walls.end(),
                   [](const WallFrame& a, const WallFrame& b) { return a.length > b.length; });
  return walls;
}

int doorCount(const FloorPlan& plan, int space) {
  return static_cast<int>(std::count_if(plan.doors.begin(), plan.doors.end(), [&](const PlannedDoor& door) {
    return door.space_a == space || door.space_b == space;
  }));
}

// Some neighbouring rooms get a door through their shared wall (both then have two doors).
void addRoomToRoomDoors(FloorPlan* plan, Random* random) {
  const int room_count = static_cast<int>(plan->rooms.size());
  for (int i = 0; i < room_count; ++i) {
    if (!random->percent(kRoomToRoomDoorPercent) || doorCount(*plan, i + 1) != 1) continue;
    std::vector<PlannedDoor> candidates;
    for (int j = 0; j < room_count; ++j) {
      if (j == i || doorCount(*plan, j + 1) != 1) continue;
      const Rect& a = plan->rooms[i];
      const Rect& b = plan->rooms[j];
      if (a.x1 == b.x0 || a.x0 == b.x1) {
        const int x = a.x1 == b.x0 ? a.x1 : a.x0;
        const int low = std::max(a.y0, b.y0), high = std::min(a.y1, b.y1);
        if (high - low >= kMinSharedWallForDoor)
          candidates.push_back({{x, (low + high) / 2}, i + 1, j + 1});
      } else if (a.y1 == b.y0 || a.y0 == b.y1) {
        const int y = a.y1 == b.y0 ? a.y1 : a.y0;
        const int low = std::max(a.x0, b.x0), high = std::min(a.x1, b.x1);
        if (high - low >= kMinSharedWallForDoor)
          candidates.push_back({{(low + high) / 2, y}, i + 1, j + 1});
      }
    }
    if (candidates.empty()) continue;
    PlannedDoor door = random->pick(candidates);
    // Move the door off the middle of the shared wall, keeping it clear of the wall's ends.
    const Rect& a = plan->rooms[door.space_a - 1];
    const Rect& b = plan->rooms[door.space_b - 1];
    if (a.x1 == b.x0 || a.x0 == b.x1)
      door.centre.y = random->uniform(std::max(a.y0, b.y0) + kDoorCornerClearance,
                                      std::min(a.y1, b.y1) - kDoorCornerClearance);
    else
      door.centre.x = random->uniform(std::max(a.x0, b.x0) + kDoorCornerClearance,
                                      std::min(a.x1, b.x1) - kDoorCornerClearance);
    plan->doors.push_back(door);
  }
}

// Room label from the building type and floor area.
std::string roomLabel(const Rect& room, bool school, Random* random) {
  const double square_metres = static_cast<double>(room.area()) / (kUnitsPerMetre * kUnitsPerMetre);
  if (square_metres < 9.0) return random->pick<std::string>({"CLOSET", "WASHROOM", "CLOSET"});
  if (square_metres < 16.0)
    return school ? random->pick<std::string>({"OFFICE", "SMALLADMINISTRATIVE", "WASHROOM"})
                  : random->pick<std::string>({"OFFICE", "OFFICE", "MEDIUMSERVICE"});
  if (square_metres < 28.0)
    return school ? random->pick<std::string>({"CLASSROOM", "LAB", "MEDIUMADMINISTRATIVE"})
                  : random->pick<std::string>({"OFFICE", "SHAREDOFFICE", "LAB"});
  return school ? random->pick<std::string>({"CLASSROOM", "CLASSROOM", "LAB"})
                : random->pick<std::string>({"SHAREDOFFICE", "SHAREDOFFICE", "LAB"});
}

// Consistency checks of a plan; a failure is a generator bug.
void checkPlan(const FloorPlan& plan) {
  for (size_t i = 0; i < plan.rooms.size(); ++i) {
    for (const Rect& part : plan.corridor_parts)
      if (plan.rooms[i].overlaps(part)) throw std::logic_error("generated room overlaps the corridor");
    for (size_t j = i + 1; j < plan.rooms.size(); ++j)
      if (plan.rooms[i].overlaps(plan.rooms[j])) throw std::logic_error("generated rooms overlap");
  }
}

FloorPlan makeFloorPlan(SizeClass size_class, bool school, Random* random) {
  FloorPlan plan;
  plan.corridor_parts = corridorLayout(size_class, random);
  plan.corridor_outline = unionOutline(plan.corridor_parts);
  for (const WallFrame& wall : corridorWalls(plan.corridor_outline)) {
    if (wall.length < kMinRoomWidth) continue;
    // A short wall is a corridor's end: a small room there, or none.
    const bool end_wall = wall.length < 2 * kMinRoomWidth;
    if (end_wall && !random->percent(kEndRoomPercent)) continue;
    placeRoomsAlongWall(wall, end_wall ? kMaxEndRoomDepth : kMaxRoomDepth, &plan, random);
  }
  addRoomToRoomDoors(&plan, random);
  for (const Rect& room : plan.rooms) plan.room_labels.push_back(roomLabel(room, school, random));
  checkPlan(plan);
  return plan;
}

// ---------------------------------------------------------------------------------------------------------
// Plan -> environment model.

// One piece of a space's boundary: a wall from `a` to `b`, or a door (door >= 0) at a = b.
struct BoundaryPiece {
  GridPoint a, b;
  int door = -1;
};

// True when p lies strictly inside the axis-aligned segment [a, b].
bool strictlyInside(const GridPoint& p, const GridPoint& a, const GridPoint& b) {
  if (a.x == b.x) return p.x == a.x && p.y > std::min(a.y, b.y) && p.y < std::max(a.y, b.y);
  if (a.y == b.y) return p.y == a.y && p.x > std::min(a.x, b.x) && p.x < std::max(a.x, b.x);
  return false;
}

// The boundary of a space in outline order, walls split at its doors.
std::vector<BoundaryPiece> boundaryOf(const std::vector<GridPoint>& outline, int space,
                                      const std::vector<PlannedDoor>& doors) {
  std::vector<BoundaryPiece> pieces;
  int doors_found = 0;
  for (size_t k = 0; k < outline.size(); ++k) {
    const GridPoint& a = outline[k];
    const GridPoint& b = outline[(k + 1) % outline.size()];
    std::vector<std::pair<int, int>> on_edge;  // (distance from a, door index)
    for (size_t d = 0; d < doors.size(); ++d) {
      const PlannedDoor& door = doors[d];
      if ((door.space_a == space || door.space_b == space) && strictlyInside(door.centre, a, b))
        on_edge.emplace_back(std::abs(door.centre.x - a.x) + std::abs(door.centre.y - a.y), static_cast<int>(d));
    }
    std::sort(on_edge.begin(), on_edge.end());
    GridPoint from = a;
    for (const auto& [distance, door] : on_edge) {
      (void)distance;
      pieces.push_back({from, doors[door].centre, -1});
      pieces.push_back({doors[door].centre, doors[door].centre, door});
      from = doors[door].centre;
      ++doors_found;
    }
    pieces.push_back({from, b, -1});
  }
  if (doors_found != static_cast<int>(std::count_if(doors.begin(), doors.end(), [&](const PlannedDoor& door) {
        return door.space_a == space || door.space_b == space;
      })))
    throw std::logic_error("a generated door is not on its space's outline");
  return pieces;
}

std::string buildingId(Random* random) {
  char text[40];
  std::snprintf(text, sizeof(text), "%08x-%04x-4%03x-%04x-%08x%04x", random->bits(), random->bits() & 0xffffu,
                random->bits() & 0xfffu, (random->bits() & 0x3fffu) | 0x8000u, random->bits(),
                random->bits() & 0xffffu);
  return text;
}

struct WorldIdentity {
  std::string name;
  std::string building_id;
  std::string building_type;
  double wall_thickness = 0.15;
};

Environment toEnvironment(const FloorPlan& plan, const WorldIdentity& identity) {
  // Shift so that every coordinate is >= 0.
  int min_x = std::numeric_limits<int>::max(), min_y = std::numeric_limits<int>::max(), max_y = 0;
  for (const GridPoint& p : plan.corridor_outline) {
    min_x = std::min(min_x, p.x);
    min_y = std::min(min_y, p.y);
  }
  for (const Rect& r : plan.rooms) {
    min_x = std::min(min_x, r.x0);
    min_y = std::min(min_y, r.y0);
  }
  auto shifted = [&](const GridPoint& p) { return GridPoint{p.x - min_x, p.y - min_y}; };

  std::vector<std::vector<GridPoint>> outlines;
  outlines.emplace_back();
  for (const GridPoint& p : plan.corridor_outline) outlines.back().push_back(shifted(p));
  for (const Rect& room : plan.rooms) {
    outlines.emplace_back();
    for (const GridPoint& p : room.corners()) outlines.back().push_back(shifted(p));
  }
  std::vector<PlannedDoor> doors = plan.doors;
  for (PlannedDoor& door : doors) door.centre = shifted(door.centre);
  for (const auto& outline : outlines)
    for (const GridPoint& p : outline) max_y = std::max(max_y, p.y);

  const int space_count = static_cast<int>(outlines.size());
  std::vector<std::vector<BoundaryPiece>> boundaries;
  for (int s = 0; s < space_count; ++s) boundaries.push_back(boundaryOf(outlines[s], s, doors));

  // Portal ids follow the order in which doors first appear in the file, so "p7" is door number 7.
  std::vector<std::string> door_ids(doors.size());
  int next_door_number = 1;
  for (const auto& boundary : boundaries)
    for (const BoundaryPiece& piece : boundary)
      if (piece.door >= 0 && door_ids[piece.door].empty()) door_ids[piece.door] = "p" + std::to_string(next_door_number++);

  auto spaceId = [](int s) { return "s" + std::to_string(s + 1); };
  // Pixels times metres_per_pixel, exactly as the XML reader computes metres, so a written and re-read world
  // is bit-identical.
  auto toMetres = [](const GridPoint& p) { return common::Point2(p.x * kMetresPerUnit, p.y * kMetresPerUnit); };

  Environment environment;
  environment.building_id = identity.building_id;
  environment.name = identity.name;
  environment.building_type = identity.building_type;
  environment.metres_per_pixel = kMetresPerUnit;
  environment.flip_v = static_cast<double>(max_y);
  environment.wall_thickness = identity.wall_thickness;
  for (int s = 0; s < space_count; ++s) {
    Space space;
    space.id = spaceId(s);
    space.type = s == 0 ? "C" : "R";
    space.label = s == 0 ? "CORRIDOR" : plan.room_labels[s - 1];
    for (const GridPoint& p : outlines[s]) space.outline.push_back(toMetres(p));
    int wall_number = 0;
    for (const BoundaryPiece& piece : boundaries[s]) {
      LineSegment segment;
      segment.a = toMetres(piece.a);
      segment.b = toMetres(piece.b);
      if (piece.door >= 0) {
        segment.id = door_ids[piece.door];
        segment.segment_class = SegmentClass::kPortal;
        const PlannedDoor& door = doors[piece.door];
        PortalLink link;
        link.segment_id = segment.id;
        link.target_ids = {space.id, spaceId(door.space_a == s ? door.space_b : door.space_a)};
        space.portals.push_back(link);
      } else {
        segment.id = "w" + std::to_string(s + 1) + "_" + std::to_string(++wall_number);
      }
      space.segments.push_back(segment);
    }
    environment.spaces.push_back(std::move(space));
  }
  deriveDoors(&environment, identity.name);
  return environment;
}

int classIndex(SizeClass size_class) { return static_cast<int>(size_class); }

bool meetsClass(const Environment& environment, SizeClass size_class) {
  const int closable = static_cast<int>(closableDoors(environment).size());
  if (sizeClassOf(closable) != size_class) return false;
  return size_class != SizeClass::kSmall || closable >= kMinSmallClosableDoors;
}

}  // namespace

SizeClass sizeClassOf(int closable_doors) {
  if (closable_doors < 10) return SizeClass::kSmall;
  if (closable_doors <= 15) return SizeClass::kMedium;
  return SizeClass::kLarge;
}

SizeClass sizeClassOf(const Environment& environment) {
  return sizeClassOf(static_cast<int>(closableDoors(environment).size()));
}

const char* toString(SizeClass size_class) {
  switch (size_class) {
    case SizeClass::kSmall: return "small";
    case SizeClass::kMedium: return "medium";
    case SizeClass::kLarge: return "large";
  }
  return "unknown";
}

SizeClass parseSizeClass(const std::string& text) {
  for (SizeClass size_class : {SizeClass::kSmall, SizeClass::kMedium, SizeClass::kLarge})
    if (text == toString(size_class)) return size_class;
  throw common::InputError("command line", "unknown size class '" + text + "' (small|medium|large)");
}

Environment generateWorld(std::uint32_t seed, SizeClass size_class) {
  const auto class_seed = static_cast<std::uint32_t>(classIndex(size_class));
  // Identity and style come from their own stream, so they do not change between layout attempts.
  Random identity_random({seed, class_seed, 0x1d3e7u});
  WorldIdentity identity;
  identity.name = std::string("generated_") + toString(size_class) + "_seed" + std::to_string(seed);
  identity.building_id = buildingId(&identity_random);
  const bool school = identity_random.percent(50);
  identity.building_type = school ? "SCHOOL" : "OFFICE";
  identity.wall_thickness = identity_random.uniform(10, 25) / 100.0;

  for (std::uint32_t attempt = 0; attempt < kMaxAttempts; ++attempt) {
    Random layout_random({seed, class_seed, attempt});
    const FloorPlan plan = makeFloorPlan(size_class, school, &layout_random);
    Environment environment = toEnvironment(plan, identity);
    if (meetsClass(environment, size_class)) return environment;
  }
  throw std::logic_error("generateWorld: no " + std::string(toString(size_class)) + " world after " +
                         std::to_string(kMaxAttempts) + " attempts (seed " + std::to_string(seed) + ")");
}

}  // namespace hidden_rooms::world
