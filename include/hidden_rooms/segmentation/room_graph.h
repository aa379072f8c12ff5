#pragma once

// The segmentation of an occupancy grid into a floor of rooms (floor.h), with its closed doors as borders and the
// predicted rooms behind them as rooms of their own.

#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/segmentation/floor.h"
#include "hidden_rooms/segmentation/room_segmenter.h"

namespace hidden_rooms::segmentation {

struct FloorSegmentationOptions {
  std::string method = "default";
  std::map<std::string, double> parameters;  // overrides of the method's defaults
  // Give every room a type and its kind with the shipped room type model (room_types.h); false: every room is of
  // kind room, without a type (for training that model).
  bool classify_rooms = true;
};

// Segments the free cells of `map` (cells <= 19 after map_saver's rule) with the closed doors of `doors` drawn as
// borders. `predicted_rooms` (the map's size or empty): label k > 0 on the cells of a predicted room (a
// prediction's rooms.png); each becomes a predicted room, linked by its door. Throws InputError for an empty map or
// one without free cells, a door outside the map, a label image of another size, or an unknown method or
// parameter.
SegmentedFloor segmentFloor(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                            const cv::Mat1w& predicted_rooms, const FloorSegmentationOptions& options);

}  // namespace hidden_rooms::segmentation
