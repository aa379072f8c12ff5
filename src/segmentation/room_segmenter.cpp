#include "hidden_rooms/segmentation/room_segmenter.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <set>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/segmentation/segmenters.h"

namespace hidden_rooms::segmentation {

namespace {

using Factory = std::function<std::unique_ptr<RoomSegmenter>()>;

const std::map<std::string, Factory>& registry() {
  static const std::map<std::string, Factory> methods = {
      {"default", [] { return std::make_unique<PassageSegmenter>(); }},
      {"morphological", [] { return std::make_unique<MorphologicalSegmenter>(); }},
      {"voronoi", [] { return std::make_unique<VoronoiSegmenter>(); }},
  };
  return methods;
}

// Every parameter name some registered method reads.
const std::set<std::string>& namesReadByAnyMethod() {
  static const std::set<std::string> names = [] {
    std::set<std::string> all;
    for (const auto& [name, factory] : registry())
      for (const auto& [parameter, value] : factory()->defaultParameters()) all.insert(parameter);
    return all;
  }();
  return names;
}

}  // namespace

std::vector<std::string> roomSegmenterNames() {
  std::vector<std::string> names;
  for (const auto& [name, factory] : registry()) names.push_back(name);
  return names;
}

std::unique_ptr<RoomSegmenter> makeRoomSegmenter(const std::string& name) {
  const auto found = registry().find(name);
  if (found != registry().end()) return found->second();
  std::string known;
  for (const std::string& each : roomSegmenterNames()) known += (known.empty() ? "" : ", ") + each;
  throw common::InputError("method", "unknown segmentation method '" + name + "' (known: " + known + ")");
}

std::map<std::string, double> resolveSegmenterParameters(const RoomSegmenter& method,
                                                         const std::map<std::string, double>& overrides) {
  std::map<std::string, double> parameters = method.defaultParameters();
  for (const auto& [name, value] : overrides) {
    if (!namesReadByAnyMethod().count(name)) throw common::InputError("parameters", "no segmentation method reads '" + name + "'");
    if (!std::isfinite(value))
      throw common::InputError("parameters", "'" + name + "' must be finite, got " + common::formatNumber(value));
    const auto own = parameters.find(name);
    if (own != parameters.end()) own->second = value;
  }
  return parameters;
}

cv::Mat1w segmentRooms(const RoomSegmenter& method, const SegmentationInput& input,
                       const std::map<std::string, double>& overrides) {
  if (input.free.empty()) throw common::InputError("map", "is empty");
  if (!(input.resolution > 0.0) || !std::isfinite(input.resolution))
    throw common::InputError("map", "resolution must be positive, got " + common::formatNumber(input.resolution));
  if (cv::countNonZero(input.free) == 0) throw common::InputError("map", "has no free cell");
  cv::Mat1i labels = method.segment(input, resolveSegmenterParameters(method, overrides));
  labels.setTo(0, input.free == 0);
  relabelConsecutively(&labels);
  double max_label = 0.0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  if (max_label > std::numeric_limits<uint16_t>::max())
    throw common::InputError("map", "splits into " + common::formatNumber(max_label) + " rooms, more than a label "
                             "image holds (65535): is it a map of a building?");
  cv::Mat1w rooms;
  labels.convertTo(rooms, CV_16U);
  return rooms;
}

void spreadLabels(const cv::Mat1b& free, cv::Mat1i* labels, int max_steps) {
  std::vector<cv::Point> front;  // the cells labelled in the last step
  for (int row = 0; row < labels->rows; ++row)
    for (int col = 0; col < labels->cols; ++col)
      if ((*labels)(row, col) != 0) front.emplace_back(col, row);
  for (int step = 0; step < max_steps && !front.empty(); ++step) {
    std::vector<cv::Point> next_front;
    for (const cv::Point& cell : front)
      for (const cv::Point& offset : kNeighbours8) {
        const cv::Point next = cell + offset;
        if (!insideImage(free, next) || free(next) == 0 || (*labels)(next) != 0) continue;
        (*labels)(next) = (*labels)(cell);
        next_front.push_back(next);
      }
    front.swap(next_front);
  }
}

void relabelConsecutively(cv::Mat1i* labels) {
  double max_label = 0.0;
  cv::minMaxLoc(*labels, nullptr, &max_label);
  std::vector<int> renumbered(static_cast<size_t>(max_label) + 1, 0);
  int next = 0;
  for (int& label : *labels) {
    if (label <= 0) {
      label = 0;
      continue;
    }
    if (renumbered[label] == 0) renumbered[label] = ++next;
    label = renumbered[label];
  }
}

void mergeSmallRooms(const cv::Mat1b& free, const cv::Mat1f& distance, const RoomLimits& limits, cv::Mat1i* labels) {
  relabelConsecutively(labels);
  double max_label = 0.0;
  cv::minMaxLoc(*labels, nullptr, &max_label);
  const int count = static_cast<int>(max_label);
  // The room graph once: areas, peaks, and per pair of rooms the cell pairs they share (8-neighbourhood).
  std::vector<double> area(count + 1, 0.0), peak(count + 1, 0.0);
  std::vector<std::map<int, double>> border(count + 1);
  for (int row = 0; row < labels->rows; ++row)
    for (int col = 0; col < labels->cols; ++col) {
      const int label = (*labels)(row, col);
      if (label == 0) continue;
      ++area[label];
      peak[label] = std::max(peak[label], static_cast<double>(distance(row, col)));
      for (const cv::Point& step : kForwardNeighbours) {
        const int r = row + step.y, c = col + step.x;
        if (r >= labels->rows || c < 0 || c >= labels->cols || free(r, c) == 0) continue;
        const int other = (*labels)(r, c);
        if (other == 0 || other == label) continue;
        ++border[label][other];
        ++border[other][label];
      }
    }
  const auto tooSmall = [&](int label) { return area[label] < limits.min_area || peak[label] < limits.min_half_width; };
  std::vector<int> merged_into(count + 1, 0);  // 0: still a room; -1: dropped
  std::set<std::pair<double, int>> small;
  for (int label = 1; label <= count; ++label)
    if (area[label] > 0 && tooSmall(label)) small.emplace(area[label], label);
  while (!small.empty()) {
    const int label = small.begin()->second;
    small.erase(small.begin());
    int target = 0;
    for (const auto& [other, length] : border[label])
      if (target == 0 || length > border[label][target]) target = other;
    if (target == 0) {  // no neighbour to join
      if (area[label] < limits.min_isolated_area || peak[label] < limits.min_half_width) merged_into[label] = -1;
      continue;
    }
    merged_into[label] = target;
    small.erase({area[target], target});
    area[target] += area[label];
    peak[target] = std::max(peak[target], peak[label]);
    if (tooSmall(target)) small.emplace(area[target], target);
    for (const auto& [other, length] : border[label]) {
      border[other].erase(label);
      if (other == target) continue;
      border[other][target] += length;
      border[target][other] += length;
    }
    border[label].clear();
  }
  std::vector<int> final_label(count + 1, 0);
  for (int label = 1; label <= count; ++label) {
    int root = label;
    while (merged_into[root] > 0) root = merged_into[root];
    final_label[label] = merged_into[root] < 0 ? 0 : root;
  }
  for (auto& label : *labels) label = final_label[label];
  relabelConsecutively(labels);
}

}  // namespace hidden_rooms::segmentation
