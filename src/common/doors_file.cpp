#include "hidden_rooms/common/doors_file.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/input_limits.h"

namespace hidden_rooms::common {

namespace {

std::string where(size_t index) { return "doors[" + std::to_string(index) + "]"; }

double finiteNumber(const YAML::Node& node, const std::string& what, const std::string& source) {
  double value = 0.0;
  try {
    value = node.as<double>();
  } catch (const YAML::Exception&) {
    throw InputError(source, what + " is not a number");
  }
  if (!std::isfinite(value)) throw InputError(source, what + " is not finite");
  return value;
}

MapDoor readDoor(const YAML::Node& node, size_t index, const std::string& source) {
  if (!node.IsMap()) throw InputError(source, where(index) + " is not a mapping");
  MapDoor door;
  if (!node["id"]) throw InputError(source, where(index) + " has no 'id'");
  try {
    door.id = node["id"].as<int>();
  } catch (const YAML::Exception&) {
    throw InputError(source, where(index) + ".id is not an integer");
  }
  const YAML::Node position = node["position"];
  if (!position || !position.IsSequence() || position.size() != 2)
    throw InputError(source, where(index) + " (id " + std::to_string(door.id) + ") needs 'position: [x, y]'");
  door.position = Point2(finiteNumber(position[0], where(index) + ".position[0]", source),
                         finiteNumber(position[1], where(index) + ".position[1]", source));
  if (!node["width"]) throw InputError(source, where(index) + " (id " + std::to_string(door.id) + ") has no 'width'");
  door.width = finiteNumber(node["width"], where(index) + ".width", source);
  if (door.width <= 0.0) throw InputError(source, where(index) + ".width must be positive");
  if (!node["orientation"])
    throw InputError(source, where(index) + " (id " + std::to_string(door.id) + ") has no 'orientation'");
  const std::string orientation = node["orientation"].as<std::string>("");
  if (orientation == "O") door.orientation = DoorOrientation::kAlongX;
  else if (orientation == "V") door.orientation = DoorOrientation::kAlongY;
  else throw InputError(source, where(index) + ".orientation is '" + orientation + "' (O or V)");
  if (const YAML::Node transform = node["map_from_world"]) {
    if (!transform.IsSequence() || transform.size() != 3)
      throw InputError(source, where(index) + ".map_from_world must be [x, y, yaw]");
    door.map_from_world = Pose2{finiteNumber(transform[0], where(index) + ".map_from_world[0]", source),
                                finiteNumber(transform[1], where(index) + ".map_from_world[1]", source),
                                finiteNumber(transform[2], where(index) + ".map_from_world[2]", source)};
  }
  return door;
}

}  // namespace

DoorsFile parseDoors(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& error) {
    throw InputError(source, std::string("malformed YAML: ") + error.what());
  }
  if (!root.IsMap()) throw InputError(source, "doors file must be a mapping with a 'doors' list");
  DoorsFile file;
  if (root["frame"]) file.frame = root["frame"].as<std::string>("");
  if (file.frame.empty()) throw InputError(source, "'frame' is empty");
  const YAML::Node doors = root["doors"];
  if (!doors) throw InputError(source, "missing 'doors' list");
  if (doors.IsNull()) return file;  // "doors:" with nothing: no closed door
  if (!doors.IsSequence()) throw InputError(source, "'doors' must be a list");
  checkLimit(source, "the number of doors", static_cast<double>(doors.size()), kMaxDoors);
  std::set<int> ids;
  for (size_t i = 0; i < doors.size(); ++i) {
    MapDoor door = readDoor(doors[i], i, source);
    if (!ids.insert(door.id).second) throw InputError(source, "door id " + std::to_string(door.id) + " is used twice");
    file.doors.push_back(door);
  }
  return file;
}

DoorsFile loadDoors(const std::string& path) { return parseDoors(readTextFile(path, "doors file"), path); }

void saveDoors(const DoorsFile& doors, const std::string& path) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "frame" << YAML::Value << doors.frame;
  out << YAML::Key << "doors" << YAML::Value << YAML::BeginSeq;
  for (const MapDoor& door : doors.doors) {
    out << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << door.id;
    out << YAML::Key << "position" << YAML::Value << YAML::Flow << YAML::BeginSeq << door.position.x()
        << door.position.y() << YAML::EndSeq;
    out << YAML::Key << "width" << YAML::Value << door.width;
    out << YAML::Key << "orientation" << YAML::Value << toString(door.orientation);
    if (door.map_from_world)
      out << YAML::Key << "map_from_world" << YAML::Value << YAML::Flow << YAML::BeginSeq << door.map_from_world->x
          << door.map_from_world->y << door.map_from_world->yaw << YAML::EndSeq;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  writeTextAtomically(path, std::string(out.c_str()) + "\n", "doors file");
}

const char* toString(DoorOrientation orientation) { return orientation == DoorOrientation::kAlongX ? "O" : "V"; }

void checkDoorsInsideMap(const OccupancyGrid& map, const DoorsFile& doors) {
  std::set<int> ids;
  for (const MapDoor& door : doors.doors) {
    if (!ids.insert(door.id).second)
      throw InputError("doors", "door id " + std::to_string(door.id) + " is used twice");
    int col = 0, row = 0;
    if (!map.cellOf(door.position, &col, &row)) {
      throw InputError(
          "door " + std::to_string(door.id),
          "position (" + formatNumber(door.position.x()) + ", " + formatNumber(door.position.y()) +
              ") is outside the map (x " + formatNumber(map.origin.x()) + " .. " +
              formatNumber(map.origin.x() + map.width() * map.resolution) + ", y " +
              formatNumber(map.origin.y()) + " .. " +
              formatNumber(map.origin.y() + map.height() * map.resolution) + " m)");
    }
  }
}

}  // namespace hidden_rooms::common
