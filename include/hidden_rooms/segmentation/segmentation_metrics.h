#pragma once

// Scores of a room segmentation against ground truth: the survey's per-room recall and precision (Bormann et al.,
// ICRA 2016, as ipa_room_segmentation computes them) and Matthews' correlation coefficient over pairs of cells.

#include <map>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>


namespace hidden_rooms::segmentation {

// Regions of at most this many cells are left out of the scores, on both sides (the survey's rule).
constexpr int kSurveyMinRegionCells = 101;

struct SegmentationScores {
  int truth_rooms = 0;  // ground-truth rooms scored
  int found_rooms = 0;  // segments scored
  // Each ground-truth room is matched with the segment that overlaps it most (recall: overlap / room area), each
  // segment with the room that overlaps it most (precision: overlap / segment area). Micro: mean over rooms
  // (segments); macro: the overlaps pooled over all cells.
  double recall_micro = 0.0;
  double precision_micro = 0.0;
  double recall_macro = 0.0;
  double precision_macro = 0.0;
  // Matthews' correlation coefficient over the pairs of ground-truth room cells: a pair is positive when both
  // cells lie in one room; predicted positive when both lie in one segment (cells outside every segment are
  // alone). 1: the same partition; about 0: unrelated.
  double mcc = 0.0;
};

// `found` and `truth` are label images of one size (0 = no room). Throws InputError when the sizes differ or the
// ground truth has no room of at least `min_region_cells` cells.
SegmentationScores scoreSegmentation(const cv::Mat1w& found, const cv::Mat1w& truth,
                                     int min_region_cells = kSurveyMinRegionCells);

// How well the rooms' labels (kinds, types) match the ground truth's: each found room (of at least
// `min_region_cells` cells) takes the label of the ground-truth room that overlaps it most; rooms overlapping none,
// or a ground-truth room with an empty label, are not scored.
struct LabelScores {
  int rooms = 0;    // found rooms scored
  int correct = 0;  // with the ground truth's label
  std::map<std::string, std::pair<int, int>> per_label;  // ground-truth label -> (correct, rooms)
  double accuracy() const { return rooms > 0 ? static_cast<double>(correct) / rooms : 0.0; }
  // The share of the rooms labelled `label` in the ground truth that were found with it (1 without such rooms).
  double recall(const std::string& label) const;
};
// `found_labels[k - 1]`: the label of found room k; `truth_labels[k - 1]`: of ground-truth room k. Throws InputError
// when the images differ in size or a room has no label.
LabelScores scoreRoomLabels(const cv::Mat1w& found, const std::vector<std::string>& found_labels,
                            const cv::Mat1w& truth, const std::vector<std::string>& truth_labels,
                            int min_region_cells = kSurveyMinRegionCells);

// The ground truth of the survey's test maps: an 8-bit image with the room borders drawn in black; each
// 8-connected region of pixels above 250 is a room (labels 1..N), the rest 0.
cv::Mat1w roomsFromBorderImage(const cv::Mat1b& image);

}  // namespace hidden_rooms::segmentation
