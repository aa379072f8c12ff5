#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/occupancy_grid.h"

namespace hidden_rooms::map3d {

// 2D maps to and from OctoMap 3D maps (octomap::OcTree .bt, octomap::ColorOcTree .ot). OctoMap's types stay
// inside the implementation; the frame is the map's (z up, the floor at z = 0).

struct ExtrusionOptions {
  double height = 2.5;      // metres: walls (occupied cells) and free space (free cells) span z in [0, height)
  double resolution = 0.0;  // voxel edge, metres; 0 = the map's resolution
};

// The map extruded into 3D and written to `path`: occupied cells become occupied voxel columns, free cells free
// columns, unknown cells stay unknown. `.ot` writes a ColorOcTree in which the voxels of predicted rooms (cells
// with label k > 0 in `room_labels`, map-sized or empty, and the walls next to them) take the room's overlay
// colour and the rest is grey; `.bt` writes a plain OcTree (occupancy only). Throws InputError for another
// extension, bad options, a label image of the wrong size or a file that cannot be written.
void exportOctomap(const common::OccupancyGrid& map, const cv::Mat1w& room_labels, const ExtrusionOptions& options,
                   const std::string& path);

struct SliceOptions {
  double z_min = 0.1;       // metres: the height band projected to 2D
  double z_max = 2.0;
  double resolution = 0.0;  // cell size of the 2D map, metres; 0 = the tree's resolution
};

// A height band of a 3D OctoMap (.bt or .ot) projected to a 2D map: a cell is occupied when any voxel of the
// band above it is occupied, free when some voxel of that band is observed free and none is occupied, unknown
// otherwise. The grid covers the tree's known extent. Throws InputError for a missing, unreadable or empty file or a bad band.
common::OccupancyGrid sliceOctomap(const std::string& path, const SliceOptions& options);

}  // namespace hidden_rooms::map3d
