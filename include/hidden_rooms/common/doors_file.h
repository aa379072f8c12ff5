#pragma once

#include <optional>
#include <string>
#include <vector>

#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"

namespace hidden_rooms::common {

// Door orientation as in doors.yaml: kAlongX ("O") when the door line (the wall it sits in) runs along x,
// kAlongY ("V") when it runs along y.
enum class DoorOrientation { kAlongX, kAlongY };
const char* toString(DoorOrientation orientation);  // "O" or "V"

// One door of a doors.yaml file, in the map frame.
struct MapDoor {
  int id = 0;
  Point2 position = Point2::Zero();  // metres, in the file's frame
  double width = 0.9;                // metres
  DoorOrientation orientation = DoorOrientation::kAlongX;
  // Optional: where a simulated world lies in this map at the door (the rigid transform map <- world that carried
  // the door over, docs/method.md#closed-doors-in-the-map), written for explored maps of known environments.
  std::optional<Pose2> map_from_world;
};

// The package's closed-doors file (doors.yaml):
//   frame: map
//   doors:
//     - {id: 1, position: [x, y], width: 0.9, orientation: O}   # O: door line along x, V: along y
// and optionally `map_from_world: [x, y, yaw]` per door. Unknown keys are ignored.
struct DoorsFile {
  std::string frame = "map";
  std::vector<MapDoor> doors;
};

// Throws InputError naming the file and the problem (malformed YAML, missing keys, non-finite numbers,
// non-positive width, orientation other than O/V, duplicate ids).
DoorsFile loadDoors(const std::string& path);
DoorsFile parseDoors(const std::string& yaml_text, const std::string& source_name);
void saveDoors(const DoorsFile& doors, const std::string& path);

// For doors from outside (a service request, a doors file beside a map): throws InputError("door ID", ...) naming
// the first door whose position lies outside the map's extent (usually a door given in another frame), and
// InputError("doors", ...) when two doors share an id.
void checkDoorsInsideMap(const OccupancyGrid& map, const DoorsFile& doors);

}  // namespace hidden_rooms::common
