#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc.hpp>

#include "hidden_rooms/segmentation/segmenters.h"

namespace hidden_rooms::segmentation {

namespace {

// Union-find over cells; each root keeps the largest distance to a wall in its basin.
class Basins {
 public:
  explicit Basins(size_t cells) : parent_(cells, -1), peak_(cells, 0.0f) {}
  bool seen(int cell) const { return parent_[cell] >= 0; }
  void open(int cell, float distance) {
    parent_[cell] = cell;
    peak_[cell] = distance;
  }
  int root(int cell) {
    while (parent_[cell] != cell) {
      parent_[cell] = parent_[parent_[cell]];
      cell = parent_[cell];
    }
    return cell;
  }
  float peak(int root) const { return peak_[root]; }
  void join(int root, int into) {
    parent_[root] = into;
    peak_[into] = std::max(peak_[into], peak_[root]);
  }

 private:
  std::vector<int> parent_;
  std::vector<float> peak_;
};

// The cells of the line from `from` along `direction` (unit), one per step of a cell, at most `steps`.
std::vector<cv::Point> ray(const cv::Point2d& from, const cv::Point2d& direction, int steps) {
  std::vector<cv::Point> cells;
  for (int step = 1; step <= steps; ++step) {
    const cv::Point2d at = from + direction * step;
    cells.emplace_back(static_cast<int>(std::lround(at.x)), static_cast<int>(std::lround(at.y)));
  }
  return cells;
}

// Closes the openings of straight walls: from the free end (tip) of every thin wall, along the wall's direction,
// the free run to the next obstacle becomes a border when it is at most `max_gap` cells long and the wall line goes
// on beyond that obstacle (a thin wall along the same line, at least `min_run` cells, with no free run longer than
// `max_gap` before it). So a room whose open front lies on a corridor's wall line is cut from the corridor along
// that line, while a wall that ends in a corridor does not cut it (no wall continues its line across).
cv::Mat1b closeWallGaps(const cv::Mat1b& free, int max_gap, int min_run, int max_wall_thickness) {
  // Thin walls: obstacle cells that an opening by a disc wider than a wall removes (thick blocks and the
  // unknown outside stay).
  const cv::Mat1b obstacle = free == 0;
  cv::Mat1b thick;
  const int diameter = max_wall_thickness + 1;
  cv::morphologyEx(obstacle, thick, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(diameter, diameter)));
  const cv::Mat1b thin = obstacle & ~thick;
  cv::Mat1b skeleton;
  cv::ximgproc::thinning(thin, skeleton, cv::ximgproc::THINNING_GUOHALL);

  cv::Mat1b closed = free.clone();
  for (int row = 0; row < skeleton.rows; ++row)
    for (int col = 0; col < skeleton.cols; ++col) {
      if (skeleton(row, col) == 0) continue;
      // A tip: one skeleton neighbour. Its direction: from the skeleton cell min_run steps back to the tip.
      cv::Point tip(col, row), previous(-1, -1), at = tip;
      int neighbours = 0;
      for (const cv::Point& step : kNeighbours8)
        neighbours += insideImage(skeleton, tip + step) && skeleton(tip + step) != 0;
      if (neighbours != 1) continue;
      int traced = 0;
      for (; traced < min_run; ++traced) {
        cv::Point next(-1, -1);
        for (const cv::Point& step : kNeighbours8) {
          const cv::Point candidate = at + step;
          if (candidate != previous && insideImage(skeleton, candidate) && skeleton(candidate) != 0) next = candidate;
        }
        if (next.x < 0) break;
        previous = at;
        at = next;
      }
      if (traced < min_run) continue;  // a stub, not a wall
      cv::Point2d direction(tip.x - at.x, tip.y - at.y);
      direction /= std::hypot(direction.x, direction.y);

      // Out of the wall, across the free run, to the obstacle at its end.
      const std::vector<cv::Point> line = ray(cv::Point2d(tip), direction, 2 * (max_gap + min_run) + max_wall_thickness);
      size_t i = 0;
      while (i < line.size() && insideImage(free, line[i]) && free(line[i]) == 0) ++i;
      const size_t gap_begin = i;
      while (i < line.size() && insideImage(free, line[i]) && free(line[i]) != 0) ++i;
      const size_t gap_end = i;
      if (gap_end == gap_begin || gap_end - gap_begin > static_cast<size_t>(max_gap) || i >= line.size() ||
          !insideImage(free, line[i]))
        continue;
      // Beyond: the wall line goes on.
      bool continues = false;
      int run = 0, free_run = 0;
      for (; i < line.size() && insideImage(free, line[i]) && !continues; ++i) {
        if (free(line[i]) != 0) {
          run = 0;
          if (++free_run > max_gap) break;
          continue;
        }
        free_run = 0;
        run = thin(line[i]) != 0 ? run + 1 : 0;
        continues = run >= min_run;
      }
      if (!continues) continue;
      cv::line(closed, line[gap_begin], line[gap_end - 1], cv::Scalar(0), 2);
    }
  return closed & free;
}

}  // namespace

std::map<std::string, double> PassageSegmenter::defaultParameters() const {
  return {
      {"passage_ratio", 0.6},
      {"max_passage_width", 2.0},
      {"min_room_area", 1.0},
      {"min_isolated_area", 0.25},
      {"min_room_width", 0.5},
      {"max_wall_gap", 2.5},
  };
}

cv::Mat1i PassageSegmenter::segment(const SegmentationInput& input,
                                    const std::map<std::string, double>& parameters) const {
  const double ratio = parameters.at("passage_ratio");
  const double max_half_width = 0.5 * parameters.at("max_passage_width") / input.resolution;  // cells
  const int max_gap = static_cast<int>(std::lround(parameters.at("max_wall_gap") / input.resolution));
  const cv::Mat1b free =
      max_gap > 0 ? closeWallGaps(input.free, max_gap, static_cast<int>(std::lround(0.3 / input.resolution)),
                                  static_cast<int>(std::lround(0.3 / input.resolution)))
                  : input.free;
  cv::Mat1f distance;
  cv::distanceTransform(free, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);

  // Free cells from the widest to the narrowest (bucketed by an eighth of a cell, row-major within a bucket).
  const int cols = free.cols;
  std::vector<int> order;
  {
    double max_distance = 0.0;
    cv::minMaxLoc(distance, nullptr, &max_distance);
    const int buckets = static_cast<int>(max_distance * 8.0) + 1;
    const float* d = distance[0];
    const size_t cells = free.total();
    const auto bucket = [&](size_t i) { return buckets - 1 - static_cast<int>(d[i] * 8.0f); };
    std::vector<int> offset(buckets + 1, 0);
    for (size_t i = 0; i < cells; ++i)
      if (d[i] > 0.0f) ++offset[bucket(i) + 1];
    std::partial_sum(offset.begin(), offset.end(), offset.begin());
    order.resize(offset[buckets]);
    for (size_t i = 0; i < cells; ++i)
      if (d[i] > 0.0f) order[offset[bucket(i)]++] = static_cast<int>(i);
  }

  // Flood from the maxima down. Each cell drains to the basin of its highest neighbour (steepest ascent of the
  // distance); the other basins it touches merge with that one unless the cell is a constriction between them.
  Basins basins(free.total());
  std::vector<int> roots;
  for (const int cell : order) {
    const int row = cell / cols, col = cell % cols;
    const float level = distance(row, col);
    roots.clear();
    int highest = -1;
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) {
        const int r = row + dr, c = col + dc;
        if ((dr == 0 && dc == 0) || r < 0 || c < 0 || r >= free.rows || c >= cols) continue;
        const int neighbour = r * cols + c;
        if (!basins.seen(neighbour)) continue;
        if (highest < 0 || distance(r, c) > distance(highest / cols, highest % cols)) highest = neighbour;
        const int root = basins.root(neighbour);
        if (std::find(roots.begin(), roots.end(), root) == roots.end()) roots.push_back(root);
      }
    basins.open(cell, level);
    if (roots.empty()) continue;
    int base = basins.root(highest);
    basins.join(cell, base);
    for (const int root : roots) {
      base = basins.root(base);
      if (basins.root(root) == base) continue;
      const float smaller_peak = std::min(basins.peak(base), basins.peak(root));
      const bool constriction = level <= max_half_width && level < ratio * smaller_peak;
      if (!constriction) basins.join(basins.root(root), base);
    }
  }

  cv::Mat1i labels(free.size(), 0);
  for (const int cell : order) labels(cell / cols, cell % cols) = basins.root(cell) + 1;
  const double cell_area = input.resolution * input.resolution;
  RoomLimits limits;
  limits.min_area = parameters.at("min_room_area") / cell_area;
  limits.min_half_width = 0.5 * parameters.at("min_room_width") / input.resolution;
  limits.min_isolated_area = parameters.at("min_isolated_area") / cell_area;
  mergeSmallRooms(free, distance, limits, &labels);
  spreadLabels(input.free, &labels);  // onto the closed gaps
  return labels;
}

}  // namespace hidden_rooms::segmentation
