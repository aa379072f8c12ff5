#include "hidden_rooms/segmentation/segmentation_metrics.h"

#include <cmath>
#include <map>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::segmentation {

namespace {

double pairs(double n) { return 0.5 * n * (n - 1.0); }

// Cells per label, keeping only labels of at least `min_cells` cells (the others map to -1).
std::vector<int> keptIndex(const cv::Mat1w& labels, int min_cells, std::vector<double>* sizes) {
  std::vector<double> count(65536, 0.0);
  for (const uint16_t label : labels) ++count[label];
  std::vector<int> index(65536, -1);
  for (int label = 1; label < 65536; ++label)
    if (count[label] >= min_cells) {
      index[label] = static_cast<int>(sizes->size());
      sizes->push_back(count[label]);
    }
  return index;
}

}  // namespace

SegmentationScores scoreSegmentation(const cv::Mat1w& found, const cv::Mat1w& truth, int min_region_cells) {
  if (found.size() != truth.size())
    throw common::InputError("segmentation", "is " + std::to_string(found.cols) + "x" + std::to_string(found.rows) +
                                                 " cells, the ground truth " + std::to_string(truth.cols) + "x" +
                                                 std::to_string(truth.rows));
  std::vector<double> truth_size, found_size;
  const std::vector<int> truth_index = keptIndex(truth, min_region_cells, &truth_size);
  const std::vector<int> found_index = keptIndex(found, min_region_cells, &found_size);
  if (truth_size.empty()) throw common::InputError("ground truth", "has no room");

  // Overlaps of kept rooms and kept segments; for the pair counts also the cells of kept rooms per raw segment.
  std::map<std::pair<int, int>, double> overlap;
  std::map<int, double> truth_cells_in_segment;  // raw segment label (0: none) -> cells in kept rooms
  std::map<std::pair<int, int>, double> truth_segment_cells;
  for (int row = 0; row < truth.rows; ++row)
    for (int col = 0; col < truth.cols; ++col) {
      const int room = truth_index[truth(row, col)];
      const int segment_label = found(row, col);
      const int segment = found_index[segment_label];
      if (room >= 0 && segment >= 0) ++overlap[{segment, room}];
      if (room >= 0 && segment_label != 0) {
        ++truth_cells_in_segment[segment_label];
        ++truth_segment_cells[{segment_label, room}];
      }
    }

  SegmentationScores scores;
  scores.truth_rooms = static_cast<int>(truth_size.size());
  scores.found_rooms = static_cast<int>(found_size.size());
  std::vector<double> best_for_room(truth_size.size(), 0.0), best_for_segment(found_size.size(), 0.0);
  for (const auto& [key, cells] : overlap) {
    best_for_segment[key.first] = std::max(best_for_segment[key.first], cells);
    best_for_room[key.second] = std::max(best_for_room[key.second], cells);
  }
  double overlap_sum = 0.0, size_sum = 0.0;
  for (size_t room = 0; room < truth_size.size(); ++room) {
    scores.recall_micro += best_for_room[room] / truth_size[room];
    overlap_sum += best_for_room[room];
    size_sum += truth_size[room];
  }
  scores.recall_micro /= truth_size.size();
  scores.recall_macro = overlap_sum / size_sum;
  if (!found_size.empty()) {
    overlap_sum = size_sum = 0.0;
    for (size_t segment = 0; segment < found_size.size(); ++segment) {
      scores.precision_micro += best_for_segment[segment] / found_size[segment];
      overlap_sum += best_for_segment[segment];
      size_sum += found_size[segment];
    }
    scores.precision_micro /= found_size.size();
    scores.precision_macro = overlap_sum / size_sum;
  }

  // Pair counts over the cells of kept rooms.
  double cells = 0.0, truth_pairs = 0.0, found_pairs = 0.0, both_pairs = 0.0;
  for (const double size : truth_size) {
    cells += size;
    truth_pairs += pairs(size);
  }
  for (const auto& [segment, count] : truth_cells_in_segment) found_pairs += pairs(count);
  for (const auto& [key, count] : truth_segment_cells) both_pairs += pairs(count);
  const double all_pairs = pairs(cells);
  const double tp = both_pairs, fp = found_pairs - both_pairs, fn = truth_pairs - both_pairs;
  const double tn = all_pairs - tp - fp - fn;
  const double denominator = std::sqrt((tp + fp) * (tp + fn) * (tn + fp) * (tn + fn));
  scores.mcc = denominator > 0.0 ? (tp * tn - fp * fn) / denominator : 0.0;
  return scores;
}

double LabelScores::recall(const std::string& label) const {
  const auto found = per_label.find(label);
  return found == per_label.end() || found->second.second == 0
             ? 1.0
             : static_cast<double>(found->second.first) / found->second.second;
}

LabelScores scoreRoomLabels(const cv::Mat1w& found, const std::vector<std::string>& found_labels,
                            const cv::Mat1w& truth, const std::vector<std::string>& truth_labels,
                            int min_region_cells) {
  if (found.size() != truth.size()) throw common::InputError("segmentation", "differs in size from the ground truth");
  std::map<int, std::map<int, int>> overlap;  // found room -> ground-truth room -> cells
  std::map<int, int> size;
  for (int row = 0; row < found.rows; ++row)
    for (int col = 0; col < found.cols; ++col) {
      const int label = found(row, col);
      if (label == 0) continue;
      ++size[label];
      if (truth(row, col) != 0) ++overlap[label][truth(row, col)];
    }
  LabelScores scores;
  for (const auto& [room, cells] : overlap) {
    if (size[room] < min_region_cells) continue;
    int best = 0;
    for (const auto& [truth_room, count] : cells)
      if (best == 0 || count > cells.at(best)) best = truth_room;
    if (room > static_cast<int>(found_labels.size()))
      throw common::InputError("segmentation", "room " + std::to_string(room) + " has no label");
    if (best > static_cast<int>(truth_labels.size()))
      throw common::InputError("ground truth", "room " + std::to_string(best) + " has no label");
    const std::string& expected = truth_labels[best - 1];
    if (expected.empty()) continue;
    const bool right = found_labels[room - 1] == expected;
    ++scores.rooms;
    scores.correct += right;
    ++scores.per_label[expected].second;
    scores.per_label[expected].first += right;
  }
  return scores;
}

cv::Mat1w roomsFromBorderImage(const cv::Mat1b& image) {
  cv::Mat1i components;
  const int count = cv::connectedComponents(image > 250, components, 8, CV_32S);
  if (count - 1 > 65535) throw common::InputError("ground truth", "has more than 65535 rooms");
  cv::Mat1w rooms;
  components.convertTo(rooms, CV_16U);
  return rooms;
}

}  // namespace hidden_rooms::segmentation
