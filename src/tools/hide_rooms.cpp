// hide_rooms MAP.yaml --out DIR [--max-rooms N] [--max-door-width M] [--min-area A] [--method NAME]: closed-door
// cases from a map of one's own. The map is segmented into rooms; the rooms a single doorway joins to the rest of
// the floor are hidden behind closed doors, so that predict_rooms_offline --gt-rooms scores a prediction on the map
// against what the map showed there.
#include <iomanip>
#include <iostream>
#include <sstream>

#include "hidden_rooms/common/command_line.h"
#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/evaluation/closable_rooms.h"
#include "hidden_rooms/segmentation/room_graph.h"

namespace po = boost::program_options;
using namespace hidden_rooms;

namespace {

int run(int argc, char** argv) {
  std::string map_path, out_dir;
  evaluation::ClosableRoomOptions hide;
  segmentation::FloorSegmentationOptions floor_options;
  po::options_description options("Options");
  options.add_options()
      ("map", po::value(&map_path)->required(), "input map (map_server yaml): a complete map of the floor")
      ("out", po::value(&out_dir)->required(), "output folder (created)")
      ("max-rooms", po::value(&hide.max_rooms)->default_value(hide.max_rooms),
       "hide the largest this many closable rooms (0: all)")
      ("max-door-width", po::value(&hide.max_door_width)->default_value(hide.max_door_width),
       "metres: a doorway wider than this is an opening, not a door")
      ("min-area", po::value(&hide.min_area)->default_value(hide.min_area), "square metres: smaller rooms stay")
      ("method", po::value(&floor_options.method)->default_value(floor_options.method), "segmentation method");
  po::positional_options_description positional;
  positional.add("map", 1);
  po::variables_map values;
  if (!common::parseCommandLine(
          argc, argv,
          "Usage: hide_rooms MAP.yaml --out DIR [--max-rooms N] [--max-door-width M] [--min-area A] [--method NAME]\n"
          "Segments the map into rooms and hides the rooms (not corridors) that one doorway alone joins to the\n"
          "rest of the floor, as closed doors would. Writes the closed-door case: DIR/map.yaml + DIR/map.pgm,\n"
          "DIR/doors.yaml (a closed door across each doorway) and DIR/gt_rooms.png (label k: the room behind\n"
          "door k, as the map showed it), for predict_rooms_offline --gt-rooms.",
          options, positional, &values))
    return common::kExitOk;
  if (hide.max_rooms < 0) throw common::InputError("--max-rooms", "must be 0 or more");
  if (!(hide.max_door_width > 0.0)) throw common::InputError("--max-door-width", "must be positive");
  if (!(hide.min_area >= 0.0)) throw common::InputError("--min-area", "must be 0 or more");

  const common::OccupancyGrid map = common::loadMap(map_path);
  floor_options.classify_rooms = true;  // corridors are not hidden
  const segmentation::SegmentedFloor floor = segmentation::segmentFloor(map, {}, {}, floor_options);
  const std::vector<int> labels = evaluation::closableRooms(floor, hide);
  if (labels.empty()) {
    std::ostringstream rule;
    rule << "has no closable room (a room of at least " << hide.min_area << " m2 with one doorway of at most "
         << hide.max_door_width << " m)";
    throw common::InputError(map_path, rule.str());
  }
  const world::HiddenRoomsCase hidden = evaluation::hideRooms(map, floor, labels, hide);

  common::OutputFolder out(out_dir, {map_path, common::mapImagePath(map_path)});
  common::saveMap(hidden.map, out.mapPrefix("map"));
  common::saveDoors(hidden.closed_doors, out.file("doors.yaml"));
  common::saveLabelImage(hidden.true_rooms, out.file("gt_rooms.png"));
  out.commit();

  std::cout << std::fixed << std::setprecision(2) << labels.size() << " of " << floor.rooms.size()
            << " rooms hidden -> " << out_dir << "\n";
  for (size_t k = 0; k < labels.size(); ++k) {
    const common::MapDoor& door = hidden.closed_doors.doors[k];
    std::cout << "  door " << door.id << " at (" << door.position.x() << ", " << door.position.y() << "), "
              << door.width << " m: room of " << floor.rooms[labels[k] - 1].area << " m2\n";
  }
  return common::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return common::runTool("hide_rooms", [&] { return run(argc, argv); });
}
