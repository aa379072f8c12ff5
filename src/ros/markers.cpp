#include "hidden_rooms/ros/markers.h"

#include <cstdio>
#include <map>
#include <set>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/ros/conversions.h"

namespace hidden_rooms {
namespace {

std_msgs::ColorRGBA colour(double r, double g, double b, double a) {
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(r);
  c.g = static_cast<float>(g);
  c.b = static_cast<float>(b);
  c.a = static_cast<float>(a);
  return c;
}

std_msgs::ColorRGBA roomColourRgba(int label, double alpha) {
  const cv::Vec3b bgr = common::roomColour(label);
  return colour(bgr[2] / 255.0, bgr[1] / 255.0, bgr[0] / 255.0, alpha);
}

// A map-frame point of continuous image coordinates (x = column, y = row from the top).
geometry_msgs::Point imagePoint(const common::OccupancyGrid& map, double x, double y, double z) {
  return toRos(
      common::Point2(map.origin.x() + x * map.resolution, map.origin.y() + (map.height() - y) * map.resolution), z);
}

visualization_msgs::Marker newMarker(const std::string& ns, int id, int type, const std::string& frame_id,
                                     const ros::Time& stamp) {
  visualization_msgs::Marker marker;
  marker.header.frame_id = frame_id;
  marker.header.stamp = stamp;
  marker.ns = ns;
  marker.id = id;
  marker.type = type;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose.orientation.w = 1.0;
  marker.scale.x = marker.scale.y = marker.scale.z = 1.0;
  marker.color = colour(1.0, 1.0, 1.0, 1.0);
  return marker;
}

// An array that starts with a DELETEALL marker.
visualization_msgs::MarkerArray startArray(const std::string& frame_id, const ros::Time& stamp) {
  visualization_msgs::MarkerArray array;
  visualization_msgs::Marker clear = newMarker("", 0, visualization_msgs::Marker::CUBE, frame_id, stamp);
  clear.action = visualization_msgs::Marker::DELETEALL;
  array.markers.push_back(clear);
  return array;
}

// Two triangles per axis-aligned image rectangle [x0, x1) x [y0, y1).
void addRectangle(const common::OccupancyGrid& map, double x0, double y0, double x1, double y1, double z,
                  const std_msgs::ColorRGBA* vertex_colour, visualization_msgs::Marker* marker) {
  const geometry_msgs::Point a = imagePoint(map, x0, y1, z), b = imagePoint(map, x1, y1, z),
                             c = imagePoint(map, x1, y0, z), d = imagePoint(map, x0, y0, z);
  for (const geometry_msgs::Point& p : {a, b, c, a, c, d}) {
    marker->points.push_back(p);
    if (vertex_colour != nullptr) marker->colors.push_back(*vertex_colour);
  }
}

// The cells of a mask as few rectangles: runs of each row, stacked while the next row has the same run.
void addMaskTriangles(const common::OccupancyGrid& map, const cv::Mat1b& mask, double z,
                      visualization_msgs::Marker* marker) {
  std::vector<cv::Point> cells;
  cv::findNonZero(mask, cells);
  if (cells.empty()) return;
  const cv::Rect box = cv::boundingRect(cells);
  std::map<std::pair<int, int>, int> open;  // run [begin, end) -> first row
  auto close_runs = [&](const std::set<std::pair<int, int>>& keep, int row) {
    for (auto it = open.begin(); it != open.end();) {
      if (keep.count(it->first) == 0) {
        addRectangle(map, it->first.first, it->second, it->first.second, row, z, nullptr, marker);
        it = open.erase(it);
      } else {
        ++it;
      }
    }
  };
  for (int row = box.y; row < box.y + box.height; ++row) {
    std::set<std::pair<int, int>> runs;
    const uchar* line = mask.ptr<uchar>(row);
    for (int col = box.x; col < box.x + box.width;) {
      if (line[col] == 0) {
        ++col;
        continue;
      }
      const int begin = col;
      while (col < box.x + box.width && line[col] != 0) ++col;
      runs.insert({begin, col});
    }
    close_runs(runs, row);
    for (const auto& run : runs) open.emplace(run, row);
  }
  close_runs({}, box.y + box.height);
}

}  // namespace

visualization_msgs::MarkerArray toMarkers(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                                          const std::vector<prediction::RoomPrediction>& rooms, const cv::Mat1w& labels,
                                          const std::string& frame_id, const ros::Time& stamp) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray array = startArray(frame_id, stamp);
  for (size_t k = 0; k < rooms.size(); ++k) {
    const prediction::RoomPrediction& room = rooms[k];
    const int label = static_cast<int>(k) + 1;
    if (!room.placed) continue;
    const cv::Mat1b cells = labels == label;
    Marker fill = newMarker("rooms", room.door_id, Marker::TRIANGLE_LIST, frame_id, stamp);
    fill.color = roomColourRgba(label, 0.55);
    addMaskTriangles(map, cells, 0.01, &fill);
    if (!fill.points.empty()) array.markers.push_back(fill);
    if (room.polygon.size() >= 2) {
      Marker outline = newMarker("outlines", room.door_id, Marker::LINE_STRIP, frame_id, stamp);
      outline.scale.x = 2.0 * map.resolution;
      outline.color = roomColourRgba(label, 1.0);
      for (const common::Point2& p : room.polygon) outline.points.push_back(toRos(p, 0.02));
      outline.points.push_back(outline.points.front());
      array.markers.push_back(outline);
    }
    const cv::Moments moments = cv::moments(cells, true);
    const cv::Mat1b own = room.mask;
    const cv::Moments fallback = moments.m00 > 0 ? moments : cv::moments(own, true);
    if (fallback.m00 > 0) {
      Marker text = newMarker("labels", room.door_id, Marker::TEXT_VIEW_FACING, frame_id, stamp);
      text.pose.position = imagePoint(map, fallback.m10 / fallback.m00 + 0.5, fallback.m01 / fallback.m00 + 0.5, 0.5);
      text.scale.z = 1.0;  // metres: text height
      char area[32];
      std::snprintf(area, sizeof(area), "%.1f", room.area);
      text.text = "door " + std::to_string(room.door_id) + "\n" + area + " m2";
      array.markers.push_back(text);
    }
  }
  Marker door_lines = newMarker("doors", 0, Marker::LINE_LIST, frame_id, stamp);
  door_lines.scale.x = 0.3;  // metres: line width
  for (size_t k = 0; k < doors.doors.size(); ++k) {
    const common::MapDoor& door = doors.doors[k];
    const bool placed = k < rooms.size() && rooms[k].placed;
    const std_msgs::ColorRGBA c = placed ? colour(0.9, 0.1, 0.1, 1.0) : colour(0.5, 0.5, 0.5, 1.0);
    const common::Point2 half = door.orientation == common::DoorOrientation::kAlongX
                                    ? common::Point2(door.width / 2, 0)
                                    : common::Point2(0, door.width / 2);
    for (const common::Point2& p : {common::Point2(door.position - half), common::Point2(door.position + half)}) {
      door_lines.points.push_back(toRos(p, 0.03));
      door_lines.colors.push_back(c);
    }
  }
  if (!door_lines.points.empty()) array.markers.push_back(door_lines);
  // What the colours mean, centred above the map.
  Marker legend = newMarker("legend", 0, Marker::TEXT_VIEW_FACING, frame_id, stamp);
  legend.pose.position = imagePoint(map, 0.5 * map.width(), -2.0 / map.resolution, 0.5);
  legend.scale.z = 1.0;  // metres: text height
  legend.text = "coloured: predicted room (door id, area)   red bar: closed door   grey bar: door not placed\n"
                "map: white free, black wall, grey unexplored";
  array.markers.push_back(legend);
  return array;
}

visualization_msgs::MarkerArray toMarkers(const segmentation::SegmentedFloor& floor, const std::string& frame_id,
                                          const ros::Time& stamp) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray array = startArray(frame_id, stamp);
  Marker nodes = newMarker("room_nodes", 0, Marker::SPHERE_LIST, frame_id, stamp);
  nodes.scale.x = nodes.scale.y = nodes.scale.z = 0.4;
  for (const segmentation::Room& room : floor.rooms) {
    const double alpha = room.predicted ? 0.5 : 1.0;
    if (room.outline.size() >= 2) {
      Marker outline = newMarker("room_outlines", room.label, Marker::LINE_STRIP, frame_id, stamp);
      outline.scale.x = 0.08;
      outline.color = roomColourRgba(room.label, alpha);
      for (const common::Point2& vertex : room.outline) outline.points.push_back(toRos(vertex, 0.03));
      outline.points.push_back(outline.points.front());
      array.markers.push_back(outline);
    }
    Marker text = newMarker("room_labels", room.label, Marker::TEXT_VIEW_FACING, frame_id, stamp);
    text.pose.position = toRos(room.centroid, 0.8);
    text.scale.z = 0.7;  // metres: text height
    char area[32];
    std::snprintf(area, sizeof(area), "%.1f m2", room.area);
    text.text = std::to_string(room.label) + " " + (room.predicted ? "predicted " : "") +
                (room.type.empty() ? segmentation::toString(room.kind) : room.type) + "\n" + area;
    array.markers.push_back(text);
    nodes.points.push_back(toRos(room.centroid, 0.3));
    nodes.colors.push_back(roomColourRgba(room.label, alpha));
  }
  if (!nodes.points.empty()) array.markers.push_back(nodes);
  const std::pair<segmentation::PassageKind, std_msgs::ColorRGBA> kinds[] = {
      {segmentation::PassageKind::kOpen, colour(0.1, 0.7, 0.1, 1.0)},
      {segmentation::PassageKind::kClosed, colour(0.9, 0.1, 0.1, 1.0)},
      {segmentation::PassageKind::kPredicted, colour(1.0, 0.55, 0.0, 1.0)}};
  for (const auto& [kind, edge_colour] : kinds) {
    Marker edges = newMarker("room_graph", static_cast<int>(kind), Marker::LINE_LIST, frame_id, stamp);
    edges.scale.x = 0.06;
    edges.color = edge_colour;
    for (const segmentation::Passage& passage : floor.passages) {
      if (passage.kind != kind) continue;
      for (const int label : {passage.room_a, passage.room_b}) {
        if (label == 0) continue;
        edges.points.push_back(toRos(floor.rooms[label - 1].centroid, 0.3));
        edges.points.push_back(toRos(passage.centre, 0.3));
      }
    }
    if (!edges.points.empty()) array.markers.push_back(edges);
  }
  return array;
}

visualization_msgs::MarkerArray toDebugMarkers(const common::OccupancyGrid& map, const prediction::Layout& layout,
                                               const std::string& frame_id, const ros::Time& stamp) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray array;
  const prediction::CellGrid& grid = layout.grid;
  if (grid.xs.size() < 2 || grid.ys.size() < 2) return array;
  Marker lines = newMarker("debug_extended_lines", 0, Marker::LINE_LIST, frame_id, stamp);
  lines.scale.x = map.resolution;
  for (const prediction::ExtendedLine& line : layout.lines) {
    const std_msgs::ColorRGBA c = line.source == prediction::LineSource::kWall       ? colour(0.2, 0.4, 1.0, 1.0)
                                  : line.source == prediction::LineSource::kDoorPair ? colour(1.0, 0.6, 0.0, 1.0)
                                                                                     : colour(0.6, 0.6, 0.6, 1.0);
    if (line.axis == prediction::LineAxis::kHorizontal) {
      lines.points.push_back(imagePoint(map, grid.xs.front(), line.position, 0.04));
      lines.points.push_back(imagePoint(map, grid.xs.back(), line.position, 0.04));
    } else {
      lines.points.push_back(imagePoint(map, line.position, grid.ys.front(), 0.04));
      lines.points.push_back(imagePoint(map, line.position, grid.ys.back(), 0.04));
    }
    lines.colors.push_back(c);
    lines.colors.push_back(c);
  }
  if (!lines.points.empty()) array.markers.push_back(lines);
  Marker cells = newMarker("debug_in_out_cells", 0, Marker::TRIANGLE_LIST, frame_id, stamp);
  for (const prediction::LayoutCell& cell : grid.cells) {
    const std_msgs::ColorRGBA c = cell.out ? colour(0.9, 0.2, 0.2, 0.25) : colour(0.2, 0.8, 0.2, 0.25);
    addRectangle(map, cell.rect.x, cell.rect.y, cell.rect.x + cell.rect.width, cell.rect.y + cell.rect.height, 0.005,
                 &c, &cells);
  }
  if (!cells.points.empty()) array.markers.push_back(cells);
  return array;
}

visualization_msgs::MarkerArray toMarkers(const common::OccupancyGrid& map, const ExplorationView& view,
                                          const std::string& frame_id, const ros::Time& stamp) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray array = startArray(frame_id, stamp);

  Marker cells = newMarker("frontiers", 0, Marker::CUBE_LIST, frame_id, stamp);
  cells.scale.x = cells.scale.y = map.resolution;
  cells.scale.z = 0.02;
  if (view.frontiers != nullptr) {
    for (const exploration::Frontier& frontier : view.frontiers->frontiers) {
      const bool chosen = view.goal && frontier.label == view.goal_frontier_label;
      for (const cv::Point& cell : frontier.cells) {
        const common::Point2 centre = map.cellCentre(cell.x, cell.y);
        cells.points.push_back(toRos(centre, 0.01));
        cells.colors.push_back(chosen ? colour(1.0, 0.5, 0.0, 1.0) : colour(0.1, 0.4, 1.0, 1.0));
      }
    }
  }
  if (!cells.points.empty()) array.markers.push_back(cells);

  if (view.goal) {
    Marker goal = newMarker("goal", 0, Marker::SPHERE, frame_id, stamp);
    goal.pose.position = toRos(*view.goal, 0.1);
    goal.scale.x = goal.scale.y = goal.scale.z = 0.3;
    goal.color = colour(1.0, 0.5, 0.0, 1.0);
    array.markers.push_back(goal);

    Marker path = newMarker("path", 0, Marker::LINE_STRIP, frame_id, stamp);
    path.scale.x = 0.05;
    path.color = colour(0.0, 0.8, 0.2, 1.0);
    for (const common::Point2& p : view.path) path.points.push_back(toRos(p, 0.05));
    if (path.points.size() >= 2) array.markers.push_back(path);
  }

  // Places as spheres of `diameter` metres (flattened to `height`) at `z`.
  const auto spheres = [&](const char* ns, const std::vector<common::Point2>& places, double diameter, double height,
                           double z, const std_msgs::ColorRGBA& tint) {
    if (places.empty()) return;
    Marker marker = newMarker(ns, 0, Marker::SPHERE_LIST, frame_id, stamp);
    marker.scale.x = marker.scale.y = diameter;
    marker.scale.z = height;
    marker.color = tint;
    for (const common::Point2& place : places) marker.points.push_back(toRos(place, z));
    array.markers.push_back(marker);
  };
  spheres("blacklist", view.blacklist, 0.2, 0.2, 0.1, colour(1.0, 0.0, 0.0, 0.8));
  spheres("blocked_passages", view.blocked_passages, 2.0 * view.blocked_passage_radius, 0.05, 0.05,
          colour(0.6, 0.0, 0.6, 0.6));
  return array;
}

}  // namespace hidden_rooms
