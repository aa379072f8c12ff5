#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace hidden_rooms::evaluation {

// Scores of a prediction against the truth, docs/method.md#evaluation. Label images hold k on the cells of the room
// behind the k-th door (1-based) and 0 elsewhere (8- or 16-bit).
struct RoomScores {
  std::vector<double> iou;  // per door k = 1..door_count: |P_k ∩ T_k| / |P_k ∪ T_k|; 0 when both are empty
  double mean_iou = 0.0;    // mean over the doors (a door with no prediction scores 0)
  double iou_total = 0.0;   // |∪P ∩ ∪T| / |∪P ∪ ∪T| over all rooms together
};

// Throws InputError when the images differ in size or are not single-channel integer images.
RoomScores scoreRooms(const cv::Mat& predicted_labels, const cv::Mat& true_labels, int door_count);

}  // namespace hidden_rooms::evaluation
