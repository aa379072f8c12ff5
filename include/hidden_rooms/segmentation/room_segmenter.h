#pragma once

// Room segmentation of an occupancy grid: every free cell gets a room label. One interface for the package's
// method and the survey's baselines (Bormann et al., ICRA 2016), chosen by name (`makeRoomSegmenter`).

#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace hidden_rooms::segmentation {

// What every method gets: the cells a robot can stand in (255 free, 0 wall or unknown) and the grid's resolution.
// Borders the caller knows (closed doors) are drawn into `free` as 0 beforehand.
struct SegmentationInput {
  cv::Mat1b free;
  double resolution = 0.05;  // metres per cell
};

class RoomSegmenter {
 public:
  virtual ~RoomSegmenter() = default;
  virtual std::string name() const = 0;
  // Every parameter the method reads, with its default (config/segmentation.yaml documents them).
  virtual std::map<std::string, double> defaultParameters() const = 0;
  // Labels of the input's size: one positive number per room on its cells, 0 on free cells the method leaves out
  // (pockets too small to be a room); non-free cells may hold anything (segmentRooms clears them and numbers the
  // rooms 1..N). `parameters` holds the method's defaults with the caller's overrides (resolveSegmenterParameters).
  virtual cv::Mat1i segment(const SegmentationInput& input, const std::map<std::string, double>& parameters) const = 0;
};

// The registered methods, e.g. {"default", "morphological", "voronoi"}.
std::vector<std::string> roomSegmenterNames();
// Throws InputError naming the method and the known ones when `name` is not registered.
std::unique_ptr<RoomSegmenter> makeRoomSegmenter(const std::string& name);

// The method's defaults with the overrides applied. Overrides that only other methods read are ignored (one
// parameters file serves every method); a name no method reads, or a non-finite value, throws
// InputError("parameters", ...).
std::map<std::string, double> resolveSegmenterParameters(const RoomSegmenter& method,
                                                         const std::map<std::string, double>& overrides);

// Segments with the method's parameters resolved. Throws InputError for an empty input, a non-positive resolution,
// or an input without free cells.
cv::Mat1w segmentRooms(const RoomSegmenter& method, const SegmentationInput& input,
                       const std::map<std::string, double>& overrides = {});

// --- Building blocks shared by the methods ---

// The eight neighbours of a cell, row by row; the forward half of them (right and the row below), so that a scan
// over all cells visits every pair of neighbouring cells once.
inline const cv::Point kNeighbours8[] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0}, {1, 0}, {-1, 1}, {0, 1}, {1, 1}};
inline const cv::Point kForwardNeighbours[] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
inline bool insideImage(const cv::Mat& image, const cv::Point& cell) {
  return cell.x >= 0 && cell.y >= 0 && cell.x < image.cols && cell.y < image.rows;
}

// Grows the labelled cells of `labels` into the unlabelled free cells (8-connected breadth-first, each cell taking
// the label that reaches it first: borders fall halfway between the seeds), at most `max_steps` cells far. Free
// cells no label reaches stay 0.
void spreadLabels(const cv::Mat1b& free, cv::Mat1i* labels, int max_steps = std::numeric_limits<int>::max());

// What a room needs to be one (cells).
struct RoomLimits {
  double min_area = 0.0;        // smaller rooms join a neighbour
  double min_half_width = 0.0;  // so do rooms whose largest distance to a wall is below this
  double min_isolated_area = 0.0;  // a room too small or narrow without neighbours stays one with this area
};

// Merges every room below `limits` (area, or largest value of `distance` over its cells) into the neighbouring room
// it shares the longest border with (8-neighbourhood through free cells), smallest first, so that a chain of small
// rooms ends in a large one; a small room without neighbours stays a room when it has at least
// `limits.min_isolated_area` cells and is not too narrow, else it is dropped (label 0). Then numbers the labels
// 1..N in order of first appearance (row-major).
void mergeSmallRooms(const cv::Mat1b& free, const cv::Mat1f& distance, const RoomLimits& limits, cv::Mat1i* labels);

// Numbers the labels 1..N in order of first appearance (row-major), 0 staying 0.
void relabelConsecutively(cv::Mat1i* labels);

}  // namespace hidden_rooms::segmentation
