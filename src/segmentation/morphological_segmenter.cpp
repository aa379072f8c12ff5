#include <vector>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/segmentation/segmenters.h"

namespace hidden_rooms::segmentation {

std::map<std::string, double> MorphologicalSegmenter::defaultParameters() const {
  // The survey's defaults (ipa_room_segmentation: room_area_factor_{lower,upper}_limit_morphological, and its
  // fixed number of erosions).
  return {
      {"morphological_min_core_area", 0.8},
      {"morphological_max_core_area", 47.0},
      {"morphological_erosions", 73},
  };
}

cv::Mat1i MorphologicalSegmenter::segment(const SegmentationInput& input,
                                          const std::map<std::string, double>& parameters) const {
  const double cell_area = input.resolution * input.resolution;
  const double min_area = parameters.at("morphological_min_core_area") / cell_area;
  const double max_area = parameters.at("morphological_max_core_area") / cell_area;
  const int erosions = static_cast<int>(parameters.at("morphological_erosions"));
  cv::Mat1b remaining = input.free.clone();
  std::vector<std::vector<cv::Point>> cores;
  for (int erosion = 0; erosion < erosions && cv::countNonZero(remaining) > 0; ++erosion) {
    cv::erode(remaining, remaining, cv::Mat(), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
    std::vector<std::vector<cv::Point>> contours;
    std::vector<cv::Vec4i> hierarchy;
    cv::findContours(remaining.clone(), contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_SIMPLE);
    for (size_t i = 0; i < contours.size(); ++i) {
      if (hierarchy[i][3] != -1) continue;  // a hole's contour
      double area = cv::contourArea(contours[i]);
      for (int hole = hierarchy[i][2]; hole >= 0; hole = hierarchy[hole][0]) area -= cv::contourArea(contours[hole]);
      if (area <= min_area || area >= max_area) continue;
      // The region is a room's core: it leaves the erosion.
      cores.push_back(contours[i]);
      cv::drawContours(remaining, contours, static_cast<int>(i), cv::Scalar(0), cv::FILLED);
    }
  }
  // Cores filled in the order found (a later core's outline may cover an earlier one inside it, as in the survey's
  // implementation), walls and unknown cells cleared, then grown into the rest of the free space.
  cv::Mat1i labels(input.free.size(), 0);
  for (size_t i = 0; i < cores.size(); ++i)
    cv::drawContours(labels, cores, static_cast<int>(i), cv::Scalar(static_cast<int>(i) + 1), cv::FILLED);
  labels.setTo(0, input.free == 0);
  spreadLabels(input.free, &labels);
  return labels;
}

}  // namespace hidden_rooms::segmentation
