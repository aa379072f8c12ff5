// segment_rooms MAP.yaml [--doors DOORS.yaml] [--rooms rooms.yaml] --out DIR [--method NAME] [--params FILE.yaml]:
// the floor of a map as rooms (closed doors as borders, predicted rooms as rooms of their own) and the topological
// map between them.
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/segmentation/floor_output.h"
#include "hidden_rooms/segmentation/room_graph.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

int run(int argc, char** argv) {
  std::string map_path, doors_path, rooms_path, out_dir, params_path;
  segmentation::FloorSegmentationOptions floor_options;
  po::options_description options("Options");
  options.add_options()
      ("map", po::value(&map_path)->required(), "input map (map_server yaml)")
      ("doors", po::value(&doors_path), "closed doors (doors.yaml, map frame): borders between rooms")
      ("rooms", po::value(&rooms_path), "predicted rooms (a prediction's rooms.yaml): rooms of their own")
      ("out", po::value(&out_dir)->required(), "output folder (created)")
      ("method", po::value(&floor_options.method)->default_value(floor_options.method), "segmentation method")
      ("params", po::value(&params_path), "parameter overrides: flat YAML of name: number")
;
  po::positional_options_description positional;
  positional.add("map", 1);
  std::string methods;
  for (const std::string& name : segmentation::roomSegmenterNames()) methods += (methods.empty() ? "" : ", ") + name;
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: segment_rooms MAP.yaml [--doors DOORS.yaml] [--rooms rooms.yaml] --out DIR [--method NAME]\n"
          "                     [--params FILE.yaml]\n"
          "Methods: " + methods + "\n"
          "Writes DIR/rooms.png (label k on the cells of room k), DIR/rooms.yaml (rooms and the passages\n"
          "between them), DIR/rooms.xml (the thesis's environment schema) and DIR/preview.png.",
          options, positional, &values))
    return common::kExitOk;

  // Read and check everything before writing anything.
  const common::OccupancyGrid map = common::loadMap(map_path);
  const common::DoorsFile doors = doors_path.empty() ? common::DoorsFile() : common::loadDoors(doors_path);
  const cv::Mat1w predicted = rooms_path.empty() ? cv::Mat1w() : common::roomLabelsFromYaml(rooms_path, map);
  if (!params_path.empty()) floor_options.parameters = common::loadParameterFile(params_path);
  common::OutputFolder out(out_dir, {map_path, common::mapImagePath(map_path), doors_path, rooms_path, params_path});

  const auto start = std::chrono::steady_clock::now();
  const segmentation::SegmentedFloor floor = segmentation::segmentFloor(map, doors, predicted, floor_options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  segmentation::writeFloorOutputs(floor, map, std::filesystem::path(map_path).stem().string(), &out);
  out.commit();

  int corridors = 0, predicted_rooms = 0;
  for (const segmentation::Room& room : floor.rooms) {
    corridors += room.kind == segmentation::RoomKind::kCorridor;
    predicted_rooms += room.predicted;
  }
  int open = 0;
  for (const segmentation::Passage& passage : floor.passages) open += passage.kind == segmentation::PassageKind::kOpen;
  std::cout << floor_options.method << ": " << floor.rooms.size() << " rooms (" << corridors << " corridors, "
            << predicted_rooms << " predicted), " << floor.passages.size() << " passages (" << open
            << " open, " << floor.passages.size() - open << " doors) in " << std::fixed << std::setprecision(3)
            << seconds << " s -> " << out_dir
            << std::endl;
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("segment_rooms", [&] { return run(argc, argv); });
}
