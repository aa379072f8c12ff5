#include <gtest/gtest.h>

#include <sstream>
#include <tinyxml2.h>

#include <cmath>
#include <set>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/world/environment.h"
#include "test_util.h"

namespace hidden_rooms::world {
namespace {

using testing::corridorWithTwoRoomsXml;

// Counts straight from the XML, independently of the model: spaces under floor/spaces and distinct PORTAL ids.
std::pair<size_t, size_t> countSpacesAndPortals(const std::string& path) {
  tinyxml2::XMLDocument document;
  EXPECT_EQ(document.LoadFile(path.c_str()), tinyxml2::XML_SUCCESS);
  size_t spaces = 0;
  std::set<std::string> portals;
  const auto* list = document.RootElement()->FirstChildElement("floor")->FirstChildElement("spaces");
  for (const auto* space = list->FirstChildElement("space"); space; space = space->NextSiblingElement("space")) {
    ++spaces;
    const auto* representation = space->FirstChildElement("space_representation");
    if (representation == nullptr) continue;
    for (const auto* line = representation->FirstChildElement("linesegment"); line;
         line = line->NextSiblingElement("linesegment"))
      if (std::string(line->FirstChildElement("class")->GetText()) == "PORTAL") portals.insert(line->Attribute("id"));
  }
  return {spaces, portals.size()};
}

void expectSameGeometry(const Environment& a, const Environment& b) {
  EXPECT_NEAR(a.metres_per_pixel, b.metres_per_pixel, 1e-12);
  ASSERT_EQ(a.spaces.size(), b.spaces.size());
  for (size_t s = 0; s < a.spaces.size(); ++s) {
    const Space& x = a.spaces[s];
    const Space& y = b.spaces[s];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.label, y.label);
    EXPECT_EQ(x.type, y.type);
    ASSERT_EQ(x.outline.size(), y.outline.size()) << x.id;
    for (size_t i = 0; i < x.outline.size(); ++i) EXPECT_LT((x.outline[i] - y.outline[i]).norm(), 1e-9);
    ASSERT_EQ(x.segments.size(), y.segments.size());
    for (size_t i = 0; i < x.segments.size(); ++i) {
      EXPECT_EQ(x.segments[i].id, y.segments[i].id);
      EXPECT_EQ(x.segments[i].segment_class, y.segments[i].segment_class);
      EXPECT_EQ(x.segments[i].type, y.segments[i].type);
      EXPECT_LT((x.segments[i].a - y.segments[i].a).norm(), 1e-9);
      EXPECT_LT((x.segments[i].b - y.segments[i].b).norm(), 1e-9);
    }
    ASSERT_EQ(x.portals.size(), y.portals.size());
    for (size_t i = 0; i < x.portals.size(); ++i) {
      EXPECT_EQ(x.portals[i].segment_id, y.portals[i].segment_id);
      EXPECT_EQ(x.portals[i].target_ids, y.portals[i].target_ids);
    }
  }
  ASSERT_EQ(a.doors.size(), b.doors.size());
  for (size_t d = 0; d < a.doors.size(); ++d) {
    EXPECT_EQ(a.doors[d].id, b.doors[d].id);
    EXPECT_EQ(a.doors[d].number, b.doors[d].number);
    EXPECT_EQ(a.doors[d].status, b.doors[d].status);
    EXPECT_EQ(a.doors[d].orientation, b.doors[d].orientation);
    EXPECT_EQ(a.doors[d].space_indices, b.doors[d].space_indices);
    EXPECT_LT((a.doors[d].centre - b.doors[d].centre).norm(), 1e-9);
  }
}

TEST(Environment, EverySharedEnvironmentParsesWithItsSpacesAndDoors) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const auto files = testing::sharedEnvironmentFiles();
  ASSERT_EQ(files.size(), 63u);
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    Environment environment;
    ASSERT_NO_THROW(environment = loadEnvironment(path));
    const auto [spaces, portals] = countSpacesAndPortals(path);
    EXPECT_EQ(environment.spaces.size(), spaces);
    EXPECT_EQ(environment.doors.size(), portals);
    EXPECT_GT(environment.metres_per_pixel, 0.01);
    EXPECT_LT(environment.metres_per_pixel, 0.5);
    for (const Door& door : environment.doors) EXPECT_FALSE(door.space_indices.empty()) << door.id;
    EXPECT_FALSE(closableDoors(environment).empty());
    const auto [low, high] = environment.bounds();
    EXPECT_GE(low.y(), -1e-9);  // y flipped so that the file's pixels map to y >= 0
    EXPECT_GT((high - low).minCoeff(), 5.0);
  }
}

TEST(Environment, RoundTripOfEverySharedEnvironmentIsLossless) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  for (const std::string& path : testing::sharedEnvironmentFiles()) {
    SCOPED_TRACE(path);
    const Environment original = loadEnvironment(path);
    const std::string xml = environmentToXml(original);
    const Environment again = parseEnvironment(xml, "round trip");
    expectSameGeometry(original, again);
    EXPECT_EQ(environmentToXml(again), xml);  // a second round trip changes nothing
  }
}

TEST(Environment, ConvertsPixelsToMetresWithYUp) {
  const Environment environment = parseEnvironment(corridorWithTwoRoomsXml(), "synthetic");
  EXPECT_DOUBLE_EQ(environment.metres_per_pixel, 0.05);
  ASSERT_EQ(environment.spaces.size(), 3u);
  ASSERT_EQ(environment.doors.size(), 2u);
  // Pixel (40, 40) with the largest pixel y = 120: x = 2 m, y = (120 - 40) * 0.05 = 4 m.
  const Door& door_a = environment.doors[environment.findDoor("door_a")];
  EXPECT_LT((door_a.centre - common::Point2(2.0, 4.0)).norm(), 1e-12);
  EXPECT_EQ(door_a.orientation, common::DoorOrientation::kAlongX);
  EXPECT_NEAR(door_a.wall_angle, 0.0, 1e-12);
  EXPECT_EQ(door_a.space_indices.size(), 2u);
  EXPECT_EQ(environment.findDoor("2"), environment.findDoor("door_b"));
  EXPECT_EQ(environment.findDoor("7"), -1);
  EXPECT_NEAR(common::area(environment.spaces[0].outline), 10.0 * 2.0, 1e-9);
}

TEST(Environment, FindsClosableDoorsAndTheRoomsBehindThem) {
  const Environment environment = parseEnvironment(corridorWithTwoRoomsXml(), "synthetic");
  EXPECT_EQ(closableDoors(environment), (std::vector<int>{0, 1}));
  EXPECT_EQ(environment.spaces[roomBehindDoor(environment, environment.findDoor("door_a"))].id, "room_a");
  EXPECT_EQ(environment.spaces[roomBehindDoor(environment, environment.findDoor("door_b"))].id, "room_b");
}

TEST(Environment, ReadsAndWritesTheThesisDoorStatus) {
  const Environment closed = parseEnvironment(corridorWithTwoRoomsXml("CLOSED"), "synthetic");
  EXPECT_EQ(closed.doors[closed.findDoor("door_a")].status, DoorStatus::kClosed);
  EXPECT_EQ(closed.doors[closed.findDoor("door_b")].status, DoorStatus::kUnspecified);
  const Environment again = parseEnvironment(environmentToXml(closed), "round trip");
  EXPECT_EQ(again.doors[again.findDoor("door_a")].status, DoorStatus::kClosed);
  EXPECT_THROW(parseEnvironment(corridorWithTwoRoomsXml("AJAR"), "synthetic"), common::InputError);
}

TEST(Environment, SelectsDoorsByNumberIdOrAll) {
  const Environment environment = parseEnvironment(corridorWithTwoRoomsXml(), "synthetic");
  EXPECT_EQ(parseDoorSelection(environment, "", "x"), (std::set<int>{}));
  EXPECT_EQ(parseDoorSelection(environment, "all", "x"), (std::set<int>{0, 1}));
  EXPECT_EQ(parseDoorSelection(environment, "2, door_a", "x"), (std::set<int>{0, 1}));
  EXPECT_THROW(parseDoorSelection(environment, "3", "x"), common::InputError);
  for (const char* spec : {"1,,2", ",1", "1,", " , "})  // an empty item: a typo, not "no door"
    EXPECT_NE(testing::inputErrorMessage([&] { parseDoorSelection(environment, spec, "--closed"); })
                  .find("has an empty door number"),
              std::string::npos)
        << spec;
}

// Bad input: each error names the input and the problem.
void expectError(const std::string& xml, const std::string& expected_problem) {
  try {
    parseEnvironment(xml, "bad.xml");
    FAIL() << "no error for: " << expected_problem;
  } catch (const common::InputError& error) {
    EXPECT_EQ(error.source(), "bad.xml");
    EXPECT_NE(std::string(error.what()).find(expected_problem), std::string::npos) << error.what();
  }
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(Environment, RejectsMalformedXml) {
  expectError("<building><scale>", "malformed XML");
  expectError("", "malformed XML");
  expectError("<house/>", "root element must be <building>");
}

TEST(Environment, RejectsAMissingOrBadScale) {
  const std::string xml = corridorWithTwoRoomsXml();
  const auto begin = xml.find("<scale>");
  const auto end = xml.find("</scale>") + std::string("</scale>").size();
  expectError(std::string(xml).erase(begin, end - begin), "missing <scale>");
  expectError(replaced(xml, "<value>20</value>", "<value>-20</value>"), "positive distances");
  expectError(replaced(xml, "<value>20</value>", "<value>twenty</value>"), "not a finite number");
  expectError(replaced(xml, "<um>cm</um>", "<um>furlong</um>"), "unknown length unit");
}

TEST(Environment, RejectsASelfIntersectingOutline) {
  // Room A's outline as a bow tie: (0,40) (80,120) (80,40) (0,120) crosses itself in the middle.
  const std::string xml = replaced(
      corridorWithTwoRoomsXml(),
      "<point x=\"0\" y=\"40\"/><point x=\"80\" y=\"40\"/><point x=\"80\" y=\"120\"/><point x=\"0\" y=\"120\"/>",
      "<point x=\"0\" y=\"40\"/><point x=\"80\" y=\"120\"/><point x=\"80\" y=\"40\"/><point x=\"0\" y=\"120\"/>");
  expectError(xml, "outline of space 'room_a'");
  expectError(xml, "crosses itself");
}

TEST(Environment, RejectsAnOutlineThatRunsOverItself) {
  // The corridor's outline loops twice around its right half: no edge crosses another, but drawn even-odd that
  // half is empty (the degenerate corridor lost 64 % of its free cells to this).
  const std::string corridor_outline =
      "<point x=\"0\" y=\"0\"/><point x=\"0\" y=\"40\"/><point x=\"200\" y=\"40\"/><point x=\"200\" y=\"0\"/>";
  const std::string looped = replaced(
      corridorWithTwoRoomsXml(), corridor_outline,
      "<point x=\"0\" y=\"0\"/><point x=\"0\" y=\"40\"/><point x=\"200\" y=\"40\"/><point x=\"200\" y=\"0\"/>"
      "<point x=\"100\" y=\"0\"/><point x=\"100\" y=\"40\"/><point x=\"200\" y=\"40\"/><point x=\"200\" y=\"0\"/>");
  expectError(looped, "outline of space 'corridor' (line 1) runs over itself: it encloses 30 m2 but a drawing of it "
                      "fills 10");
  expectError(replaced(corridorWithTwoRoomsXml(), corridor_outline, corridor_outline + corridor_outline),
              "encloses 40 m2 but a drawing of it fills 0.");  // traced twice: only the edges are drawn
}

TEST(Environment, RepairsAreWarnedNotSilent) {
  // A copy of door_a's PORTAL on room_a's west wall, 2.8 m from the first; room_b's outline of two points.
  const std::string xml = replaced(
      corridorWithTwoRoomsXml("", "<linesegment id=\"door_a\"><point x=\"0\" y=\"80\"/><point x=\"0\" y=\"80\"/>"
                                  "<class>PORTAL</class></linesegment>"),
      "<point x=\"80\" y=\"40\"/><point x=\"200\" y=\"40\"/><point x=\"200\" y=\"120\"/><point x=\"80\" y=\"120\"/>",
      "<point x=\"80\" y=\"40\"/><point x=\"200\" y=\"40\"/>");
  const Environment environment = parseEnvironment(xml, "synthetic");
  ASSERT_EQ(environment.repairs.size(), 2u);
  EXPECT_EQ(environment.repairs[0], "the outline of space 'room_b' (line 1) has fewer than 3 distinct vertices; the "
                                    "space has no floor");
  EXPECT_EQ(environment.repairs[1], "portal 'door_a' appears at two places 2.83 m apart; the door is placed at its "
                                    "first appearance");
  EXPECT_LT((environment.doors[0].centre - common::Point2(2.0, 4.0)).norm(), 1e-9);  // the first copy
  std::ostringstream printed;
  printRepairs(environment, "plan.xml", printed);
  EXPECT_EQ(printed.str().find("warning: plan.xml: the outline of space 'room_b'"), 0u);
  EXPECT_TRUE(parseEnvironment(corridorWithTwoRoomsXml(), "synthetic").repairs.empty());
}

TEST(Environment, RejectsADoorOnNoWall) {
  const std::string portal =
      "<linesegment id=\"floating\"><point x=\"40\" y=\"80\"/><point x=\"40\" y=\"80\"/><class>PORTAL</class>"
      "</linesegment>";
  expectError(corridorWithTwoRoomsXml("", portal), "portal 'floating' at pixel (40, 80) lies on no wall");
}

TEST(Environment, RejectsBadNumbersAndMissingIds) {
  expectError(replaced(corridorWithTwoRoomsXml(), "<point x=\"0\" y=\"0\"/>", "<point x=\"nan\" y=\"0\"/>"),
              "not a finite number");
  expectError(replaced(corridorWithTwoRoomsXml(), "<point x=\"0\" y=\"0\"/>", "<point x=\"0\"/>"), "lacks x or y");
  expectError(replaced(corridorWithTwoRoomsXml(), "<space id=\"room_b\">", "<space id=\"room_a\">"), "used twice");
  expectError(replaced(corridorWithTwoRoomsXml(), "<class>WALL</class>", "<class>WINDOW</class>"), "WALL or PORTAL");
}

TEST(Environment, LoadNamesAMissingFile) {
  try {
    loadEnvironment("/nonexistent/world.xml");
    FAIL();
  } catch (const common::InputError& error) {
    EXPECT_EQ(std::string(error.what()), "/nonexistent/world.xml: cannot open environment file");
  }
}

}  // namespace
}  // namespace hidden_rooms::world
