#include "hidden_rooms/common/occupancy_grid.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::common {

namespace {

// map_saver's thresholds (nav_msgs cell values).
constexpr int kSaveFreeMax = 19;       // 0.196 * 100, written as free_thresh 0.196
constexpr int kSaveOccupiedMin = 65;   // written as occupied_thresh 0.65

template <typename T>
T readScalar(const YAML::Node& root, const char* key, const std::string& source) {
  const YAML::Node node = root[key];
  if (!node) throw InputError(source, std::string("missing key '") + key + "'");
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    throw InputError(source, std::string("key '") + key + "' has an invalid value");
  }
}

double readFinite(const YAML::Node& root, const char* key, const std::string& source) {
  const double value = readScalar<double>(root, key, source);
  if (!std::isfinite(value)) throw InputError(source, std::string("key '") + key + "' is not finite");
  return value;
}

MapMetadata readMetadata(const std::string& yaml_path) {
  const YAML::Node root = loadYamlFile(yaml_path, "map yaml");
  if (!root.IsMap()) throw InputError(yaml_path, "map yaml must be a mapping of keys");

  MapMetadata metadata;
  metadata.image = readScalar<std::string>(root, "image", yaml_path);
  if (metadata.image.empty()) throw InputError(yaml_path, "key 'image' is empty");
  metadata.resolution = readFinite(root, "resolution", yaml_path);
  if (metadata.resolution <= 0.0)
    throw InputError(yaml_path, "resolution must be positive, got " + std::to_string(metadata.resolution));

  const YAML::Node origin = root["origin"];
  if (!origin || !origin.IsSequence() || origin.size() != 3)
    throw InputError(yaml_path, "key 'origin' must be a list [x, y, yaw]");
  try {
    metadata.origin = Point2(origin[0].as<double>(), origin[1].as<double>());
    metadata.origin_yaw = origin[2].as<double>();
  } catch (const YAML::Exception&) {
    throw InputError(yaml_path, "key 'origin' must hold three numbers");
  }
  if (!metadata.origin.allFinite() || !std::isfinite(metadata.origin_yaw))
    throw InputError(yaml_path, "key 'origin' is not finite");
  if (std::abs(metadata.origin_yaw) > 1e-9)
    throw InputError(yaml_path, "origin yaw " + std::to_string(metadata.origin_yaw) + " is not supported (only 0)");

  if (root["negate"]) {
    const int negate = readScalar<int>(root, "negate", yaml_path);
    if (negate != 0 && negate != 1) throw InputError(yaml_path, "negate is " + std::to_string(negate) + " (0 or 1)");
    metadata.negate = negate == 1;
  }
  metadata.occupied_thresh = readFinite(root, "occupied_thresh", yaml_path);
  metadata.free_thresh = readFinite(root, "free_thresh", yaml_path);
  if (!(metadata.free_thresh >= 0.0 && metadata.free_thresh < metadata.occupied_thresh &&
        metadata.occupied_thresh <= 1.0))
    throw InputError(yaml_path, "thresholds must satisfy 0 <= free_thresh < occupied_thresh <= 1");
  if (root["mode"]) {
    const std::string mode = readScalar<std::string>(root, "mode", yaml_path);
    if (mode == "trinary") metadata.mode = MapMode::kTrinary;
    else if (mode == "scale") metadata.mode = MapMode::kScale;
    else if (mode == "raw") metadata.mode = MapMode::kRaw;
    else throw InputError(yaml_path, "mode '" + mode + "' is not trinary, scale or raw");
  }
  return metadata;
}

std::filesystem::path imagePathOf(const std::string& yaml_path, const MapMetadata& metadata) {
  const std::filesystem::path image_path(metadata.image);
  return image_path.is_relative() ? std::filesystem::path(yaml_path).parent_path() / image_path : image_path;
}

}  // namespace

Point2 OccupancyGrid::cellCentre(int col, int row) const {
  return origin + resolution * Point2(col + 0.5, height() - row - 0.5);
}

Point2 OccupancyGrid::toImage(const Point2& point) const {
  const Point2 local = (point - origin) / resolution;
  return Point2(local.x(), height() - local.y());
}

bool OccupancyGrid::cellOf(const Point2& point, int* col, int* row) const {
  const Point2 image = toImage(point);
  // The map's closed extent (NaN fails every comparison): a point on the far edges belongs to the edge cells.
  if (!(image.x() >= 0.0 && image.x() <= width() && image.y() >= 0.0 && image.y() <= height())) return false;
  *col = std::min(static_cast<int>(image.x()), width() - 1);
  *row = std::min(static_cast<int>(image.y()), height() - 1);
  return true;
}

cv::Mat1b OccupancyGrid::toGreyImage() const {
  cv::Mat1b grey(cells.size());
  for (int row = 0; row < cells.rows; ++row)
    for (int col = 0; col < cells.cols; ++col) {
      const int value = cells(row, col);
      if (value < 0 || value > 100) grey(row, col) = 205;
      else if (value == kFree) grey(row, col) = 254;
      else grey(row, col) = static_cast<uchar>(std::lround(254.0 * (100 - value) / 100.0));
    }
  return grey;
}

OccupancyGrid gridFromImage(const cv::Mat& image, const MapMetadata& metadata) {
  // map_server averages the colour channels (ignoring alpha) and treats translucent pixels as unknown.
  cv::Mat image8;
  if (image.depth() == CV_16U) image.convertTo(image8, CV_8U, 1.0 / 257.0);
  else image.convertTo(image8, CV_8U);
  std::vector<cv::Mat1b> channels;
  cv::split(image8, channels);
  cv::Mat1b alpha;
  if (channels.size() == 4 || channels.size() == 2) {
    alpha = channels.back();
    channels.pop_back();
  }
  cv::Mat1f sum = cv::Mat1f::zeros(image8.size());
  for (const cv::Mat1b& channel : channels) cv::add(sum, channel, sum, cv::noArray(), CV_32F);
  cv::Mat1b grey8;
  sum.convertTo(grey8, CV_8U, 1.0 / static_cast<double>(channels.size()));

  OccupancyGrid grid;
  grid.resolution = metadata.resolution;
  grid.origin = metadata.origin;
  grid.cells.create(grey8.size());
  for (int row = 0; row < grey8.rows; ++row)
    for (int col = 0; col < grey8.cols; ++col) {
      double colour = grey8(row, col);
      if (metadata.negate) colour = 255.0 - colour;
      int8_t value;
      if (metadata.mode == MapMode::kRaw) {
        value = static_cast<int8_t>(static_cast<int>(colour));
      } else {
        const double occupancy = (255.0 - colour) / 255.0;
        const bool transparent = !alpha.empty() && alpha(row, col) < 255;
        if (occupancy > metadata.occupied_thresh) value = OccupancyGrid::kOccupied;
        else if (occupancy < metadata.free_thresh) value = OccupancyGrid::kFree;
        else if (metadata.mode == MapMode::kTrinary || transparent) value = OccupancyGrid::kUnknown;
        else
          value = static_cast<int8_t>(1 + 98 * (occupancy - metadata.free_thresh) /
                                              (metadata.occupied_thresh - metadata.free_thresh));
      }
      grid.cells(row, col) = value;
    }
  return grid;
}

std::string mapImagePath(const std::string& yaml_path) {
  return imagePathOf(yaml_path, readMetadata(yaml_path)).string();
}

OccupancyGrid loadMap(const std::string& yaml_path) {
  const MapMetadata metadata = readMetadata(yaml_path);
  const std::filesystem::path image_path = imagePathOf(yaml_path, metadata);
  if (!isFile(image_path.string()))
    throw InputError(yaml_path, "map image '" + image_path.string() + "' does not exist");
  cv::Mat image;
  try {
    image = readImage(image_path.string());
  } catch (const InputError& error) {
    throw InputError(yaml_path, "map image '" + image_path.string() + "' cannot be read as an image: " + error.problem());
  }
  return gridFromImage(image, metadata);
}

OccupancyGrid trinary(const OccupancyGrid& grid) {
  OccupancyGrid result = grid;
  result.cells = cv::Mat_<int8_t>(grid.cells.size(), OccupancyGrid::kUnknown);
  result.cells.setTo(OccupancyGrid::kFree, (grid.cells >= 0) & (grid.cells <= kSaveFreeMax));
  result.cells.setTo(OccupancyGrid::kOccupied, grid.cells >= kSaveOccupiedMin);
  return result;
}

std::string saveMap(const OccupancyGrid& grid, const std::string& prefix, const std::string& image_extension) {
  if (grid.empty()) throw InputError(prefix, "cannot save an empty map");
  const cv::Mat1b image = trinary(grid).toGreyImage();
  const std::filesystem::path yaml_path = prefix + ".yaml";
  const std::filesystem::path image_path = prefix + image_extension;
  writeImage(image_path.string(), image);

  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "image" << YAML::Value << image_path.filename().string();
  out << YAML::Key << "resolution" << YAML::Value << grid.resolution;
  out << YAML::Key << "origin" << YAML::Value << YAML::Flow << YAML::BeginSeq << grid.origin.x() << grid.origin.y()
      << 0.0 << YAML::EndSeq;
  out << YAML::Key << "negate" << YAML::Value << 0;
  out << YAML::Key << "occupied_thresh" << YAML::Value << 0.65;
  out << YAML::Key << "free_thresh" << YAML::Value << 0.196;
  out << YAML::EndMap;
  writeTextAtomically(yaml_path.string(), std::string(out.c_str()) + "\n", "map yaml");
  return yaml_path.string();
}

cv::Mat1b reachableFreeCells(const OccupancyGrid& grid, int col, int row) {
  cv::Mat1b mask = cv::Mat1b::zeros(grid.height() + 2, grid.width() + 2);
  if (col < 0 || row < 0 || col >= grid.width() || row >= grid.height() || grid.cells(row, col) != OccupancyGrid::kFree)
    return cv::Mat1b::zeros(grid.height(), grid.width());
  cv::Mat1b passable = (grid.cells == OccupancyGrid::kFree);
  cv::floodFill(passable, mask, cv::Point(col, row), 128, nullptr, 0, 0, 4 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
  return mask(cv::Rect(1, 1, grid.width(), grid.height())).clone();
}

}  // namespace hidden_rooms::common
