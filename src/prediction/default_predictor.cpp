#include "hidden_rooms/prediction/default_predictor.h"
#include "hidden_rooms/prediction/room_network.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <limits>
#include <map>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/prediction/thesis_predictor.h"

namespace hidden_rooms::prediction {

namespace {

// Working states of a pixel; map values at or above kOccupiedFrom are walls.
constexpr uint8_t kUnknownPx = 0, kFreePx = 1, kOccupiedPx = 2;
constexpr int8_t kOccupiedFrom = 50;
constexpr double kWallDrift = 0.15;  // m: how far a tilted or resampled wall's cells stray from its row
constexpr int kNetworkDoorReach = 3;  // pixels: the learned model's room touches its door's disc grown by this

cv::Mat1b statesOf(const common::OccupancyGrid& map) {
  cv::Mat1b states(map.cells.size(), kUnknownPx);
  states.setTo(kFreePx, map.cells >= 0);
  states.setTo(kOccupiedPx, map.cells >= kOccupiedFrom);
  return states;
}

// A door in the working image: centre pixel, wall axis a and normal n (unit axis vectors, n into the unknown).
struct DoorFrame {
  bool ok = false;
  std::string problem;
  cv::Point p;
  cv::Point a, n;
  int half_width = 1;     // pixels
  int band0 = 0, s0 = 0;  // wall rows v in [band0, s0), first unknown row s0
  int left = 0, right = 0;  // lateral extent, u in [left, right]
  bool lateral_open = false;
  int depth = 0;           // pixels behind s0
  bool bounded = false;
  std::vector<int> bounded_depths;
  double neighbour_depth = -1.0;
  int depth_source = 0;  // 0 measured, 1 explored neighbours, 2 sibling doors, 3 square prior
};

class Frame {
 public:
  Frame(const cv::Mat1b& states, const cv::Rect& box) : s_(states), box_(box) {}
  cv::Point at(const DoorFrame& d, int u, int v) const { return d.p + u * d.a + v * d.n; }
  bool inside(const cv::Point& q) const { return q.x >= 0 && q.y >= 0 && q.x < s_.cols && q.y < s_.rows; }
  bool inBox(const cv::Point& q) const { return box_.contains(q); }
  uint8_t state(const cv::Point& q) const { return inside(q) ? s_(q) : kUnknownPx; }

 private:
  const cv::Mat1b& s_;
  cv::Rect box_;
};

// kWallDrift in pixels of a map of `resolution` (m per pixel), at least one.
int wallDriftPixels(double resolution) { return std::max(1, static_cast<int>(std::lround(kWallDrift / resolution))); }

int median(std::vector<int> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

// Unseen wall thickness in metres of the map whose statesOf is `states` (see unseenWallThickness in the header).
double unseenWallMetres(const cv::Mat1b& states, double resolution) {
  constexpr int kMinWallRun = 3;  // pixels: shorter runs between free pixels are specks and ragged wall faces
  const int max_run = static_cast<int>(1.0 / resolution);  // walls are thinner than a metre
  std::vector<int> through, one_sided;
  const auto scan = [&](auto state_at, int lines, int length) {
    for (int line = 0; line < lines; ++line) {
      int begin = 0;
      while (begin < length) {
        if (state_at(line, begin) == kFreePx) {
          ++begin;
          continue;
        }
        int end = begin;  // the non-free run [begin, end)
        while (end < length && state_at(line, end) != kFreePx) ++end;
        const int run = end - begin;
        const bool free_before = begin > 0, free_after = end < length;
        if (free_before && free_after) {
          if (run >= kMinWallRun && run <= max_run && state_at(line, begin) == kOccupiedPx &&
              state_at(line, end - 1) == kOccupiedPx)
            through.push_back(run);  // a wall seen from both sides (its inside may be unknown)
        } else if (free_before || free_after) {
          // A wall seen from the free side only: its occupied cells, followed by unknown ones.
          int occupied = 0;
          const int step = free_before ? 1 : -1, first = free_before ? begin : end - 1;
          while (occupied < run && state_at(line, first + step * occupied) == kOccupiedPx) ++occupied;
          if (occupied > 0 && occupied < run) one_sided.push_back(occupied);
        }
        begin = end;
      }
    }
  };
  scan([&](int r, int c) { return states(r, c); }, states.rows, states.cols);
  scan([&](int c, int r) { return states(r, c); }, states.cols, states.rows);
  if (through.size() < 20 || one_sided.size() < 20) return 0.0;
  // The most common thickness: walls crossed at an angle give longer runs, which a median or quantile would follow.
  std::map<int, int> counts;
  for (int run : through) ++counts[run];
  const int typical = std::max_element(counts.begin(), counts.end(), [](const auto& a, const auto& b) {
                        return a.second < b.second;
                      })->first;
  // A SLAM map draws each wall face in the cell its surface lies in, about a cell into the space it was seen from:
  // a wall seen from both sides shows one such cell more than one seen from one side.
  return std::max(0, typical - median(one_sided) - 1) * resolution;
}

// Unknown fraction of the strip behind the door (width of the door, `depth` pixels) on side n.
double unknownBehind(const Frame& f, DoorFrame d, int depth) {
  int unknown = 0, total = 0;
  for (int v = 1; v <= depth; ++v)
    for (int u = -d.half_width; u <= d.half_width; ++u) {
      ++total;
      unknown += f.state(f.at(d, u, v)) == kUnknownPx && f.inside(f.at(d, u, v));
    }
  return total ? static_cast<double>(unknown) / total : 0.0;
}

// Side, wall rows and first unknown row of a door.
void placeDoor(const Frame& f, double resolution, const DefaultOptions& P, DoorFrame* d) {
  const int reach = std::max(2, static_cast<int>(std::lround(P.start_search_radius / resolution)));
  const cv::Point n0 = d->n;
  const double plus = unknownBehind(f, *d, reach);
  d->n = -n0;
  const double minus = unknownBehind(f, *d, reach);
  d->n = plus >= minus ? n0 : -n0;
  if (std::max(plus, minus) <= 0.0) {
    d->problem = "no unknown space behind the door";
    return;
  }
  // First row behind the door (v >= -reach/2) where most of the door's width is unknown.
  d->s0 = std::numeric_limits<int>::min();
  for (int v = -reach / 2; v <= reach; ++v) {
    int unknown = 0, total = 0;
    for (int u = -d->half_width; u <= d->half_width; ++u) {
      const cv::Point q = f.at(*d, u, v);
      if (!f.inside(q)) continue;
      ++total;
      unknown += f.state(q) == kUnknownPx;
    }
    if (total && unknown * 2 > total) {
      // The row must be followed by unknown rows (not a speck inside the wall).
      d->s0 = v;
      break;
    }
  }
  if (d->s0 == std::numeric_limits<int>::min()) {
    d->problem = "no unknown space behind the door";
    return;
  }
  // Wall rows: occupied rows just before s0 (any pixel across the door width).
  d->band0 = d->s0;
  for (int v = d->s0 - 1; v >= d->s0 - reach; --v) {
    bool occupied = false;
    for (int u = -d->half_width; u <= d->half_width && !occupied; ++u)
      occupied = f.state(f.at(*d, u, v)) == kOccupiedPx;
    if (!occupied) break;
    d->band0 = v;
  }
  if (d->band0 == d->s0) d->band0 = d->s0 - 1;
  d->ok = true;
}

// Occupied pixels in column u from row v towards the explored side (decreasing v), counted up to `limit`.
int occupiedRun(const Frame& f, const DoorFrame& d, int u, int v, int limit) {
  int run = 0;
  while (run < limit && f.state(f.at(d, u, v - run)) == kOccupiedPx) ++run;
  return run;
}

// Whether the wall goes on past a stub at a stepped row, as past the side wall of a door niche: beyond the stub
// (column u_after onwards, `step` = +-1) row v_mid is not free and, within two columns, an occupied pixel lies
// between rows v_from and v_to (the stub's length). A free-standing stub (a pillar, the end of a perpendicular
// wall) has free space beyond it; a corner of the wall has nothing beyond it.
bool isWallStep(const Frame& f, const DoorFrame& d, int u_after, int step, int v_from, int v_to, int v_mid) {
  for (int k = 0; k < 3; ++k)
    if (f.state(f.at(d, u_after + k * step, v_mid)) == kFreePx) return false;
  for (int k = 0; k < 3; ++k)
    for (int v = std::min(v_from, v_to); v <= std::max(v_from, v_to); ++v)
      if (f.state(f.at(d, u_after + k * step, v)) == kOccupiedPx) return true;
  return false;
}

// Whether a cell of column u within `reach` rows of row v is known.
bool knownNear(const Frame& f, const DoorFrame& d, int u, int v, int reach) {
  for (int t = -reach; t <= reach; ++t)
    if (f.state(f.at(d, u, v + t)) != kUnknownPx) return true;
  return false;
}

// How far the room reaches along the wall in direction `sign`.
int lateralExtent(const Frame& f, double resolution, const DefaultOptions& P, DoorFrame* d, int sign) {
  const int max_u = static_cast<int>(P.max_extent / resolution);
  const int gap_limit = std::max(1, static_cast<int>(P.wall_gap / resolution));
  const int probe1 = std::max(2, static_cast<int>(0.4 / resolution));
  const int probe2 = std::max(3, static_cast<int>(0.8 / resolution));
  int last_wall = 0, gap = 0;
  // The wall is tracked: its rows may drift by a few pixels (slightly tilted walls of SLAM maps).
  int band0 = d->band0, band1 = d->s0 - 1;
  const int persistence = std::max(2, static_cast<int>(std::lround(0.15 / resolution)));
  const int drift = wallDriftPixels(resolution);
  int known_run = 0;
  const int stub_px = P.stub_length > 0.0 ? std::max(2, static_cast<int>(std::lround(P.stub_length / resolution))) : 0;
  const int max_stub_width = std::max(2, static_cast<int>(1.0 / resolution));
  for (int k = 1; k <= max_u; ++k) {
    const int u = sign * k;
    const cv::Point behind = f.at(*d, u, d->s0 + 1);
    if (!f.inside(behind)) {
      d->lateral_open = true;
      return sign * std::max(k - 1, last_wall);
    }
    // Known space behind the wall over a few columns: a perpendicular wall of an explored room. Each probe reads
    // the cells within the wall drift of its row, where a tilted or resampled wall's cells fall.
    int known = 0;
    for (int v : {band1 + 2, band1 + probe1, band1 + probe2}) known += knownNear(f, *d, u, v, drift);
    if (known >= 2) {
      if (++known_run >= persistence) return sign * (k - known_run);
    } else {
      known_run = 0;
    }
    // A stub of wall leaving the door's wall into the explored side (a pillar or the end of a perpendicular
    // wall): rooms on the other side usually end there. The room ends at the stub's middle.
    if (stub_px > 0 && k > d->half_width + 1 && occupiedRun(f, *d, u, band0 - 1, stub_px) >= stub_px) {
      int width = 1;
      while (width < max_stub_width && occupiedRun(f, *d, sign * (k + width), band0 - 1, stub_px) >= stub_px)
        ++width;
      // The side wall of a door niche (or of a step in the wall) is no stub: the wall goes on past it.
      if (!isWallStep(f, *d, sign * (k + width), sign, band0 - 1, band0 - stub_px, band0 - 1 - stub_px / 2))
        return sign * (k + (width - 1) / 2 - 1);  // up to the stub's middle column, exclusive
    }
    int first = std::numeric_limits<int>::max(), last = std::numeric_limits<int>::min();
    for (int v = band0 - 2; v <= band1 + 2; ++v)
      if (f.state(f.at(*d, u, v)) == kOccupiedPx) first = std::min(first, v), last = std::max(last, v);
    if (last >= first) {
      gap = 0;
      last_wall = k;
      band0 = first;
      band1 = std::max(last, first);
    } else if (++gap > gap_limit) {
      return sign * last_wall;
    }
  }
  return sign * max_u;
}

// The columns u a door's depth is read over, [first, last]: its extent less a tenth of its width at each end.
struct DepthColumns {
  int first = 0, last = -1;
  int count() const { return std::max(0, last - first + 1); }
};

DepthColumns depthColumns(const DoorFrame& d) {
  const int margin = (d.right - d.left + 1) / 10;
  return {d.left + margin, d.right - margin};
}

// Per column of the extent, the unknown run behind the wall; sets depth when enough columns end on known space.
void measureDepth(const Frame& f, double resolution, const DefaultOptions& P, DoorFrame* d) {
  const int max_v = static_cast<int>(P.max_extent / resolution);
  const int width = d->right - d->left + 1;
  const DepthColumns columns = depthColumns(*d);
  d->bounded_depths.clear();
  // A slightly tilted wall (SLAM maps) reaches a few rows past s0 away from the door: a column's run starts
  // after its own wall pixels within that drift.
  const int drift = wallDriftPixels(resolution);
  for (int u = columns.first; u <= columns.last; ++u) {
    int v = d->s0;
    while (v < d->s0 + drift && f.inside(f.at(*d, u, v)) && f.state(f.at(*d, u, v)) != kUnknownPx) ++v;
    for (; v <= d->s0 + max_v; ++v) {
      const cv::Point q = f.at(*d, u, v);
      if (!f.inside(q) || !f.inBox(q)) break;
      if (f.state(q) != kUnknownPx) {
        d->bounded_depths.push_back(v - d->s0);
        break;
      }
    }
  }
  d->bounded = columns.count() > 0 && d->bounded_depths.size() >= P.bounded_fraction * columns.count();
  if (d->bounded) d->depth = median(d->bounded_depths);
  // Known space far beyond the room's proportions is no evidence of its back wall (a door into a large unknown
  // region): the depth is then left to the priors.
  if (d->bounded && d->depth > P.max_aspect * width) d->bounded = false;
}

// Depth of explored rooms on the same side of the same wall, within reach of the door's extent.
double neighbourDepth(const Frame& f, double resolution, const DefaultOptions& P, const DoorFrame& d) {
  const int reach = static_cast<int>(P.neighbour_reach / resolution);
  const int max_v = static_cast<int>(P.max_extent / resolution);
  const int entry = std::max(2, static_cast<int>(0.5 / resolution));
  const int unknown_run_limit = std::max(2, static_cast<int>(0.5 / resolution));
  std::vector<int> depths;
  for (int sign : {-1, 1}) {
    const int start = sign < 0 ? d.left - 1 : d.right + 1;
    for (int k = 0; k < reach; ++k) {
      const int u = start + sign * k;
      // An occupied pixel (the wall) then a free pixel just behind the wall line: an explored room there.
      int v = d.band0 - 3;
      while (v <= d.s0 + entry && f.state(f.at(d, u, v)) != kOccupiedPx) ++v;
      while (v <= d.s0 + entry && f.state(f.at(d, u, v)) != kFreePx) ++v;
      if (v > d.s0 + entry || v < d.s0 - 1) continue;
      int unknown_run = 0;
      bool closed = false;
      for (; v <= d.s0 + max_v; ++v) {
        const cv::Point q = f.at(d, u, v);
        if (!f.inside(q)) break;
        const uint8_t s = f.state(q);
        if (s == kOccupiedPx) {
          closed = true;
          break;
        }
        unknown_run = s == kUnknownPx ? unknown_run + 1 : 0;
        if (unknown_run > unknown_run_limit) break;
      }
      if (closed) depths.push_back(v - d.s0);
    }
  }
  if (depths.size() < static_cast<size_t>(std::max(3, static_cast<int>(1.0 / resolution)))) return -1.0;
  const int depth = median(depths);
  return depth * resolution >= P.min_depth ? depth : -1.0;
}

// The image pixel of a door's position.
cv::Point doorPixel(const common::OccupancyGrid& map, const common::MapDoor& door) {
  const common::Point2 image = map.toImage(door.position);
  return {static_cast<int>(std::floor(image.x())), static_cast<int>(std::floor(image.y()))};
}

// Pixels from a door's first unknown row `entry` to the near side of `box`, along the door's normal.
int gapAlongNormal(const DoorFrame& d, const cv::Point& entry, const cv::Rect& box) {
  if (d.n.x > 0) return box.x - entry.x;
  if (d.n.x < 0) return entry.x - (box.br().x - 1);
  if (d.n.y > 0) return box.y - entry.y;
  return entry.y - (box.br().y - 1);
}

// The part of a room's rectangle before `box`, along the door's normal.
cv::Rect endBefore(const DoorFrame& d, cv::Rect room, const cv::Rect& box) {
  if (d.n.x > 0) room.width = std::max(0, box.x - room.x);
  else if (d.n.x < 0) room.width = std::max(0, room.br().x - box.br().x), room.x = box.br().x;
  else if (d.n.y > 0) room.height = std::max(0, box.y - room.y);
  else room.height = std::max(0, room.br().y - box.br().y), room.y = box.br().y;
  return room;
}

// The transform turning an image of `size` by -angle (radians) about its centre onto a grid large enough for all
// of it, whose size it sets in `turned_size`.
cv::Matx23d straighteningTransform(const cv::Size& size, double angle, cv::Size* turned_size) {
  const double c = std::abs(std::cos(angle)), s = std::abs(std::sin(angle));
  turned_size->width = static_cast<int>(std::ceil(c * size.width + s * size.height)) + 2;
  turned_size->height = static_cast<int>(std::ceil(s * size.width + c * size.height)) + 2;
  // The turn about the image's centre, then that centre moved to the turned grid's.
  cv::Matx23d forward = cv::getRotationMatrix2D(cv::Point2f(size.width / 2.0f, size.height / 2.0f),
                                                angle * 180.0 / CV_PI, 1.0);
  forward(0, 2) += (turned_size->width - size.width) / 2.0;
  forward(1, 2) += (turned_size->height - size.height) / 2.0;
  return forward;
}

// A well-mixed hash of a pixel's position (the splitmix64 finalizer).
uint64_t cellHash(const cv::Point& p) {
  uint64_t h = (static_cast<uint64_t>(static_cast<uint32_t>(p.x)) << 32) | static_cast<uint32_t>(p.y);
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ULL;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebULL;
  return h ^ (h >> 31);
}

}  // namespace

void clipToKnownOutline(const cv::Mat1b& known, const cv::Point& door, int reach, int min_depth, cv::Mat1b* mask) {
  const cv::Rect image(0, 0, known.cols, known.rows);
  const cv::Rect room = cv::boundingRect(*mask);
  if (room.area() == 0) return;
  // x limits from the rows beside the room, y limits from its columns.
  const cv::Rect rows = cv::Rect(0, room.y - reach, known.cols, room.height + 2 * reach) & image;
  const cv::Rect columns = cv::Rect(room.x - reach, 0, room.width + 2 * reach, known.rows) & image;
  const cv::Rect in_rows = cv::boundingRect(known(rows)), in_columns = cv::boundingRect(known(columns));
  if (in_rows.area() == 0 || in_columns.area() == 0) return;
  const int x0 = in_rows.x, x1 = in_rows.br().x, y0 = in_columns.y + columns.y, y1 = in_columns.br().y + columns.y;
  // Keep [x0, x1) x [y0, y1), each limit only when it lies at least min_depth beyond the door.
  const cv::Rect keep(cv::Point(door.x - x0 >= min_depth ? x0 : 0, door.y - y0 >= min_depth ? y0 : 0),
                      cv::Point(x1 - door.x >= min_depth ? x1 : known.cols, y1 - door.y >= min_depth ? y1 : known.rows));
  cv::Mat1b outside(room.size(), 255);
  outside((keep & room) - room.tl()).setTo(0);
  (*mask)(room).setTo(0, outside);
}

double dominantWallAngle(const common::OccupancyGrid& map, size_t max_points) {
  // The projection profiles of the wall pixels: turned by the walls' angle, the pixels of each wall fall into a
  // few rows or columns, so the profiles along both axes are sharpest (their sums of squared counts largest).
  // Robust to the staircase a turned wall is rasterized into, which biases gradient directions towards 0.
  std::vector<cv::Point> cells;
  cv::findNonZero(map.cells >= kOccupiedFrom, cells);
  if (cells.empty()) return 0.0;
  // Thinned to about max_points cells, each kept by a hash of its position: every k-th cell in raster order
  // would form a sheared lattice on solid wall blocks, whose own rows would pass for the walls' direction.
  const uint64_t stride = cells.size() / std::max<size_t>(1, max_points) + 1;
  std::vector<cv::Point2d> points;
  for (const cv::Point& cell : cells)
    if (stride == 1 || cellHash(cell) % stride == 0) points.emplace_back(cell.x, cell.y);
  const double diagonal = std::hypot(map.width(), map.height());
  const int bins = static_cast<int>(std::ceil(2.0 * diagonal)) + 2;
  std::vector<int> along(bins), across(bins);
  const auto sharpness = [&](double angle) {
    std::fill(along.begin(), along.end(), 0);
    std::fill(across.begin(), across.end(), 0);
    const double c = std::cos(angle), s = std::sin(angle);
    for (const cv::Point2d& p : points) {
      ++along[static_cast<int>(std::floor(c * p.x + s * p.y + diagonal))];
      ++across[static_cast<int>(std::floor(-s * p.x + c * p.y + diagonal))];
    }
    double sum = 0.0;
    for (int b = 0; b < bins; ++b) sum += double(along[b]) * along[b] + double(across[b]) * across[b];
    return sum;
  };
  // Coarse search over the 90 degree period, then finer around the best angle.
  const double degree = CV_PI / 180.0;
  double best = 0.0, best_value = -1.0;
  for (double step : {1.0 * degree, 0.1 * degree, 0.02 * degree}) {
    const double centre = best, span = best_value < 0.0 ? 45.0 * degree : 10.0 * step;
    for (double angle = centre - span; angle < centre + span; angle += step) {
      const double value = sharpness(angle);
      if (value > best_value) best_value = value, best = angle;
    }
  }
  best = std::fmod(best + CV_PI, CV_PI / 2.0);
  if (best >= CV_PI / 4.0) best -= CV_PI / 2.0;
  return best;
}

double unseenWallThickness(const common::OccupancyGrid& map) { return unseenWallThickness(map, dominantWallAngle(map)); }

double unseenWallThickness(const common::OccupancyGrid& map, double wall_angle) {
  // Read across the walls: the states turned straight by nearest cell, which keeps each wall's thickness (a
  // linear resampling would thicken thin walls), so that the runs cross turned walls square. Beyond the map's
  // edge each cell takes its edge cell's state: the edge is no unknown space.
  cv::Size size;
  const cv::Matx23d forward = straighteningTransform(map.cells.size(), wall_angle, &size);
  cv::Mat1b straight;
  cv::warpAffine(statesOf(map), straight, cv::Mat(forward), size, cv::INTER_NEAREST, cv::BORDER_REPLICATE);
  return unseenWallMetres(straight, map.resolution);
}

const common::OptionTable<DefaultOptions>& defaultOptionTable() {
  using O = DefaultOptions;
  static const common::OptionTable<O> table{
      {"start_search_radius", &O::start_search_radius, "m: a door's nearest unknown cell lies within this",
       common::above(0)},
      {"default_wall_gap", &O::wall_gap, "m: longest gap in the door's wall still followed", common::atLeast(0)},
      {"default_max_extent", &O::max_extent, "m: longest lateral extent and depth searched", common::above(0)},
      {"default_bounded_fraction", &O::bounded_fraction,
       "share of columns ending on a known pixel for a measured depth", common::between(0, 1)},
      {"default_neighbour_reach", &O::neighbour_reach,
       "m: how far along the wall explored neighbours are looked for", common::atLeast(0)},
      {"default_min_depth", &O::min_depth, "m: smallest depth taken from the square prior or the model's room",
       common::atLeast(0)},
      {"default_model_depth", &O::model_depth,
       "1: a rectangle whose depth the map does not show takes the depth of the learned model's room; 0: a square"},
      {"default_model_min_probability", &O::model_min_probability,
       "a cell is in the learned model's room when the model's probability is above this", {0, 1, true, true}},
      {"default_max_aspect", &O::max_aspect,
       "a depth measured on known space counts up to this many times the width", common::above(0)},
      {"default_local_frame_radius", &O::local_frame_radius,
       "m: the walls within this of a door give its frame; 0: the map's frame", common::atLeast(0)},
      {"default_local_frame_tolerance", &O::local_frame_tolerance,
       "degrees: doors whose wall angles differ less share one frame", common::atLeast(0)},
      {"default_min_rotation", &O::min_rotation, "degrees: maps turned less are not predicted turned straight",
       common::atLeast(0)},
      {"default_grown_area_ratio", &O::grown_area_ratio,
       "grown rooms less than this many times the rectangle give way", common::atLeast(0)},
      {"default_stub_length", &O::stub_length, "m: wall stubs this long into the explored side end an extent",
       common::atLeast(0)},
      {"default_stub_by_model", &O::stub_by_model,
       "1 (default_network 1 and 3): a rectangle laid out past the stubs replaces the stubbed one when most of the "
       "cells it adds are in the learned model's room; 0: stubs always end rectangles"},
      {"default_outline_reach", &O::outline_reach,
       "m: band beside a room within which the known map's extent bounds it", common::atLeast(0)},
      {"default_wall_margin", &O::wall_margin,
       "m: unseen wall thickness left out of rooms; < 0: estimated from the map",
       {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(), false, false}},
      {"default_network", &O::network,
       "learned room model: 0 unused; 1 chooses rectangle or grown room; 2 its rooms; 3 the candidate room agreeing "
       "most with the other two",
       {0, 3, false, false, true}},
  };
  return table;
}

RoomCandidate mostAgreedCandidate(const CandidateAgreement& iou, const std::array<bool, 3>& present) {
  const std::array<double, 3> votes = {iou.rectangle_grown + iou.rectangle_model,
                                       iou.rectangle_grown + iou.grown_model,
                                       iou.rectangle_model + iou.grown_model};
  RoomCandidate chosen = RoomCandidate::kGrown;  // ties: the grown room, then the rectangle
  double best = present[1] ? votes[1] : -1.0;
  for (const RoomCandidate candidate : {RoomCandidate::kRectangle, RoomCandidate::kModel}) {
    const size_t k = static_cast<size_t>(candidate);
    if (present[k] && votes[k] > best) {
      best = votes[k];
      chosen = candidate;
    }
  }
  return chosen;
}

namespace {

// The layout the grown rooms stand on: the reference's (LayoutOptions) but for four choices that cost this method on
// the benchmark or on some buildings of the corpus (docs/results.md#closed-door-benchmark): the flat angular window;
// walls of bounded spread, not chained; IN/OUT by unknown pixels, not by the explored outline; DBSCAN on the affinity
// itself.
LayoutOptions grownRoomLayout() {
  LayoutOptions layout;
  layout.angular_kernel = 0;
  layout.wall_chaining = false;
  layout.explored_outline = false;
  layout.affinity_normalized = false;
  return layout;
}

}  // namespace

std::map<std::string, double> DefaultPredictor::defaultParameters() const {
  std::map<std::string, double> parameters = layoutParameters(grownRoomLayout());
  const std::map<std::string, double> own = common::optionValues(defaultOptionTable(), DefaultOptions());
  parameters.insert(own.begin(), own.end());
  return parameters;
}

namespace {

// Step 1, extent: every door of the request, placed on its wall (placeDoor) with its lateral extent
// (lateralExtent); a door that cannot be placed keeps ok = false and its problem.
std::vector<DoorFrame> framedDoors(const PredictionRequest& request, const DefaultOptions& P, const Frame& f) {
  const common::OccupancyGrid& map = request.map;
  const double resolution = map.resolution;
  std::vector<DoorFrame> doors(request.doors.doors.size());
  for (size_t i = 0; i < doors.size(); ++i) {
    const common::MapDoor& door = request.doors.doors[i];
    DoorFrame& d = doors[i];
    cv::Point unused;
    if (!nearestUnknownCell(map, door.position, P.start_search_radius, &unused, &d.problem)) continue;
    const common::Point2 image = map.toImage(door.position);
    d.p = cv::Point(static_cast<int>(std::floor(image.x())), static_cast<int>(std::floor(image.y())));
    d.a = door.orientation == common::DoorOrientation::kAlongX ? cv::Point(1, 0) : cv::Point(0, 1);
    d.n = cv::Point(d.a.y, d.a.x);
    d.half_width = std::max(1, static_cast<int>(0.5 * door.width / resolution));
    placeDoor(f, resolution, P, &d);
    if (!d.ok) continue;
    d.left = lateralExtent(f, resolution, P, &d, -1);
    d.right = lateralExtent(f, resolution, P, &d, +1);
  }
  return doors;
}

// Step 2, extent (continued): doors on the same wall and side share its extent, cut at the midpoints between them.
// Returns per door its siblings: the placed doors on its wall and side within its extent (before the cut).
std::vector<std::vector<int>> splitSharedExtents(double resolution, std::vector<DoorFrame>* doors) {
  auto along = [](const DoorFrame& d, const cv::Point& q) { return d.a.x * q.x + d.a.y * q.y; };
  auto across = [](const DoorFrame& d, const cv::Point& q) { return d.n.x * q.x + d.n.y * q.y; };
  const int same_wall = std::max(2, static_cast<int>(0.6 / resolution));
  const size_t count = doors->size();
  std::vector<std::vector<int>> siblings(count);
  for (size_t i = 0; i < count; ++i) {
    if (!(*doors)[i].ok) continue;
    DoorFrame& d = (*doors)[i];
    const int ci = along(d, d.p), wall_i = across(d, d.p) + d.s0;
    int left = d.left, right = d.right;
    for (size_t j = 0; j < count; ++j) {
      if (j == i || !(*doors)[j].ok) continue;
      const DoorFrame& e = (*doors)[j];
      if (e.a != d.a || e.n != d.n) continue;
      if (std::abs(across(e, e.p) + e.s0 - wall_i) > same_wall) continue;
      const int offset = (along(e, e.p) - ci) * (d.a.x + d.a.y);  // u of the other door in d's frame
      if (offset < d.left || offset > d.right) continue;
      siblings[i].push_back(static_cast<int>(j));
      if (offset > 0) right = std::min(right, offset / 2);
      else if (offset < 0) left = std::max(left, offset / 2 + 1);
    }
    d.left = left;
    d.right = right;
  }
  return siblings;
}

// Depth of the learned model's room of door d: per depth column, the farthest row of the room behind the wall;
// their median, or -1 when the room reaches fewer than half of the columns.
double modelRoomDepth(const Frame& f, const DoorFrame& d, const NetworkRoom& room, int max_v) {
  if (room.box.area() == 0 || room.mask.empty()) return -1.0;
  const DepthColumns columns = depthColumns(d);
  std::vector<int> depths;
  for (int u = columns.first; u <= columns.last; ++u) {
    int farthest = 0;
    for (int v = d.s0; v <= d.s0 + max_v; ++v) {
      const cv::Point q = f.at(d, u, v);
      if (room.box.contains(q) && room.mask(q - room.box.tl())) farthest = v - d.s0 + 1;
    }
    if (farthest > 0) depths.push_back(farthest);
  }
  if (columns.count() == 0 || 2 * depths.size() < static_cast<size_t>(columns.count())) return -1.0;
  return median(depths);
}

// Step 2, depth: every placed door's depth, measured (measureDepth), else from the explored neighbours
// (neighbourDepth), else the median of its bounded siblings, else the depth of the learned model's room
// (`model_rooms`, per door; null: none), else the square prior; depth_source tells which.
void measureDepths(const Frame& f, double resolution, const DefaultOptions& P,
                   const std::vector<std::vector<int>>& siblings, const std::vector<NetworkRoom>* model_rooms,
                   std::vector<DoorFrame>* doors) {
  for (DoorFrame& d : *doors)
    if (d.ok) measureDepth(f, resolution, P, &d);
  for (size_t i = 0; i < doors->size(); ++i) {
    DoorFrame& d = (*doors)[i];
    if (!d.ok || d.bounded) continue;
    double depth = neighbourDepth(f, resolution, P, d);
    d.depth_source = 1;
    if (depth < 0) {
      d.depth_source = 2;
      std::vector<int> sibling_depths;
      for (int j : siblings[i])
        if ((*doors)[j].bounded) sibling_depths.push_back((*doors)[j].depth);
      if (!sibling_depths.empty()) depth = median(sibling_depths);
    }
    if (depth < 0 && model_rooms != nullptr) {
      d.depth_source = 4;
      depth = modelRoomDepth(f, d, (*model_rooms)[i], static_cast<int>(P.max_extent / resolution));
      if (depth >= 0) depth = std::max(depth, P.min_depth / resolution);
    }
    if (depth < 0) {
      d.depth_source = 3;
      depth = std::max(static_cast<double>(d.right - d.left + 1), P.min_depth / resolution);
    }
    d.depth = static_cast<int>(std::lround(depth));
  }
}

// Per door its rectangle in the working image ([left, right] x [s0, s0 + depth] in the door's frame, inclusive);
// empty for doors not placed.
std::vector<cv::Rect> doorRectangles(const Frame& f, const std::vector<DoorFrame>& doors) {
  std::vector<cv::Rect> rects(doors.size());
  for (size_t i = 0; i < doors.size(); ++i) {
    const DoorFrame& d = doors[i];
    if (!d.ok) continue;
    const cv::Point c1 = f.at(d, d.left, d.s0), c2 = f.at(d, d.right, d.s0 + d.depth);
    rects[i] = cv::Rect(cv::Point(std::min(c1.x, c2.x), std::min(c1.y, c2.y)),
                        cv::Point(std::max(c1.x, c2.x) + 1, std::max(c1.y, c2.y) + 1));
  }
  return rects;
}

// Keeps the part of `r` in [lo, hi) along x (x_axis) or y; an empty range leaves an empty rectangle at lo.
void keepRange(cv::Rect* r, int lo, int hi, bool x_axis) {
  int a = x_axis ? r->x : r->y, b = x_axis ? r->x + r->width : r->y + r->height;
  a = std::max(a, lo), b = std::min(b, hi);
  if (b < a) b = a;
  if (x_axis) r->x = a, r->width = b - a;
  else r->y = a, r->height = b - a;
}

// Cuts two overlapping rectangles apart across x (cut_x) or y at the middle of their overlap, kept between the
// doors' entry pixels pi and pj; false when the doors lie at the same coordinate along that axis.
bool cutBetweenDoors(bool cut_x, const cv::Point& pi, const cv::Point& pj, cv::Rect* ri, cv::Rect* rj) {
  const int ci = cut_x ? pi.x : pi.y, cj = cut_x ? pj.x : pj.y;
  // The middle of the overlap, kept between the doors.
  const int lo = std::max(cut_x ? ri->x : ri->y, cut_x ? rj->x : rj->y);
  const int hi = std::min(cut_x ? ri->x + ri->width : ri->y + ri->height,
                          cut_x ? rj->x + rj->width : rj->y + rj->height);
  const int mid = std::clamp((lo + hi + 1) / 2, std::min(ci, cj) + 1, std::max(std::min(ci, cj) + 1, std::max(ci, cj)));
  const int big = std::numeric_limits<int>::max() / 4;
  keepRange(ri, ci < cj ? -big : mid, ci < cj ? mid : big, cut_x);
  keepRange(rj, ci < cj ? mid : -big, ci < cj ? big : mid, cut_x);
  return ci != cj;
}

// Step 2, overlap: every pair of overlapping rectangles (in index order) is separated. Doors on perpendicular
// walls: the overlap goes to the door nearer to it (along that door's normal); the other room ends where the
// overlap begins, when it keeps at least min_depth_px that way. Otherwise both cuts between the doors are tried
// and the one keeping more of the two rooms wins (doors in line: only the cut between).
void separateOverlaps(const Frame& f, const std::vector<DoorFrame>& doors, int min_depth_px,
                      std::vector<cv::Rect>* rects) {
  std::vector<cv::Rect>& r = *rects;
  for (size_t i = 0; i < doors.size(); ++i)
    for (size_t j = i + 1; j < doors.size(); ++j) {
      if (!doors[i].ok || !doors[j].ok || (r[i] & r[j]).area() == 0) continue;
      const cv::Point pi = f.at(doors[i], 0, doors[i].s0), pj = f.at(doors[j], 0, doors[j].s0);
      if ((doors[i].n.x != 0) != (doors[j].n.x != 0)) {
        const cv::Rect overlap = r[i] & r[j];
        const int gap_i = gapAlongNormal(doors[i], pi, overlap), gap_j = gapAlongNormal(doors[j], pj, overlap);
        const size_t farther = gap_i > gap_j ? i : j;
        const cv::Rect shortened = endBefore(doors[farther], r[farther], overlap);
        const int kept_depth = doors[farther].n.x != 0 ? shortened.width : shortened.height;
        if (gap_i != gap_j && kept_depth >= min_depth_px) {
          r[farther] = shortened;
          continue;
        }
      }
      cv::Rect xi = r[i], xj = r[j], yi = r[i], yj = r[j];
      const bool x_ok = cutBetweenDoors(true, pi, pj, &xi, &xj), y_ok = cutBetweenDoors(false, pi, pj, &yi, &yj);
      const bool use_x = x_ok && (!y_ok || xi.area() + xj.area() >= yi.area() + yj.area());
      r[i] = use_x ? xi : yi;
      r[j] = use_x ? xj : yj;
    }
}

// Step 3: per placed door the unknown pixels of its rectangle (working image), a pixel claimed by several rooms
// going to the nearest door (the earlier one on a tie), then only the part 4-connected to the door's entry pixel
// (all of it when that pixel is not the room's). Empty masks for doors not placed.
std::vector<cv::Mat1b> roomMasks(const Frame& f, const std::vector<DoorFrame>& doors,
                                 const std::vector<cv::Rect>& rects, const cv::Mat1b& states) {
  const size_t count = doors.size();
  const cv::Size work_size = states.size();
  std::vector<cv::Mat1b> masks(count);
  cv::Mat1s owner(work_size, static_cast<short>(-1));
  const cv::Mat1b unknown = states == kUnknownPx;
  for (size_t i = 0; i < count; ++i) {
    const DoorFrame& d = doors[i];
    if (!d.ok) continue;
    const cv::Rect rect = rects[i] & cv::Rect(0, 0, work_size.width, work_size.height);
    masks[i] = cv::Mat1b::zeros(work_size);
    if (rect.area() == 0) continue;
    masks[i](rect).setTo(255, unknown(rect));
    for (int r = rect.y; r < rect.br().y; ++r)
      for (int c = rect.x; c < rect.br().x; ++c) {
        if (!masks[i](r, c)) continue;
        short& o = owner(r, c);
        if (o < 0) {
          o = static_cast<short>(i);
          continue;
        }
        const cv::Point q(c, r);
        const cv::Point po = doors[o].p, pi = d.p;
        const double di = cv::norm(q - pi), dout = cv::norm(q - po);
        if (di < dout) o = static_cast<short>(i);
      }
  }
  for (size_t i = 0; i < count; ++i) {
    if (!doors[i].ok || masks[i].empty()) continue;
    // A room's pixels lie in its rectangle: the work below stays there (an empty rectangle, e.g. of two doors at
    // one place, leaves an empty room).
    const cv::Rect rect = rects[i] & cv::Rect(0, 0, work_size.width, work_size.height);
    if (rect.empty()) continue;
    cv::Mat1b in_rect = masks[i](rect);
    in_rect.setTo(0, owner(rect) != static_cast<short>(i));
    // Keep what is connected to the door.
    const cv::Point seed = f.at(doors[i], 0, doors[i].s0);
    if (!rect.contains(seed) || !masks[i](seed)) {
      // The door's own column may be claimed by another room: keep the largest part instead.
      continue;
    }
    cv::Mat1b flood = cv::Mat1b::zeros(rect.height + 2, rect.width + 2);
    cv::floodFill(in_rect, flood, seed - rect.tl(), 255, nullptr, 0, 0, 4 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
    flood(cv::Rect(1, 1, rect.width, rect.height)).copyTo(in_rect);
  }
  return masks;
}

// |a ∩ b| / |a ∪ b| of two masks of one size (0 when both are empty).
double maskIoU(const cv::Mat1b& a, const cv::Mat1b& b) {
  const double either = cv::countNonZero(a | b);
  return either > 0 ? cv::countNonZero(a & b) / either : 0.0;
}

// The rooms, one per door of the request: the masks without the map's known cells (`map_known`, 255), with the
// rectangle's terms; unplaced doors get an empty room with their problem.
std::vector<RoomPrediction> mapFrameRooms(const PredictionRequest& request, const std::vector<DoorFrame>& doors,
                                          const std::vector<cv::Rect>& rects, const std::vector<cv::Mat1b>& masks,
                                          const cv::Mat1b& map_known) {
  const common::OccupancyGrid& map = request.map;
  const double resolution = map.resolution;
  std::vector<RoomPrediction> rooms;
  for (size_t i = 0; i < doors.size(); ++i) {
    RoomPrediction room;
    room.door_id = request.doors.doors[i].id;
    room.problem = doors[i].problem;
    cv::Rect cells_within(0, 0, map.width(), map.height());  // where the room's cells lie: its rectangle
    if (doors[i].ok && !masks[i].empty()) {
      room.mask = masks[i];
      cells_within &= rects[i];
      room.mask(cells_within).setTo(0, map_known(cells_within));
      room.terms["width"] = (doors[i].right - doors[i].left + 1) * resolution;
      room.terms["depth"] = doors[i].depth * resolution;
      room.terms["depth_bounded"] = doors[i].bounded ? 1.0 : 0.0;
      room.terms["depth_source"] = doors[i].depth_source;
      room.terms["lateral_open"] = doors[i].lateral_open ? 1.0 : 0.0;
    } else {
      room.mask = cv::Mat1b::zeros(map.cells.size());
    }
    finishPrediction(map, &room, cells_within);
    rooms.push_back(std::move(room));
  }
  return rooms;
}

// The wall-fitted rectangle of every door (steps 1 to 3 of the header); `map_states` is the map's statesOf and
// `map_known` its known cells (255); `model_rooms` the learned model's room per door for the depth prior (null:
// none).
std::vector<RoomPrediction> rectangleRooms(const PredictionRequest& request, const DefaultOptions& P,
                                           const cv::Mat1b& map_states, const cv::Mat1b& map_known,
                                           const std::vector<NetworkRoom>* model_rooms) {
  const double resolution = request.map.resolution;
  const Frame f(map_states, cv::boundingRect(map_states != kUnknownPx));
  std::vector<DoorFrame> doors = framedDoors(request, P, f);
  const std::vector<std::vector<int>> siblings = splitSharedExtents(resolution, &doors);
  measureDepths(f, resolution, P, siblings, model_rooms, &doors);
  std::vector<cv::Rect> rects = doorRectangles(f, doors);
  separateOverlaps(f, doors, std::max(1, static_cast<int>(std::lround(P.min_depth / resolution))), &rects);
  const std::vector<cv::Mat1b> masks = roomMasks(f, doors, rects, map_states);
  return mapFrameRooms(request, doors, rects, masks, map_known);
}

// A map turned straight: its cells turned by -angle about their centre onto a grid large enough for all of them,
// and the doors moved with them. `forward` takes a pixel of the map to the turned grid's.
struct StraightRequest {
  PredictionRequest request;
  cv::Matx23d forward;
};

StraightRequest turnedStraight(const PredictionRequest& request, double angle) {
  StraightRequest straight;
  cv::Size turned_size;
  straight.forward = straighteningTransform(request.map.cells.size(), angle, &turned_size);
  const int W = turned_size.width, H = turned_size.height;
  // Each state turned with linear interpolation, so that a turned wall stays a closed line (nearest-pixel
  // sampling breaks a thin wall into steps with gaps): a cell is a wall when walls cover a quarter of it, else
  // free when free space covers half of it, else unknown.
  const cv::Mat1b states = statesOf(request.map);
  const auto turned = [&](uint8_t state) {
    cv::Mat1b moved;
    cv::warpAffine(states == state, moved, cv::Mat(straight.forward), cv::Size(W, H), cv::INTER_LINEAR,
                   cv::BORDER_CONSTANT, cv::Scalar(0));
    return moved;
  };
  common::OccupancyGrid& map = straight.request.map;
  map.resolution = request.map.resolution;
  map.origin = common::Point2::Zero();
  map.cells = cv::Mat_<int8_t>(cv::Size(W, H), common::OccupancyGrid::kUnknown);
  map.cells.setTo(common::OccupancyGrid::kFree, turned(kFreePx) >= 128);
  map.cells.setTo(common::OccupancyGrid::kOccupied, turned(kOccupiedPx) >= 64);
  straight.request.doors = request.doors;
  for (common::MapDoor& door : straight.request.doors.doors) {
    const common::Point2 image = request.map.toImage(door.position);
    const cv::Vec2d q = straight.forward * cv::Vec3d(image.x(), image.y(), 1.0);
    door.position = common::Point2(q[0] * map.resolution, (H - q[1]) * map.resolution);
  }  // |angle| < 45 degrees: each door's wall stays closest to the axis its orientation names
  straight.request.parameters = request.parameters;
  straight.request.debug_dir = request.debug_dir;
  return straight;
}

// The rooms of a map whose walls run along x and y: rectangle or grown room per door, then the outline clip and
// the wall margin (the header's steps).
PredictionResult roomsOnStraightMap(const PredictionRequest& request, const std::map<std::string, double>& values,
                                    const DefaultOptions& P) {
  // The grown rooms: the thesis's growth with its own constants on the layout this request configures. It does
  // not depend on the rectangles, so it runs on a second thread meanwhile.
  PredictionRequest grown_request;
  grown_request.map = request.map;
  grown_request.doors = request.doors;
  grown_request.debug_dir = request.debug_dir;
  for (const std::string& name : layoutParameterNames()) grown_request.parameters[name] = values.at(name);
  std::future<PredictionResult> growth =
      std::async(std::launch::async, [&grown_request] { return ThesisPredictor().predict(grown_request); });

  const cv::Mat1b states = statesOf(request.map);
  const cv::Mat1b known = request.map.cells != common::OccupancyGrid::kUnknown;
  const double resolution = request.map.resolution;
  // Cells within the wall margin of an occupied cell: the unseen rest of the walls the robot saw from one side
  // (predict estimates a negative margin from the map before this).
  const double wall_margin = std::max(0.0, P.wall_margin);

  // The learned model's room per door (room_network.h), when it chooses or replaces them (and gives rectangles
  // their depth where the map shows none); on maps too fine for it the area rule decides.
  const int network = networkReads(resolution) ? P.network : 0;
  std::vector<NetworkRoom> network_rooms;
  if (network > 0) {
    std::vector<NetworkDoor> network_doors;
    for (const common::MapDoor& door : request.doors.doors)
      network_doors.push_back({doorPixel(request.map, door), door.width});
    network_rooms = networkRooms(states, network_doors, roomScores(states, resolution, network_doors), resolution,
                                 kNetworkDoorReach, P.model_min_probability);
  }
  std::vector<RoomPrediction> rectangles =
      rectangleRooms(request, P, states, known, network > 0 && P.model_depth ? &network_rooms : nullptr);
  std::vector<RoomPrediction> grown = growth.get().rooms;
  // IoU of a room with the model's room of door i (-1 for a missing room).
  const auto agreement = [&](const RoomPrediction& room, size_t i) {
    if (!room.placed) return -1.0;
    const NetworkRoom& seen = network_rooms[i];
    const double both = seen.box.area() > 0 ? cv::countNonZero(room.mask(seen.box) & seen.mask) : 0;
    const double either = cv::countNonZero(room.mask) + cv::countNonZero(seen.mask) - both;
    return either > 0 ? both / either : 0.0;
  };
  // A stub may be where the rooms behind the wall end or only where an explored wall meets it: a door's rectangle
  // laid out past the stubs stands in for the stubbed one when most of the cells it adds are the model's room.
  if (network > 0 && P.stub_length > 0.0 && P.stub_by_model) {
    DefaultOptions past_stubs = P;
    past_stubs.stub_length = 0.0;
    std::vector<RoomPrediction> unstubbed =
        rectangleRooms(request, past_stubs, states, known, P.model_depth ? &network_rooms : nullptr);
    for (size_t i = 0; i < rectangles.size(); ++i) {
      const NetworkRoom& seen = network_rooms[i];
      if (!unstubbed[i].placed || !rectangles[i].placed || seen.box.area() == 0) continue;
      const cv::Mat1b added = unstubbed[i].mask & ~rectangles[i].mask;
      const int count = cv::countNonZero(added);
      if (count > 0 && 2 * cv::countNonZero(added(seen.box) & seen.mask) > count)
        rectangles[i] = std::move(unstubbed[i]);
    }
  }
  // Door i's grown room replaced by the model's room (which has no terms of its own).
  std::vector<bool> use_model(rectangles.size(), false);
  const auto take_model_room = [&](size_t i) {
    use_model[i] = true;
    grown[i].terms.clear();
    grown[i].mask = cv::Mat1b::zeros(request.map.cells.size());
    if (network_rooms[i].box.area() > 0) network_rooms[i].mask.copyTo(grown[i].mask(network_rooms[i].box));
    finishPrediction(request.map, &grown[i], network_rooms[i].box);
  };

  // Per door: the rectangle, the grown room or the model's room (the header's rule for each default_network),
  // never a missing one; a rectangle gives up the pixels of the grown rooms kept for other doors.
  const size_t count = rectangles.size();
  std::vector<bool> use_rectangle(count, false);
  std::vector<cv::Rect> boxes(count);  // bounding box of each chosen room: every later step only removes cells
  cv::Mat1b kept_grown = cv::Mat1b::zeros(request.map.cells.size());
  for (size_t i = 0; i < count; ++i) {
    if (network == 3) {
      CandidateAgreement iou;
      if (rectangles[i].placed && grown[i].placed) iou.rectangle_grown = maskIoU(rectangles[i].mask, grown[i].mask);
      iou.rectangle_model = std::max(0.0, agreement(rectangles[i], i));
      iou.grown_model = std::max(0.0, agreement(grown[i], i));
      const bool has_model_room = !network_rooms[i].mask.empty() && cv::countNonZero(network_rooms[i].mask) > 0;
      const RoomCandidate chosen = mostAgreedCandidate(iou, {rectangles[i].placed, grown[i].placed, has_model_room});
      if (chosen == RoomCandidate::kModel) take_model_room(i);
      use_rectangle[i] = chosen == RoomCandidate::kRectangle;
    } else if (network == 2) {
      take_model_room(i);
    } else if (network == 1) {
      use_rectangle[i] = rectangles[i].placed && agreement(rectangles[i], i) > agreement(grown[i], i);
    } else {
      use_rectangle[i] = rectangles[i].placed && grown[i].area < P.grown_area_ratio * rectangles[i].area;
    }
    const RoomPrediction& room = use_rectangle[i] ? rectangles[i] : grown[i];
    if (room.placed) boxes[i] = cv::boundingRect(room.mask);
    if (!use_rectangle[i] && grown[i].placed) kept_grown(boxes[i]) |= grown[i].mask(boxes[i]);
  }
  cv::Mat1b wall_band;
  if (wall_margin > 0.0) {
    // Computed around the rooms only, with a margin beyond them so that their cells get their true distances.
    cv::Rect rooms_box;
    for (const cv::Rect& box : boxes) rooms_box |= box;
    const int reach = static_cast<int>(std::ceil(wall_margin / resolution)) + 2;
    const cv::Rect box = cv::Rect(rooms_box.x - reach, rooms_box.y - reach, rooms_box.width + 2 * reach,
                                  rooms_box.height + 2 * reach) &
                         cv::Rect(0, 0, request.map.width(), request.map.height());
    wall_band = cv::Mat1b::zeros(request.map.cells.size());
    if (rooms_box.area() > 0 && box.area() > 0) {
      cv::Mat1f distance;
      cv::distanceTransform(request.map.cells(box) < kOccupiedFrom, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
      wall_band(box).setTo(255, distance * resolution <= wall_margin);
    }
  }
  PredictionResult result;
  for (size_t i = 0; i < count; ++i) {
    RoomPrediction room = std::move(use_rectangle[i] ? rectangles[i] : grown[i]);
    const cv::Rect& box = boxes[i];
    const auto cells = [&] { return cv::countNonZero(room.mask(box)); };
    if (use_rectangle[i]) {
      room.mask(box).setTo(0, kept_grown(box));
      finishPrediction(request.map, &room, box);
    }
    if (P.outline_reach > 0.0 && room.placed) {
      const int before = cells();
      clipToKnownOutline(known, doorPixel(request.map, request.doors.doors[i]),
                         static_cast<int>(std::lround(P.outline_reach / resolution)),
                         static_cast<int>(std::lround(P.min_depth / resolution)), &room.mask);
      room.terms["outline_clipped"] = (before - cells()) * resolution * resolution;
      finishPrediction(request.map, &room, box);
    }
    if (!wall_band.empty() && room.placed) {
      const int before = cells();
      room.mask(box).setTo(0, wall_band(box));
      room.terms["wall_margin"] = wall_margin;
      room.terms["wall_margin_cut"] = (before - cells()) * resolution * resolution;
      finishPrediction(request.map, &room, box);
    }
    room.terms["rectangle"] = use_rectangle[i] ? 1.0 : 0.0;
    room.terms["model_room"] = use_model[i] ? 1.0 : 0.0;
    result.rooms.push_back(std::move(room));
  }
  return result;
}

// The rooms of `request` predicted on its map turned straight by `angle` (radians; not turned when under
// min_rotation), turned back onto the map.
PredictionResult roomsAtAngle(const PredictionRequest& request, double angle,
                              const std::map<std::string, double>& values, const DefaultOptions& P) {
  if (std::abs(angle * 180.0 / CV_PI) < P.min_rotation) return roomsOnStraightMap(request, values, P);
  const StraightRequest straight = turnedStraight(request, angle);
  PredictionResult result = roomsOnStraightMap(straight.request, values, P);
  const cv::Mat1b known = request.map.cells != common::OccupancyGrid::kUnknown;
  for (RoomPrediction& room : result.rooms) {
    if (!room.placed) {
      room.mask = cv::Mat1b::zeros(request.map.cells.size());
      continue;
    }
    cv::Mat1b back;
    cv::warpAffine(room.mask, back, cv::Mat(straight.forward), request.map.cells.size(),
                   cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, cv::Scalar(0));
    room.mask = (back >= 128) & ~known;
    finishPrediction(request.map, &room);
  }
  return result;
}

// Difference of two wall angles modulo 90 degrees, radians in [-pi/4, pi/4).
double wallAngleDifference(double a, double b) {
  double d = std::fmod(a - b + CV_PI / 4.0, CV_PI / 2.0);
  if (d < 0) d += CV_PI / 2.0;
  return d - CV_PI / 4.0;
}

constexpr size_t kMaxFrames = 8;  // frames of one prediction at most (predictionFrames)
constexpr size_t kLocalAnglePoints = 2000;  // wall cells a door's angle is measured on (evenly thinned beyond)

// The dominant wall angle within `radius` metres of each door (dominantWallAngle of that part of the map), or
// `global` where that part shows too few wall cells to tell.
std::vector<double> localWallAngles(const PredictionRequest& request, double global, double radius) {
  const common::OccupancyGrid& map = request.map;
  const int r = static_cast<int>(std::lround(radius / map.resolution));
  const int min_cells = std::max(20, r);  // about a wall across the window
  std::vector<double> angles;
  for (const common::MapDoor& door : request.doors.doors) {
    const cv::Point p = doorPixel(map, door);
    const cv::Rect window = cv::Rect(p.x - r, p.y - r, 2 * r + 1, 2 * r + 1) & cv::Rect(0, 0, map.width(), map.height());
    common::OccupancyGrid part;
    part.resolution = map.resolution;
    if (window.area() > 0) part.cells = map.cells(window);
    const bool enough = window.area() > 0 && cv::countNonZero(part.cells >= kOccupiedFrom) >= min_cells;
    angles.push_back(enough ? dominantWallAngle(part, kLocalAnglePoints) : global);
  }
  return angles;
}

// The frames the doors are predicted in: the map's dominant wall angle first, then each door's own angle
// (localWallAngles) when it lies more than local_frame_tolerance from every frame so far, up to kMaxFrames frames
// (each is a whole prediction: a building has a few wall directions, a drifted map a few parts); otherwise the
// door joins the frame nearest to its angle.
struct PredictionFrames {
  std::vector<double> angles;   // radians, the map's first
  std::vector<size_t> frame_of;  // per door, its frame's index
};

PredictionFrames predictionFrames(const PredictionRequest& request, const DefaultOptions& P) {
  PredictionFrames frames;
  frames.angles.push_back(dominantWallAngle(request.map));
  frames.frame_of.assign(request.doors.doors.size(), 0);
  if (P.local_frame_radius <= 0.0) return frames;
  const double tolerance = P.local_frame_tolerance * CV_PI / 180.0;
  const std::vector<double> local = localWallAngles(request, frames.angles[0], P.local_frame_radius);
  for (size_t i = 0; i < local.size(); ++i) {
    size_t nearest = 0;
    for (size_t frame = 1; frame < frames.angles.size(); ++frame)
      if (std::abs(wallAngleDifference(local[i], frames.angles[frame])) <
          std::abs(wallAngleDifference(local[i], frames.angles[nearest])))
        nearest = frame;
    const bool apart = std::abs(wallAngleDifference(local[i], frames.angles[nearest])) > tolerance;
    if (apart && frames.angles.size() < kMaxFrames) {
      nearest = frames.angles.size();
      frames.angles.push_back(local[i]);
    }
    frames.frame_of[i] = nearest;
  }
  return frames;
}

}  // namespace

PredictionResult DefaultPredictor::predict(const PredictionRequest& request) const {
  const auto start_time = std::chrono::steady_clock::now();
  checkUsableRequest(request);
  const auto values = resolveParameters(*this, request.parameters);
  DefaultOptions P;
  common::applyOptionValues(defaultOptionTable(), values, &P, "parameter ");
  common::validateOptions(defaultOptionTable(), P, "parameter ");
  // A turned map (every SLAM map is a little) is predicted turned straight, where the layout's cells and the
  // rectangles are axis-aligned, and its rooms are turned back; each door in the frame of the walls around it.
  const PredictionFrames frames = predictionFrames(request, P);
  // The unseen wall thickness is the map's: measured on its cells as given, not on a copy resampled straight
  // (resampling thickens thin walls), and shared by every frame.
  if (P.wall_margin < 0.0) P.wall_margin = unseenWallThickness(request.map, frames.angles[0]);
  PredictionResult result;
  result.rooms.resize(request.doors.doors.size());
  for (size_t g = 0; g < frames.angles.size(); ++g) {
    PredictionRequest part = request;
    part.doors.doors.clear();
    std::vector<size_t> members;
    for (size_t i = 0; i < frames.frame_of.size(); ++i)
      if (frames.frame_of[i] == g) members.push_back(i), part.doors.doors.push_back(request.doors.doors[i]);
    // The layout's debug images are those of the map's own frame, which runs for them even without doors.
    if (g > 0) part.debug_dir.clear();
    if (members.empty() && part.debug_dir.empty()) continue;
    PredictionResult rooms = roomsAtAngle(part, frames.angles[g], values, P);
    for (size_t k = 0; k < members.size(); ++k) {
      rooms.rooms[k].terms["rotation"] = frames.angles[g] * 180.0 / CV_PI;
      result.rooms[members[k]] = std::move(rooms.rooms[k]);
    }
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return result;
}

}  // namespace hidden_rooms::prediction
