#include "hidden_rooms/world/environment.h"

#include <opencv2/imgproc.hpp>
#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <map>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/input_limits.h"

namespace hidden_rooms::world {

namespace {

using tinyxml2::XMLElement;

constexpr double kPi = 3.14159265358979323846;
// A portal lies on a wall when a wall segment passes within this many XML pixels of it.
constexpr double kPortalOnWallTolerancePixels = 2.5;
// Outlines may cross themselves this close (metres) to a corner: drawing slop in real floor plans.
constexpr double kOutlineCornerTolerance = 0.25;
// Copies of one PORTAL id closer than this (metres, a double door's width) are one door: real plans give a door's
// two jambs as two copies about 0.9 m apart.
constexpr double kSamePortalDistance = 2.0;
// An outline that runs over itself (traced twice, looping around a part of itself) fills, drawn even-odd as the
// renderer draws it, another area than the one its vertices enclose; raster error stays well under this fraction.
constexpr double kFilledAreaTolerance = 0.1;
constexpr double kAreaCheckPixels = 2.5e5;    // the outline's area in pixels of the raster measuring its fill
constexpr double kAreaCheckMaxPixels = 1e6;   // pixels of that raster at most (a thin, long, slanted outline)
constexpr double kAreaCheckMaxSide = 4000.0;  // pixels of its longer side at most (a sliver)
constexpr double kAreaCheckMinPixels = 1000.0;  // an outline covering fewer pixels than this is not checked

// The area (m2) that an even-odd fill of `polygon` covers, measured on a raster fine enough for the polygon's area;
// `enclosed` itself for an outline too thin for a raster of bounded size to measure (a sliver).
double evenOddArea(const common::Polygon& polygon) {
  const double enclosed = common::area(polygon);
  if (!(enclosed > 0.0) || !std::isfinite(enclosed)) return enclosed;
  common::Point2 low = polygon.front(), high = polygon.front();
  for (const common::Point2& p : polygon) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  const common::Point2 size = high - low;
  const double pixels_per_metre =
      std::min({std::sqrt(kAreaCheckPixels / enclosed), std::sqrt(kAreaCheckMaxPixels / (size.x() * size.y())),
                kAreaCheckMaxSide / std::max(size.x(), size.y())});
  if (!std::isfinite(pixels_per_metre) || enclosed * pixels_per_metre * pixels_per_metre < kAreaCheckMinPixels)
    return enclosed;
  const cv::Size raster(static_cast<int>(std::ceil(size.x() * pixels_per_metre)) + 2,
                        static_cast<int>(std::ceil(size.y() * pixels_per_metre)) + 2);
  constexpr int kShift = 8;  // vertices with 1/256 pixel precision
  std::vector<cv::Point> vertices;
  for (const common::Point2& p : polygon) {
    const common::Point2 pixel = (p - low) * pixels_per_metre + common::Point2(1.0, 1.0);
    vertices.emplace_back(static_cast<int>(std::lround(pixel.x() * (1 << kShift))),
                          static_cast<int>(std::lround(pixel.y() * (1 << kShift))));
  }
  cv::Mat1b fill = cv::Mat1b::zeros(raster);
  cv::fillPoly(fill, std::vector<std::vector<cv::Point>>{vertices}, cv::Scalar(255), cv::LINE_8, kShift);
  return cv::countNonZero(fill) / (pixels_per_metre * pixels_per_metre);
}

std::string lineOf(const XMLElement* element) { return "line " + std::to_string(element->GetLineNum()); }

const XMLElement* requireChild(const XMLElement* parent, const char* name, const std::string& source) {
  const XMLElement* child = parent->FirstChildElement(name);
  if (child == nullptr)
    throw common::InputError(
        source, "<" + std::string(parent->Name()) + "> at " + lineOf(parent) + " has no <" + name + "> element");
  return child;
}

std::string childText(const XMLElement* parent, const char* name, const std::string& fallback = "") {
  const XMLElement* child = parent->FirstChildElement(name);
  if (child == nullptr || child->GetText() == nullptr) return fallback;
  std::string text = child->GetText();
  const auto first = text.find_first_not_of(" \t\r\n");
  const auto last = text.find_last_not_of(" \t\r\n");
  return first == std::string::npos ? "" : text.substr(first, last - first + 1);
}

double parseNumber(const std::string& text, const XMLElement* where, const std::string& what,
                   const std::string& source) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end == text.c_str() || *end != '\0' || !std::isfinite(value))
    throw common::InputError(source, what + " at " + lineOf(where) + " is not a finite number: '" + text + "'");
  return value;
}

// Reads <point x= y=> as XML pixels.
common::Point2 readPoint(const XMLElement* point, const std::string& source) {
  const char* x = point->Attribute("x");
  const char* y = point->Attribute("y");
  if (x == nullptr || y == nullptr) throw common::InputError(source, "<point> at " + lineOf(point) + " lacks x or y");
  return {parseNumber(x, point, "point x", source), parseNumber(y, point, "point y", source)};
}

double unitInMetres(const std::string& unit, const XMLElement* where, const std::string& source) {
  if (unit == "m") return 1.0;
  if (unit == "dm") return 0.1;
  if (unit == "cm" || unit.empty()) return 0.01;
  if (unit == "mm") return 0.001;
  throw common::InputError(source, "unknown length unit '" + unit + "' at " + lineOf(where) + " (m, dm, cm, mm)");
}

double readScale(const XMLElement* building, const std::string& source) {
  const XMLElement* scale = building->FirstChildElement("scale");
  if (scale == nullptr) throw common::InputError(source, "missing <scale> element (pixels to metres)");
  const XMLElement* represented = requireChild(scale, "represented_distance", source);
  const XMLElement* real = requireChild(scale, "real_distance", source);
  const double pixels = parseNumber(childText(represented, "value"), represented, "represented_distance", source);
  const double distance = parseNumber(childText(real, "value"), real, "real_distance", source) *
                          unitInMetres(childText(real, "um"), real, source);
  if (pixels <= 0.0 || distance <= 0.0)
    throw common::InputError(source, "<scale> at " + lineOf(scale) + " must have positive distances");
  return distance / pixels;
}

SegmentClass parseSegmentClass(const std::string& text, const XMLElement* where, const std::string& source) {
  if (text == "WALL") return SegmentClass::kWall;
  if (text == "PORTAL") return SegmentClass::kPortal;
  throw common::InputError(source, "linesegment at " + lineOf(where) + " has class '" + text + "' (WALL or PORTAL)");
}

DoorStatus parseStatus(const std::string& text, const XMLElement* where, const std::string& source) {
  if (text.empty()) return DoorStatus::kUnspecified;
  if (text == "OPEN") return DoorStatus::kOpen;
  if (text == "CLOSED") return DoorStatus::kClosed;
  throw common::InputError(source, "<status> at " + lineOf(where) + " is '" + text + "' (OPEN or CLOSED)");
}

double wallAngle(const LineSegment& wall) {
  return common::angleModuloPi(std::atan2(wall.b.y() - wall.a.y(), wall.b.x() - wall.a.x()));
}

bool isUsableWall(const LineSegment& segment, const common::Point2& centre, double tolerance) {
  return segment.segment_class == SegmentClass::kWall && (segment.b - segment.a).norm() > 1e-9 &&
         common::distanceToSegment(centre, segment.a, segment.b) <= tolerance;
}

// Angle (radians) between a wall and the nearest map axis.
double offAxisAngle(const LineSegment& wall) {
  const double angle = std::fmod(wallAngle(wall), kPi / 2.0);
  return std::min(angle, kPi / 2.0 - angle);
}

bool insidePolygon(const common::Polygon& polygon, const common::Point2& p) {
  bool inside = false;
  if (polygon.size() < 3) return false;
  for (size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const common::Point2& a = polygon[i];
    const common::Point2& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
      inside = !inside;
  }
  return inside;
}

// How many of the door's spaces are found stepping away from the door on both sides of a candidate wall
// (0 to 2; 2 when one side lies in one joined space and the other side in the other).
int sidesInJoinedSpaces(const Environment& environment, const Door& door, const LineSegment& wall) {
  const common::Point2 along = (wall.b - wall.a).normalized();
  const common::Point2 normal(-along.y(), along.x());
  std::vector<int> found;
  for (double side : {1.0, -1.0})
    for (double step : {0.25, 0.5, 0.75}) {
      const common::Point2 probe = door.centre + side * step * normal;
      const auto hit = std::find_if(door.space_indices.begin(), door.space_indices.end(), [&](int space) {
        return std::find(found.begin(), found.end(), space) == found.end() &&
               insidePolygon(environment.spaces[space].outline, probe);
      });
      if (hit != door.space_indices.end()) {
        found.push_back(*hit);
        break;
      }
    }
  return static_cast<int>(found.size());
}

// The wall a portal sits in, among the walls passing within `tolerance` of it: the one that separates the
// door's two spaces, then the most axis-aligned (real plans sometimes join a door to an offset parallel wall
// with a short slanted piece), then the longest. nullptr when no wall passes through the portal.
const LineSegment* wallOfPortal(const Environment& environment, const Door& door, double tolerance) {
  const LineSegment* best = nullptr;
  int best_sides = -1;
  for (const Space& space : environment.spaces)
    for (const LineSegment& segment : space.segments) {
      if (!isUsableWall(segment, door.centre, tolerance)) continue;
      const int sides = sidesInJoinedSpaces(environment, door, segment);
      bool better = best == nullptr || sides > best_sides;
      if (best != nullptr && sides == best_sides) {
        const double off = offAxisAngle(segment), best_off = offAxisAngle(*best);
        better = std::abs(off - best_off) > 1e-6 ? off < best_off
                                                 : (segment.b - segment.a).norm() > (best->b - best->a).norm();
      }
      if (better) {
        best = &segment;
        best_sides = sides;
      }
    }
  return best;
}

void writePoint(tinyxml2::XMLPrinter* out, const common::Point2& pixel) {
  out->OpenElement("point");
  out->PushAttribute("x", common::formatNumber(pixel.x()).c_str());
  out->PushAttribute("y", common::formatNumber(pixel.y()).c_str());
  out->CloseElement(true);
}

void writeTextElement(tinyxml2::XMLPrinter* out, const char* name, const std::string& text) {
  out->OpenElement(name);
  out->PushText(text.c_str());
  out->CloseElement(true);
}

}  // namespace

std::vector<LineSegment> Environment::walls() const {
  std::vector<LineSegment> result;
  for (const Space& space : spaces)
    for (const LineSegment& segment : space.segments)
      if (segment.segment_class == SegmentClass::kWall) result.push_back(segment);
  return result;
}

int Environment::findDoor(const std::string& id_or_number) const {
  for (size_t i = 0; i < doors.size(); ++i)
    if (doors[i].id == id_or_number || std::to_string(doors[i].number) == id_or_number) return static_cast<int>(i);
  return -1;
}

std::pair<common::Point2, common::Point2> Environment::bounds() const {
  const double inf = std::numeric_limits<double>::infinity();
  common::Point2 low(inf, inf), high(-inf, -inf);
  auto extend = [&](const common::Point2& p) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  };
  for (const Space& space : spaces) {
    for (const common::Point2& p : space.outline) extend(p);
    for (const LineSegment& segment : space.segments) {
      extend(segment.a);
      extend(segment.b);
    }
  }
  if (low.x() > high.x()) return {common::Point2::Zero(), common::Point2::Zero()};
  return {low, high};
}

void deriveDoors(Environment* environment, const std::string& source_name) {
  std::map<std::string, DoorStatus> previous_status;
  for (const Door& door : environment->doors) previous_status[door.id] = door.status;
  environment->doors.clear();

  std::map<std::string, int> door_of_segment;
  std::map<std::string, int> space_of_id;
  for (size_t s = 0; s < environment->spaces.size(); ++s) space_of_id[environment->spaces[s].id] = static_cast<int>(s);
  auto addSpace = [](Door* door, int space_index) {
    if (std::find(door->space_indices.begin(), door->space_indices.end(), space_index) == door->space_indices.end())
      door->space_indices.push_back(space_index);
  };

  for (size_t s = 0; s < environment->spaces.size(); ++s) {
    for (const LineSegment& segment : environment->spaces[s].segments) {
      if (segment.segment_class != SegmentClass::kPortal) continue;
      auto found = door_of_segment.find(segment.id);
      if (found != door_of_segment.end()) {
        Door& door = environment->doors[found->second];
        const double apart = (0.5 * (segment.a + segment.b) - door.centre).norm();
        if (apart > kSamePortalDistance)
          environment->repairs.push_back("portal '" + segment.id + "' appears at two places " +
                                         common::formatNumber(std::round(apart * 100.0) / 100.0) +
                                         " m apart; the door is placed at its first appearance");
      } else {
        Door door;
        door.id = segment.id;
        door.number = static_cast<int>(environment->doors.size()) + 1;
        door.centre = 0.5 * (segment.a + segment.b);
        door.implicit = segment.type == "IMPLICIT";
        auto status = previous_status.find(segment.id);
        if (status != previous_status.end()) door.status = status->second;
        found = door_of_segment.emplace(segment.id, static_cast<int>(environment->doors.size())).first;
        environment->doors.push_back(door);
      }
      addSpace(&environment->doors[found->second], static_cast<int>(s));
    }
  }
  // Portal links name the joined spaces too (some files list a portal segment in one space only).
  for (const Space& space : environment->spaces)
    for (const PortalLink& link : space.portals) {
      auto door = door_of_segment.find(link.segment_id);
      if (door == door_of_segment.end()) continue;  // a link to no PORTAL segment names no door
      for (const std::string& target : link.target_ids) {
        auto target_space = space_of_id.find(target);
        if (target_space != space_of_id.end()) addSpace(&environment->doors[door->second], target_space->second);
      }
    }

  const double tolerance = kPortalOnWallTolerancePixels * environment->metres_per_pixel;
  for (Door& door : environment->doors) {
    const LineSegment* wall = wallOfPortal(*environment, door, tolerance);
    if (wall == nullptr) {
      const double u = door.centre.x() / environment->metres_per_pixel;
      const double v = environment->flip_v - door.centre.y() / environment->metres_per_pixel;
      throw common::InputError(source_name, "portal '" + door.id + "' at pixel (" + common::formatNumber(u) + ", " +
                                                common::formatNumber(v) + ") lies on no wall");
    }
    door.wall_angle = wallAngle(*wall);
    door.orientation = std::abs(std::cos(door.wall_angle)) >= std::abs(std::sin(door.wall_angle))
                           ? common::DoorOrientation::kAlongX
                           : common::DoorOrientation::kAlongY;
  }
}

Environment parseEnvironment(const std::string& xml_text, const std::string& source) {
  tinyxml2::XMLDocument document;
  if (document.Parse(xml_text.c_str(), xml_text.size()) != tinyxml2::XML_SUCCESS)
    throw common::InputError(source, std::string("malformed XML: ") + document.ErrorStr());
  const XMLElement* building = document.RootElement();
  if (building == nullptr || std::string(building->Name()) != "building")
    throw common::InputError(source, std::string("root element must be <building>, found <") +
                                         (building != nullptr ? building->Name() : "nothing") + ">");

  Environment environment;
  environment.building_id = building->Attribute("id") != nullptr ? building->Attribute("id") : "";
  environment.name = childText(building, "name");
  if (const XMLElement* type = building->FirstChildElement("building_type"))
    environment.building_type = childText(type, "main_type");
  environment.metres_per_pixel = readScale(building, source);
  if (const XMLElement* thickness = building->FirstChildElement("wall_thickness")) {
    const double value = parseNumber(childText(building, "wall_thickness"), thickness, "wall_thickness", source);
    if (value <= 0.0)
      throw common::InputError(source, "<wall_thickness> at " + lineOf(thickness) + " must be positive");
    environment.wall_thickness = value;
  }

  const XMLElement* floor = requireChild(building, "floor", source);
  const XMLElement* spaces = requireChild(floor, "spaces", source);
  std::map<std::string, DoorStatus> portal_status;
  std::map<std::string, int> space_line;
  double max_v = -std::numeric_limits<double>::infinity();

  for (const XMLElement* element = spaces->FirstChildElement("space"); element != nullptr;
       element = element->NextSiblingElement("space")) {
    Space space;
    space.id = element->Attribute("id") != nullptr ? element->Attribute("id") : "";
    if (space.id.empty()) throw common::InputError(source, "<space> at " + lineOf(element) + " has no id");
    if (!space_line.emplace(space.id, element->GetLineNum()).second)
      throw common::InputError(source, "space id '" + space.id + "' at " + lineOf(element) + " is used twice");
    common::checkLimit(source, "the number of spaces", static_cast<double>(space_line.size()), common::kMaxSpaces);
    if (const XMLElement* labels = element->FirstChildElement("labels")) {
      space.type = childText(labels, "type");
      space.label = childText(labels, "label");
    }
    const XMLElement* polygon = requireChild(element, "bounding_polygon", source);
    for (const XMLElement* point = polygon->FirstChildElement("point"); point != nullptr;
         point = point->NextSiblingElement("point"))
      space.outline.push_back(readPoint(point, source));
    if (const XMLElement* representation = element->FirstChildElement("space_representation")) {
      for (const XMLElement* line = representation->FirstChildElement("linesegment"); line != nullptr;
           line = line->NextSiblingElement("linesegment")) {
        LineSegment segment;
        segment.id = line->Attribute("id") != nullptr ? line->Attribute("id") : "";
        if (segment.id.empty()) throw common::InputError(source, "linesegment at " + lineOf(line) + " has no id");
        const XMLElement* first = line->FirstChildElement("point");
        const XMLElement* second = first != nullptr ? first->NextSiblingElement("point") : nullptr;
        if (second == nullptr)
          throw common::InputError(source, "linesegment at " + lineOf(line) + " needs two <point>s");
        segment.a = readPoint(first, source);
        segment.b = readPoint(second, source);
        segment.segment_class = parseSegmentClass(childText(line, "class"), line, source);
        segment.type = childText(line, "type", "EXPLICIT");
        segment.features = childText(line, "features", "NORMAL");
        if (segment.segment_class == SegmentClass::kPortal) {
          const DoorStatus status = parseStatus(childText(line, "status"), line, source);
          if (status != DoorStatus::kUnspecified) portal_status[segment.id] = status;
        }
        space.segments.push_back(segment);
      }
    }
    if (const XMLElement* portals = element->FirstChildElement("portals")) {
      for (const XMLElement* portal = portals->FirstChildElement("portal"); portal != nullptr;
           portal = portal->NextSiblingElement("portal")) {
        PortalLink link;
        link.segment_id = childText(portal, "linesegment");
        link.portal_class = childText(portal, "class", link.portal_class);
        link.type = childText(portal, "type", link.type);
        link.features = childText(portal, "features", link.features);
        link.direction = childText(portal, "direction", link.direction);
        if (const XMLElement* target = portal->FirstChildElement("target"))
          for (const XMLElement* id = target->FirstChildElement("id"); id != nullptr; id = id->NextSiblingElement("id"))
            if (id->GetText() != nullptr) link.target_ids.push_back(id->GetText());
        space.portals.push_back(link);
      }
    }
    for (const common::Point2& p : space.outline) max_v = std::max(max_v, p.y());
    for (const LineSegment& segment : space.segments) max_v = std::max({max_v, segment.a.y(), segment.b.y()});
    environment.spaces.push_back(std::move(space));
  }
  if (environment.spaces.empty()) throw common::InputError(source, "the floor has no <space>");

  // XML pixels (y down) -> metres (y up).
  environment.flip_v = max_v;
  const double s = environment.metres_per_pixel;
  auto toMetres = [&](const common::Point2& pixel) { return common::Point2(pixel.x() * s, (max_v - pixel.y()) * s); };
  for (Space& space : environment.spaces) {
    for (common::Point2& p : space.outline) p = toMetres(p);
    for (LineSegment& segment : space.segments) {
      segment.a = toMetres(segment.a);
      segment.b = toMetres(segment.b);
    }
    space.outline = common::withoutRepeatedVertices(space.outline);
    const std::string where = "space '" + space.id + "' (line " + std::to_string(space_line[space.id]) + ")";
    if (space.outline.size() < 3) {  // real files have a few
      environment.repairs.push_back("the outline of " + where +
                                    " has fewer than 3 distinct vertices; the space has no floor");
      continue;
    }
    std::string problem;
    if (common::hasCrossing(space.outline, kOutlineCornerTolerance, &problem))
      throw common::InputError(source, "outline of " + where + " crosses itself: " + problem);
    const double enclosed = common::area(space.outline);
    const double filled = evenOddArea(space.outline);
    if (std::abs(filled - enclosed) > kFilledAreaTolerance * enclosed)
      throw common::InputError(source, "outline of " + where + " runs over itself: it encloses " +
                                           common::formatNumber(std::round(enclosed * 10.0) / 10.0) +
                                           " m2 but a drawing of it fills " +
                                           common::formatNumber(std::round(filled * 10.0) / 10.0) + " m2");
  }
  deriveDoors(&environment, source);
  for (Door& door : environment.doors) {
    auto status = portal_status.find(door.id);
    if (status != portal_status.end()) door.status = status->second;
  }
  return environment;
}

void printRepairs(const Environment& environment, const std::string& source, std::ostream& out) {
  for (const std::string& repair : environment.repairs) out << "warning: " << source << ": " << repair << "\n";
}

Environment loadEnvironment(const std::string& path) {
  return parseEnvironment(common::readTextFile(path, "environment file"), path);
}

std::string environmentToXml(const Environment& environment) {
  const double s = environment.metres_per_pixel;
  auto toPixels = [&](const common::Point2& p) { return common::Point2(p.x() / s, environment.flip_v - p.y() / s); };
  std::map<std::string, DoorStatus> status_of;
  for (const Door& door : environment.doors) status_of[door.id] = door.status;

  tinyxml2::XMLPrinter out;
  out.PushHeader(false, true);
  out.OpenElement("building");
  out.PushAttribute("id", environment.building_id.c_str());
  writeTextElement(&out, "name", environment.name);
  out.OpenElement("scale");
  out.OpenElement("represented_distance");
  writeTextElement(&out, "value", "1");
  writeTextElement(&out, "um", "pixel");
  out.CloseElement();
  out.OpenElement("real_distance");
  char scale[64];
  std::snprintf(scale, sizeof(scale), "%.17g", s);  // exact: reads back to the same double
  writeTextElement(&out, "value", scale);
  writeTextElement(&out, "um", "m");
  out.CloseElement();
  out.CloseElement();
  if (environment.wall_thickness)
    writeTextElement(&out, "wall_thickness", common::formatNumber(*environment.wall_thickness));
  out.OpenElement("building_type");
  writeTextElement(&out, "main_type", environment.building_type);
  out.CloseElement();
  out.OpenElement("floor");
  out.OpenElement("spaces");
  for (const Space& space : environment.spaces) {
    out.OpenElement("space");
    out.PushAttribute("id", space.id.c_str());
    out.OpenElement("labels");
    writeTextElement(&out, "type", space.type);
    writeTextElement(&out, "label", space.label);
    out.CloseElement();

    common::Polygon pixels;
    for (const common::Point2& p : space.outline) pixels.push_back(toPixels(p));
    const double twice_area = 2.0 * common::signedArea(pixels);
    common::Point2 centroid = common::Point2::Zero();
    for (size_t i = 0; i < pixels.size(); ++i) {
      const common::Point2& a = pixels[i];
      const common::Point2& b = pixels[(i + 1) % pixels.size()];
      centroid += (a + b) * (a.x() * b.y() - b.x() * a.y());
    }
    if (std::abs(twice_area) > 1e-12) centroid /= 3.0 * twice_area;
    else if (!pixels.empty()) centroid = pixels.front();
    out.OpenElement("centroid");
    // Whole pixels as in the thesis's files; the bias keeps x.5 from flipping with rounding noise.
    writePoint(&out, common::Point2(std::floor(centroid.x() + 0.5 + 1e-6), std::floor(centroid.y() + 0.5 + 1e-6)));
    out.CloseElement();
    out.OpenElement("bounding_box");
    const std::pair<const char*, std::function<bool(const common::Point2&, const common::Point2&)>> extremes[] = {
        {"maxx", [](const common::Point2& a, const common::Point2& b) { return a.x() > b.x(); }},
        {"maxy", [](const common::Point2& a, const common::Point2& b) { return a.y() > b.y(); }},
        {"minx", [](const common::Point2& a, const common::Point2& b) { return a.x() < b.x(); }},
        {"miny", [](const common::Point2& a, const common::Point2& b) { return a.y() < b.y(); }}};
    for (const auto& [name, better] : extremes) {
      if (pixels.empty()) break;
      common::Point2 extreme = pixels.front();
      for (const common::Point2& p : pixels)
        if (better(p, extreme)) extreme = p;
      out.OpenElement(name);
      writePoint(&out, extreme);
      out.CloseElement();
    }
    out.CloseElement();
    out.OpenElement("bounding_polygon");
    for (const common::Point2& p : pixels) writePoint(&out, p);
    if (pixels.size() >= 3) writePoint(&out, pixels.front());  // closed, as the thesis's files are
    out.CloseElement();

    out.OpenElement("space_representation");
    for (const LineSegment& segment : space.segments) {
      out.OpenElement("linesegment");
      out.PushAttribute("id", segment.id.c_str());
      writePoint(&out, toPixels(segment.a));
      writePoint(&out, toPixels(segment.b));
      writeTextElement(&out, "class", segment.segment_class == SegmentClass::kWall ? "WALL" : "PORTAL");
      writeTextElement(&out, "type", segment.type);
      writeTextElement(&out, "features", segment.features);
      if (segment.segment_class == SegmentClass::kPortal) {
        const DoorStatus status = status_of.count(segment.id) ? status_of[segment.id] : DoorStatus::kUnspecified;
        if (status != DoorStatus::kUnspecified)
          writeTextElement(&out, "status", status == DoorStatus::kOpen ? "OPEN" : "CLOSED");
      }
      out.CloseElement();
    }
    out.CloseElement();
    out.OpenElement("portals");
    for (const PortalLink& link : space.portals) {
      out.OpenElement("portal");
      writeTextElement(&out, "linesegment", link.segment_id);
      writeTextElement(&out, "class", link.portal_class);
      writeTextElement(&out, "type", link.type);
      writeTextElement(&out, "features", link.features);
      writeTextElement(&out, "direction", link.direction);
      out.OpenElement("target");
      for (const std::string& target : link.target_ids) writeTextElement(&out, "id", target);
      out.CloseElement();
      out.CloseElement();
    }
    out.CloseElement();
    out.CloseElement();
  }
  out.CloseElement();
  out.CloseElement();
  out.CloseElement();
  return out.CStr();
}

void saveEnvironment(const Environment& environment, const std::string& path) {
  common::writeTextAtomically(path, environmentToXml(environment), "environment file");
}

std::vector<int> closableDoors(const Environment& environment) {
  std::vector<int> result;
  for (size_t d = 0; d < environment.doors.size(); ++d)
    if (roomBehindDoor(environment, static_cast<int>(d)) >= 0) result.push_back(static_cast<int>(d));
  return result;
}

int roomBehindDoor(const Environment& environment, int door_index) {
  const Door& door = environment.doors.at(door_index);
  if (door.space_indices.size() != 2) return -1;
  std::vector<int> doors_per_space(environment.spaces.size(), 0);
  for (const Door& other : environment.doors)
    for (int space : other.space_indices) ++doors_per_space[space];
  int best = -1;
  for (int space : door.space_indices) {
    if (doors_per_space[space] != 1) continue;
    if (best < 0 || common::area(environment.spaces[space].outline) < common::area(environment.spaces[best].outline))
      best = space;
  }
  return best;
}

std::set<int> parseDoorSelection(const Environment& environment, const std::string& spec,
                                 const std::string& source_name) {
  std::set<int> selected;
  if (spec == "closable") {
    for (int door : closableDoors(environment)) selected.insert(door);
    return selected;
  }
  if (spec == "all") {
    for (size_t d = 0; d < environment.doors.size(); ++d)
      if (environment.doors[d].space_indices.size() >= 2) selected.insert(static_cast<int>(d));
    return selected;
  }
  if (spec.find_first_not_of(' ') == std::string::npos) return selected;  // no door
  for (const std::string& item : common::splitList(spec)) {
    if (item.empty())
      throw common::InputError(source_name, "'" + spec + "' has an empty door number between its commas");
    const int index = environment.findDoor(item);
    if (index < 0)
      throw common::InputError(source_name, "no door '" + item + "' (door numbers are 1.." +
                                                std::to_string(environment.doors.size()) + ", or use portal ids)");
    selected.insert(index);
  }
  return selected;
}

}  // namespace hidden_rooms::world
