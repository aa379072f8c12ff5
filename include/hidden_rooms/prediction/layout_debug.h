#pragma once

// The layout analysis's debug images (analyzeLayout's debug_dir, layout.h).

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/prediction/layout.h"

namespace hidden_rooms::prediction {

// Writes the images of `layout`, analysed from `map` and its `closed_doors`, into `dir` (created if needed):
// edges.png (`edges`, the Canny edges of the thresholded `grey` = map.toGreyImage()), segments.png,
// angular_clusters.png, walls.png, extended_lines.png, cells.png, rooms.png and start_cells.png. Throws InputError
// when `dir` cannot be created or an image cannot be written.
void writeLayoutDebugImages(const std::string& dir, const common::OccupancyGrid& map,
                            const std::vector<common::MapDoor>& closed_doors, const cv::Mat1b& grey,
                            const cv::Mat1b& edges, const Layout& layout);

}  // namespace hidden_rooms::prediction
