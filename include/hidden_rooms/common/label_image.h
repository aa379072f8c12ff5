#pragma once

// Label images: per cell 0 (no label) or a label k >= 1 (a room, a space).

#include <string>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/occupancy_grid.h"

namespace hidden_rooms::common {

// Writes a label image as PNG: 8-bit when every label fits, else 16-bit. Throws InputError on failure.
void saveLabelImage(const cv::Mat1w& labels, const std::string& path);

// The colour of the room with label k (1-based) in every picture and rviz overlay, BGR: hues spread by the
// golden angle, so that neighbouring labels differ.
cv::Vec3b roomColour(int label);

// The label image of a prediction's rooms.yaml (predict_rooms_offline, predict_rooms_client) in `map`'s grid:
// each placed room's polygon filled with its label. Throws InputError for a missing or malformed file.
cv::Mat1w roomLabelsFromYaml(const std::string& rooms_yaml, const OccupancyGrid& map);

}  // namespace hidden_rooms::common
