// slice_octomap F.bt|F.ot --z-min --z-max [--resolution] --out MAP.yaml: a height band of a 3D OctoMap projected
// into a 2D map, so prediction runs on 3D maps.
#include <iostream>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/map3d/octomap_io.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

int run(int argc, char** argv) {
  po::options_description options("Options");
  std::string octomap_path, out_path;
  map3d::SliceOptions slice;
  options.add_options()
      ("octomap", po::value(&octomap_path)->required(), "OctoMap file (.bt or .ot)")
      ("out", po::value(&out_path)->required(), "map to write (map_server yaml; the pgm goes beside it)")
      ("z-min", po::value(&slice.z_min)->default_value(0.1), "bottom of the band, metres")
      ("z-max", po::value(&slice.z_max)->default_value(2.0), "top of the band, metres")
      ("resolution", po::value(&slice.resolution)->default_value(0.0), "cell size, metres (0 = the tree's)");
  po::positional_options_description positional;
  positional.add("octomap", 1);
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: slice_octomap F.bt|F.ot --out MAP.yaml [--z-min 0.1] [--z-max 2.0] [--resolution R]\n"
          "A cell is occupied when any voxel of the band above it is occupied, free when some voxel of\n"
          "the band is observed free and none is occupied, unknown otherwise.",
          options, positional, &values))
    return common::kExitOk;
  std::string prefix = out_path;
  if (prefix.size() > 5 && prefix.substr(prefix.size() - 5) == ".yaml") prefix.resize(prefix.size() - 5);
  const common::OccupancyGrid map = map3d::sliceOctomap(octomap_path, slice);
  const std::string written = common::saveMap(map, prefix);
  std::cout << "slice_octomap: z in [" << slice.z_min << ", " << slice.z_max << "] m -> " << map.width() << "x"
            << map.height() << " cells at " << map.resolution << " m -> " << written << std::endl;
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("slice_octomap", [&] { return run(argc, argv); });
}
