#pragma once

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/geometry.h"

namespace hidden_rooms::common {

// An occupancy grid with nav_msgs/OccupancyGrid cell values (-1 unknown, 0 free .. 100 occupied), stored in
// image order: row 0 is the top row (largest y), as in the map image file. `origin` is the map-frame position
// (metres) of the lower-left corner of the lower-left cell; the grid is axis-aligned (yaw 0).
struct OccupancyGrid {
  static constexpr int8_t kUnknown = -1;
  static constexpr int8_t kFree = 0;
  static constexpr int8_t kOccupied = 100;

  cv::Mat_<int8_t> cells;
  double resolution = 0.05;     // metres per cell
  Point2 origin = Point2::Zero();

  int width() const { return cells.cols; }
  int height() const { return cells.rows; }
  bool empty() const { return cells.empty(); }

  // Centre of cell (col, row) in the map frame.
  Point2 cellCentre(int col, int row) const;
  // Continuous image coordinates (col, row, cells spanning [c, c+1)) of a map-frame point.
  Point2 toImage(const Point2& point) const;
  // The cell containing a map-frame point (a point on the grid's far edges: the edge cell); false outside the grid.
  bool cellOf(const Point2& point, int* col, int* row) const;

  // Greyscale rendering as map_server images use it: 254 free, 0 occupied, 205 unknown, intermediate
  // occupancy values scaled between 254 and 0.
  cv::Mat1b toGreyImage() const;
};

// How map_server interprets the image (its `mode` key).
enum class MapMode { kTrinary, kScale, kRaw };

// The keys of a map_server map yaml.
struct MapMetadata {
  std::string image;  // as written in the yaml (relative to the yaml's folder unless absolute)
  double resolution = 0.05;
  Point2 origin = Point2::Zero();
  double origin_yaw = 0.0;
  bool negate = false;
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  MapMode mode = MapMode::kTrinary;
};

// Loads a map_server map (yaml + image) with map_server's semantics (trinary, scale and raw modes, negate,
// thresholds, origin). Only yaw 0 is supported. Throws InputError naming the file and the problem.
OccupancyGrid loadMap(const std::string& yaml_path);
// The path of the image a map yaml names (resolved against the yaml's folder). Throws InputError like loadMap.
std::string mapImagePath(const std::string& yaml_path);
// Converts a greyscale image with map_server's rules.
OccupancyGrid gridFromImage(const cv::Mat& image, const MapMetadata& metadata);

// The grid as map_saver saves it and map_server reads it back: cells <= 19 free (0), >= 65 occupied (100), the
// others unknown (-1). SLAM maps (the mapper's, cartographer's) hold occupancy probabilities in between.
OccupancyGrid trinary(const OccupancyGrid& grid);

// Writes `PREFIX.yaml` and `PREFIX.pgm` as map_saver does (trinary: 254 free, 0 occupied, 205 unknown;
// cells <= 19 are free, >= 65 occupied), the image as `PREFIX` + `image_extension` (".png": compressed). Returns
// the yaml path. Throws InputError when it cannot write.
std::string saveMap(const OccupancyGrid& grid, const std::string& prefix, const std::string& image_extension = ".pgm");

// Free cells reachable from (col, row) through free cells (4-connected), as a 0/255 mask of the grid's size; all
// zero when (col, row) is outside the grid or not free.
cv::Mat1b reachableFreeCells(const OccupancyGrid& grid, int col, int row);

}  // namespace hidden_rooms::common
