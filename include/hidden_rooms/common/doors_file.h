#pragma once

#include <string>
#include <vector>

#include "hidden_rooms/common/geometry.h"

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
};

// The package's closed-doors file (doors.yaml):
//   frame: map
//   doors:
//     - {id: 1, position: [x, y], width: 0.9, orientation: O}   # O: door line along x, V: along y
// Unknown keys are ignored.
struct DoorsFile {
  std::string frame = "map";
  std::vector<MapDoor> doors;
};

// Throws InputError naming the file and the problem (malformed YAML, missing keys, non-finite numbers,
// non-positive width, orientation other than O/V, duplicate ids).
DoorsFile loadDoors(const std::string& path);
DoorsFile parseDoors(const std::string& yaml_text, const std::string& source_name);
void saveDoors(const DoorsFile& doors, const std::string& path);

}  // namespace hidden_rooms::common
