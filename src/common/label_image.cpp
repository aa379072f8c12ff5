#include "hidden_rooms/common/label_image.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/image_io.h"

namespace hidden_rooms::common {

void saveLabelImage(const cv::Mat1w& labels, const std::string& path) {
  double max_label = 0.0;
  if (!labels.empty()) cv::minMaxLoc(labels, nullptr, &max_label);
  cv::Mat image;
  if (max_label <= 255.0) labels.convertTo(image, CV_8U);
  else image = labels;
  writeImage(path, image);
}

cv::Vec3b roomColour(int label) {
  cv::Mat3b hsv(1, 1, cv::Vec3b(static_cast<uchar>(std::fmod(label * 137.508, 360.0) / 2), 170, 230)), bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  return bgr(0, 0);
}

}  // namespace hidden_rooms::common
