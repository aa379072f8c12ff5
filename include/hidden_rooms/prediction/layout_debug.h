#pragma once

// The layout analysis's debug images (analyzeLayout's debug_dir, layout.h).

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/prediction/layout.h"

namespace hidden_rooms::prediction {

// The images, one per stage in the order the thesis's implementation draws them: the Canny edges, the Hough
// segments, the explored outline and the bounding box, the angular clusters, the walls (spatial clusters), the
// extended lines, the IN/OUT and border cells, the rooms of IN cells (DBSCAN) and the doors' start cells.
const std::vector<std::string>& layoutDebugImageNames();

// Writes layoutDebugImageNames() of `layout`, analysed from `map` and its `closed_doors`, into `dir` (created if
// needed): `edges` are the Canny edges of the thresholded `grey` = map.toGreyImage(), `explored` the explored outline
// (empty when explored_outline is off). Throws InputError when `dir` cannot be created or an image cannot be written.
void writeLayoutDebugImages(const std::string& dir, const common::OccupancyGrid& map,
                            const std::vector<common::MapDoor>& closed_doors, const cv::Mat1b& grey,
                            const cv::Mat1b& edges, const cv::Mat1b& explored, const Layout& layout);

}  // namespace hidden_rooms::prediction
