#include "hidden_rooms/segmentation/floor_output.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <limits>
#include <map>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/label_image.h"

namespace hidden_rooms::segmentation {

namespace {

std::string spaceId(int label) { return "r" + std::to_string(label); }

// The point of `outline`'s edges nearest to `point`.
common::Point2 nearestOnOutline(const common::Polygon& outline, const common::Point2& point) {
  if (outline.size() < 2) return outline.empty() ? point : outline.front();
  common::Point2 best = point;
  double best_distance = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < outline.size(); ++i) {
    const common::Point2& a = outline[i];
    const common::Point2& b = outline[(i + 1) % outline.size()];
    const double t = std::clamp(common::projectionParameter(point, a, b), 0.0, 1.0);
    const common::Point2 candidate = a + t * (b - a);
    const double distance = (candidate - point).norm();
    if (distance < best_distance) {
      best_distance = distance;
      best = candidate;
    }
  }
  return best;
}

void emitPoint(YAML::Emitter* out, const common::Point2& point) {
  *out << YAML::Flow << YAML::BeginSeq << point.x() << point.y() << YAML::EndSeq;
}

}  // namespace

world::Environment floorToEnvironment(const SegmentedFloor& floor, const common::OccupancyGrid& map,
                                      const std::string& name) {
  world::Environment environment;
  environment.building_id = name;
  environment.name = name;
  environment.building_type = "SEGMENTED MAP";
  environment.metres_per_pixel = map.resolution;
  environment.flip_v = map.height();
  // Map frame -> the environment's frame: the grid's lower-left corner at (0, 0).
  const auto local = [&](const common::Point2& point) { return common::Point2(point - map.origin); };
  for (const Room& room : floor.rooms) {
    world::Space space;
    space.id = spaceId(room.label);
    space.type = room.kind == RoomKind::kCorridor ? "C" : "R";
    std::string label = room.type.empty() ? "ROOM" : room.type;
    std::transform(label.begin(), label.end(), label.begin(), [](unsigned char c) { return std::toupper(c); });
    space.label = room.predicted ? "PREDICTED " + label : label;
    for (const common::Point2& vertex : room.outline) space.outline.push_back(local(vertex));
    for (size_t i = 0; i < space.outline.size(); ++i) {
      world::LineSegment wall;
      wall.id = space.id + "_w" + std::to_string(i + 1);
      wall.a = space.outline[i];
      wall.b = space.outline[(i + 1) % space.outline.size()];
      space.segments.push_back(wall);
    }
    environment.spaces.push_back(space);
  }
  std::map<std::string, PassageKind> kind_of_portal;
  for (size_t i = 0; i < floor.passages.size(); ++i) {
    const Passage& passage = floor.passages[i];
    if (passage.room_a == 0) continue;  // a door with no room on either side
    world::LineSegment portal;
    portal.id = "p" + std::to_string(i + 1);
    portal.segment_class = world::SegmentClass::kPortal;
    portal.type = passage.kind == PassageKind::kOpen ? "IMPLICIT" : "EXPLICIT";
    portal.a = portal.b = nearestOnOutline(environment.spaces[passage.room_a - 1].outline, local(passage.centre));
    kind_of_portal[portal.id] = passage.kind;
    world::PortalLink link;
    link.segment_id = portal.id;
    for (const int label : {passage.room_a, passage.room_b})
      if (label != 0) link.target_ids.push_back(spaceId(label));
    for (const int label : {passage.room_a, passage.room_b}) {
      if (label == 0) continue;
      world::Space& space = environment.spaces[label - 1];
      space.segments.push_back(portal);
      space.portals.push_back(link);
    }
  }
  world::deriveDoors(&environment, name);
  for (world::Door& door : environment.doors)
    door.status = kind_of_portal.at(door.id) == PassageKind::kOpen ? world::DoorStatus::kOpen
                                                                   : world::DoorStatus::kClosed;
  return environment;
}

std::string floorToYaml(const SegmentedFloor& floor) {
  YAML::Emitter out;
  out.SetDoublePrecision(7);
  out << YAML::BeginMap;
  out << YAML::Key << "rooms" << YAML::Value << YAML::BeginSeq;
  for (const Room& room : floor.rooms) {
    out << YAML::BeginMap;
    out << YAML::Key << "label" << YAML::Value << room.label;
    out << YAML::Key << "kind" << YAML::Value << toString(room.kind);
    out << YAML::Key << "type" << YAML::Value << room.type;
    out << YAML::Key << "predicted" << YAML::Value << room.predicted;
    out << YAML::Key << "area" << YAML::Value << room.area;
    out << YAML::Key << "width" << YAML::Value << room.width;
    out << YAML::Key << "mean_width" << YAML::Value << room.mean_width;
    out << YAML::Key << "centroid" << YAML::Value;
    emitPoint(&out, room.centroid);
    out << YAML::Key << "outline" << YAML::Value << YAML::BeginSeq;
    for (const common::Point2& vertex : room.outline) emitPoint(&out, vertex);
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "passages" << YAML::Value << YAML::BeginSeq;
  for (const Passage& passage : floor.passages) {
    out << YAML::BeginMap;
    out << YAML::Key << "rooms" << YAML::Value << YAML::Flow << YAML::BeginSeq << passage.room_a << passage.room_b
        << YAML::EndSeq;
    out << YAML::Key << "kind" << YAML::Value << toString(passage.kind);
    if (passage.door_id != 0) out << YAML::Key << "door_id" << YAML::Value << passage.door_id;
    out << YAML::Key << "centre" << YAML::Value;
    emitPoint(&out, passage.centre);
    out << YAML::Key << "width" << YAML::Value << passage.width;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

cv::Mat3b floorPreview(const SegmentedFloor& floor, const common::OccupancyGrid& map) {
  cv::Mat3b image;
  cv::cvtColor(map.toGreyImage(), image, cv::COLOR_GRAY2BGR);
  for (int row = 0; row < image.rows; ++row)
    for (int col = 0; col < image.cols; ++col) {
      const int label = floor.labels(row, col);
      if (label == 0) continue;
      const cv::Vec3b colour = common::roomColour(label);
      // Predicted rooms paler, so that they read as not explored.
      image(row, col) = floor.rooms[label - 1].predicted ? cv::Vec3b(cv::Vec3i(colour) / 2 + cv::Vec3i(127, 127, 127))
                                                          : colour;
    }
  const auto pixel = [&](const common::Point2& point) {
    const common::Point2 at = map.toImage(point);
    return cv::Point(static_cast<int>(at.x()), static_cast<int>(at.y()));
  };
  for (const Passage& passage : floor.passages) {
    const cv::Scalar colour = passage.kind == PassageKind::kOpen     ? cv::Scalar(0, 160, 0)
                              : passage.kind == PassageKind::kClosed ? cv::Scalar(0, 0, 220)
                                                                     : cv::Scalar(0, 140, 255);
    for (const int label : {passage.room_a, passage.room_b})
      if (label != 0) cv::line(image, pixel(floor.rooms[label - 1].centroid), pixel(passage.centre), colour, 1);
    cv::circle(image, pixel(passage.centre), 2, colour, cv::FILLED);
  }
  for (const Room& room : floor.rooms)
    cv::circle(image, pixel(room.centroid), room.kind == RoomKind::kCorridor ? 4 : 3, cv::Scalar(0, 0, 0), cv::FILLED);
  return image;
}

void writeFloorOutputs(const SegmentedFloor& floor, const common::OccupancyGrid& map, const std::string& name,
                       common::OutputFolder* out) {
  common::saveLabelImage(floor.labels, out->file("rooms.png"));
  common::writeTextAtomically(out->file("rooms.yaml"), floorToYaml(floor), "rooms file");
  world::saveEnvironment(floorToEnvironment(floor, map, name), out->file("rooms.xml"));
  common::writeImage(out->file("preview.png"), floorPreview(floor, map));
}

}  // namespace hidden_rooms::segmentation
