#pragma once

#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/geometry.h"

namespace hidden_rooms::world {

// The thesis's environment XML (KTH floor-plan schema, docs/method.md#exploration-runs) as a metric model.
//
// Frame: the environment ("world") frame, metres, REP-103 (x right, y up). The XML stores image pixels
// (x right, y down); a pixel (u, v) maps to (u * metres_per_pixel, (flip_v - v) * metres_per_pixel), where
// flip_v is the largest v of the file, so every coordinate is >= 0 in y and the file can be written back
// with its original pixel values.

enum class SegmentClass { kWall, kPortal };

// One <linesegment> of a space's <space_representation>. A PORTAL usually has a = b (the door centre).
struct LineSegment {
  std::string id;
  common::Point2 a;
  common::Point2 b;
  SegmentClass segment_class = SegmentClass::kWall;
  std::string type = "EXPLICIT";    // EXPLICIT | IMPLICIT, kept for the round trip
  std::string features = "NORMAL";  // kept for the round trip
};

// One <portal> entry of a space's <portals>: which PORTAL segment links which spaces.
struct PortalLink {
  std::string segment_id;
  std::string portal_class = "HORIZONTAL";
  std::string type = "EXPLICIT";
  std::string features = "NORMAL";
  std::string direction = "BOTH";
  std::vector<std::string> target_ids;
};

struct Space {
  std::string id;
  std::string type;   // <labels><type>
  std::string label;  // <labels><label>: CORRIDOR, OFFICE, ...
  common::Polygon outline;  // <bounding_polygon>, metres, repeated vertices removed; < 3 if degenerate
  std::vector<LineSegment> segments;
  std::vector<PortalLink> portals;
};

enum class DoorStatus { kUnspecified, kOpen, kClosed };

// A door: one distinct PORTAL segment id of the file.
struct Door {
  std::string id;                   // the PORTAL linesegment id
  int number = 0;                   // 1-based, order of first appearance in the file; used in doors.yaml
  common::Point2 centre;            // metres
  double wall_angle = 0.0;          // direction of the wall the door sits in, radians in [0, pi)
  common::DoorOrientation orientation = common::DoorOrientation::kAlongX;
  std::vector<int> space_indices;   // spaces it joins (indices into Environment::spaces); 1 = exterior door
  DoorStatus status = DoorStatus::kUnspecified;  // the thesis's optional <status> element
  bool implicit = false;            // PORTAL of type IMPLICIT (an opening without a door leaf)
};

struct Environment {
  std::string building_id;
  std::string name;
  std::string building_type;  // <building_type><main_type>
  double metres_per_pixel = 0.05;
  double flip_v = 0.0;        // pixel row that maps to y = 0 (see the frame note above)
  // Optional package extension <wall_thickness> (metres) written by the world generator; rendering uses it
  // unless told otherwise.
  std::optional<double> wall_thickness;
  std::vector<Space> spaces;
  std::vector<Door> doors;
  // What the reader repaired rather than refused (docs/file_formats.md), one sentence each; tools print them as
  // warnings (printRepairs).
  std::vector<std::string> repairs;

  // All WALL segments of all spaces (walls shared by two spaces appear twice).
  std::vector<LineSegment> walls() const;
  // Index of the door with this XML id or this 1-based number (given as text); -1 when there is none.
  int findDoor(const std::string& id_or_number) const;
  // Axis-aligned bounds of all outlines and segments, metres: {min, max}.
  std::pair<common::Point2, common::Point2> bounds() const;
};

// Reads an environment XML. Throws InputError naming the file and the problem (malformed XML, missing or
// non-positive scale, bad numbers, self-intersecting outline, a portal that lies on no wall, ...).
Environment loadEnvironment(const std::string& path);
// Same, from text; `source_name` names the input in error messages.
Environment parseEnvironment(const std::string& xml_text, const std::string& source_name);

// Fills Environment::doors from the spaces' PORTAL segments and portal links: numbering, centre, the wall
// each door sits in (orientation), joined spaces and status. Called by the reader; builders of environments
// (the world generator) call it too. Throws InputError (naming `source_name`) when a portal lies on no wall.
void deriveDoors(Environment* environment, const std::string& source_name);

// Writes each of `environment.repairs` as "warning: <source>: <repair>" lines to `out`.
void printRepairs(const Environment& environment, const std::string& source, std::ostream& out);

// Writes the environment in the same schema (door status as <status> on its PORTAL segments).
std::string environmentToXml(const Environment& environment);
void saveEnvironment(const Environment& environment, const std::string& path);

// Door indices named by `spec`: "" = none, "all" = every door joining two spaces, "closable" = the closable doors, else
// comma-separated door numbers or portal ids. Throws InputError (naming `source_name`) for a door that does not exist.
std::set<int> parseDoorSelection(const Environment& environment, const std::string& spec,
                                 const std::string& source_name);

// Doors whose only other side is a single space that has exactly this one door (docs/method.md#batch-analysis):
// closing it hides exactly that room. Returns door indices.
std::vector<int> closableDoors(const Environment& environment);

// Index of the space behind a closable door (the space whose only door it is), or -1.
int roomBehindDoor(const Environment& environment, int door_index);

}  // namespace hidden_rooms::world
