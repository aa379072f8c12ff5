#include "hidden_rooms/common/label_image.h"

#include <yaml-cpp/yaml.h>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"

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

cv::Mat1w roomLabelsFromYaml(const std::string& rooms_yaml, const OccupancyGrid& map) {
  const YAML::Node root = loadYamlFile(rooms_yaml, "rooms file");
  const YAML::Node rooms = root["rooms"];
  if (!rooms || !rooms.IsSequence()) throw InputError(rooms_yaml, "has no 'rooms' list");
  cv::Mat1w labels = cv::Mat1w::zeros(map.height(), map.width());
  for (size_t k = 0; k < rooms.size(); ++k) {
    const YAML::Node room = rooms[k];
    const std::string where = "rooms[" + std::to_string(k) + "]";
    try {
      if (room["placed"] && !room["placed"].as<bool>()) continue;
      const int label = room["label"] ? room["label"].as<int>() : static_cast<int>(k) + 1;
      if (label <= 0 || label > 65535) throw InputError(rooms_yaml, where + ".label is out of range");
      std::vector<cv::Point> polygon;
      for (const YAML::Node& vertex : room["polygon"]) {
        const Point2 point(vertex[0].as<double>(), vertex[1].as<double>());
        if (!point.allFinite()) throw InputError(rooms_yaml, where + " has a non-finite vertex");
        const Point2 image = map.toImage(point);
        polygon.emplace_back(static_cast<int>(std::lround(image.x() - 0.5)),
                             static_cast<int>(std::lround(image.y() - 0.5)));
      }
      if (polygon.size() < 3) throw InputError(rooms_yaml, where + " needs a polygon of at least 3 vertices");
      cv::fillPoly(labels, std::vector<std::vector<cv::Point>>{polygon}, cv::Scalar(label));
    } catch (const YAML::Exception& error) {
      throw InputError(rooms_yaml, where + " is malformed: " + error.msg);
    }
  }
  return labels;
}

}  // namespace hidden_rooms::common
