#include "hidden_rooms/evaluation/evaluation.h"

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::evaluation {

namespace {

cv::Mat1i asLabels(const cv::Mat& image, const char* what) {
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U && image.depth() != CV_32S))
    throw common::InputError(what, "label image must be single-channel 8-, 16- or 32-bit integers");
  cv::Mat1i labels;
  image.convertTo(labels, CV_32S);
  return labels;
}

}  // namespace

RoomScores scoreRooms(const cv::Mat& predicted_labels, const cv::Mat& true_labels, int door_count) {
  if (predicted_labels.size() != true_labels.size())
    throw common::InputError("labels", "predicted and true label images differ in size");
  const cv::Mat1i predicted = asLabels(predicted_labels, "predicted labels");
  const cv::Mat1i truth = asLabels(true_labels, "true labels");
  std::vector<long long> intersection(door_count + 1, 0), predicted_count(door_count + 1, 0),
      true_count(door_count + 1, 0);
  long long all_intersection = 0, all_union = 0;
  for (int row = 0; row < predicted.rows; ++row)
    for (int col = 0; col < predicted.cols; ++col) {
      const int p = predicted(row, col), t = truth(row, col);
      if (p >= 1 && p <= door_count) ++predicted_count[p];
      if (t >= 1 && t <= door_count) ++true_count[t];
      if (p == t && p >= 1 && p <= door_count) ++intersection[p];
      const bool in_p = p >= 1 && p <= door_count, in_t = t >= 1 && t <= door_count;
      all_intersection += in_p && in_t;
      all_union += in_p || in_t;
    }
  RoomScores scores;
  for (int k = 1; k <= door_count; ++k) {
    const long long union_count = predicted_count[k] + true_count[k] - intersection[k];
    scores.iou.push_back(union_count > 0 ? static_cast<double>(intersection[k]) / union_count : 0.0);
    scores.mean_iou += scores.iou.back() / door_count;
  }
  scores.iou_total = all_union > 0 ? static_cast<double>(all_intersection) / all_union : 0.0;
  return scores;
}

}  // namespace hidden_rooms::evaluation
