// export_octomap MAP.yaml [--rooms rooms.yaml] --height 2.5 --out F.bt|F.ot: a 2D map (e.g. a completed map of
// predict_rooms_offline) extruded into an OctoMap.
#include <iostream>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/map3d/octomap_io.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

int run(int argc, char** argv) {
  po::options_description options("Options");
  std::string map_path, rooms_path, out_path;
  map3d::ExtrusionOptions extrusion;
  options.add_options()
      ("map", po::value(&map_path)->required(), "map_server yaml")
      ("out", po::value(&out_path)->required(), "OctoMap to write: .ot (ColorOcTree, rooms coloured) or .bt")
      ("rooms", po::value(&rooms_path), "rooms.yaml of a prediction: its rooms are coloured in the .ot")
      ("height", po::value(&extrusion.height)->default_value(2.5), "height of walls and free space, metres")
      ("resolution", po::value(&extrusion.resolution)->default_value(0.0), "voxel edge, metres (0 = the map's)");
  po::positional_options_description positional;
  positional.add("map", 1);
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: export_octomap MAP.yaml --out F.ot|F.bt [--rooms rooms.yaml] [--height 2.5]\n"
          "Extrudes the map into 3D: occupied cells become walls from the floor (z = 0) to --height,\n"
          "free cells free space, unknown cells stay unknown. A .ot file (ColorOcTree) colours the\n"
          "predicted rooms of --rooms as the overlays do and the rest grey; a .bt file is occupancy only.",
          options, positional, &values))
    return common::kExitOk;
  const common::OccupancyGrid map = common::loadMap(map_path);
  const cv::Mat1w labels = rooms_path.empty() ? cv::Mat1w() : common::roomLabelsFromYaml(rooms_path, map);
  map3d::exportOctomap(map, labels, extrusion, out_path);
  std::cout << "export_octomap: " << map.width() << "x" << map.height() << " map, " << extrusion.height
            << " m high -> " << out_path << std::endl;
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("export_octomap", [&] { return run(argc, argv); });
}
