#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include <opencv2/imgproc.hpp>

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

}  // namespace

std::map<std::string, double> PassageSegmenter::defaultParameters() const {
  return {
      {"passage_ratio", 0.6},
      {"max_passage_width", 2.0},
      {"min_room_area", 1.0},
      {"min_isolated_area", 0.25},
  };
}

cv::Mat1i PassageSegmenter::segment(const SegmentationInput& input,
                                    const std::map<std::string, double>& parameters) const {
  const double ratio = parameters.at("passage_ratio");
  const double max_half_width = 0.5 * parameters.at("max_passage_width") / input.resolution;  // cells
  const cv::Mat1b& free = input.free;
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
  mergeSmallRooms(free, parameters.at("min_room_area") / cell_area, parameters.at("min_isolated_area") / cell_area,
                  &labels);
  return labels;
}

}  // namespace hidden_rooms::segmentation
