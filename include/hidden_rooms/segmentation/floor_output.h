#pragma once

// The files a segmented floor is saved as (segment_rooms):
//   DIR/rooms.png    label image of the map's size: 0 outside every room, k on the cells of room k
//   DIR/rooms.yaml   the rooms (label, kind, type, predicted, area, width, centroid, outline) and the passages between
//                    them
//   DIR/rooms.xml    the floor in the thesis's environment schema (spaces with outlines, labels and portals)
//   DIR/preview.png  picture: rooms tinted, passages as lines between room centroids (open green, closed red,
//                    predicted orange)

#include <string>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/segmentation/floor.h"
#include "hidden_rooms/world/environment.h"

namespace hidden_rooms::segmentation {

// The floor as an environment of the thesis's schema, frame = the grid's (its lower-left corner at 0, 0), one pixel
// per cell: a space per room (type C for corridors, else R; label its type in capitals, e.g. CORRIDOR, OFFICE,
// PREDICTED CLASSROOM; ROOM when it has none) whose walls are its outline's
// edges, and a PORTAL per passage on the outline of its first room (closed and predicted doors with status
// CLOSED). Reads back with world::loadEnvironment.
world::Environment floorToEnvironment(const SegmentedFloor& floor, const common::OccupancyGrid& map,
                                      const std::string& name);

std::string floorToYaml(const SegmentedFloor& floor);
cv::Mat3b floorPreview(const SegmentedFloor& floor, const common::OccupancyGrid& map);

// Writes the files above into `out` (staged; the caller commits). Throws InputError naming a file that cannot be
// written.
void writeFloorOutputs(const SegmentedFloor& floor, const common::OccupancyGrid& map, const std::string& name,
                       common::OutputFolder* out);

}  // namespace hidden_rooms::segmentation
