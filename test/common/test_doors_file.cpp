#include <gtest/gtest.h>

#include <filesystem>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "test_util.h"

namespace hidden_rooms::common {
namespace {

TEST(DoorsFile, ReadsEveryBenchmarkDoorsFileInsideItsMap) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  int files = 0;
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(testing::sharedDir() + "/data/closed_door_benchmark")) {
    if (entry.path().filename() != "doors.yaml") continue;
    SCOPED_TRACE(entry.path().string());
    const DoorsFile doors = loadDoors(entry.path().string());
    const OccupancyGrid map = loadMap((entry.path().parent_path() / "map.yaml").string());
    EXPECT_EQ(doors.frame, "map");
    // The case folder is named after its number of closed doors: NN_doors.
    EXPECT_EQ(static_cast<int>(doors.doors.size()), std::stoi(entry.path().parent_path().filename().string()));
    for (const MapDoor& door : doors.doors) {
      int col = 0, row = 0;
      EXPECT_TRUE(map.cellOf(door.position, &col, &row)) << "door " << door.id;
      EXPECT_GT(door.width, 0.3);
    }
    ++files;
  }
  EXPECT_GE(files, 40);
}

TEST(DoorsFile, SaveThenLoadRoundTrips) {
  DoorsFile doors;
  doors.doors.push_back({3, Point2(1.5, -2.25), 0.9, DoorOrientation::kAlongY});
  doors.doors.push_back({7, Point2(0.0, 4.0), 1.2, DoorOrientation::kAlongX});
  const std::string path = testing::makeTempDir("doors_round_trip") + "/doors.yaml";
  saveDoors(doors, path);
  const DoorsFile loaded = loadDoors(path);
  ASSERT_EQ(loaded.doors.size(), 2u);
  EXPECT_EQ(loaded.doors[0].id, 3);
  EXPECT_EQ(loaded.doors[0].orientation, DoorOrientation::kAlongY);
  EXPECT_LT((loaded.doors[0].position - Point2(1.5, -2.25)).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(loaded.doors[1].width, 1.2);
  EXPECT_FALSE(loaded.doors[0].map_from_world);
  doors.doors[1].map_from_world = Pose2{0.5, -1.25, 0.03};
  saveDoors(doors, path);
  const DoorsFile with_transform = loadDoors(path);
  ASSERT_TRUE(with_transform.doors[1].map_from_world);
  EXPECT_DOUBLE_EQ(with_transform.doors[1].map_from_world->y, -1.25);
  EXPECT_DOUBLE_EQ(with_transform.doors[1].map_from_world->yaw, 0.03);
  EXPECT_FALSE(with_transform.doors[0].map_from_world);
  saveDoors(DoorsFile(), path);
  EXPECT_TRUE(loadDoors(path).doors.empty());
}

TEST(DoorsFile, IgnoresUnknownKeys) {
  const DoorsFile doors = parseDoors(
      "frame: map\nresolution: 0.05\ndoors:\n- id: 1\n  pixel: [3, 4]\n  position: [1, 2]\n  width: 1\n"
      "  orientation: V\n  colour: red\n",
      "doors.yaml");
  ASSERT_EQ(doors.doors.size(), 1u);
  EXPECT_EQ(doors.doors[0].orientation, DoorOrientation::kAlongY);
}

void expectError(const std::string& yaml, const std::string& expected_problem) {
  try {
    parseDoors(yaml, "doors.yaml");
    FAIL() << "no error for: " << expected_problem;
  } catch (const InputError& error) {
    EXPECT_EQ(error.source(), "doors.yaml");
    EXPECT_NE(std::string(error.what()).find(expected_problem), std::string::npos) << error.what();
  }
}

TEST(DoorsFile, BadDoorsFilesGiveClearErrors) {
  const std::string door = "- {id: 1, position: [1, 2], width: 0.9, orientation: O}\n";
  expectError("frame: map\ndoors: [\n", "malformed YAML");
  expectError("- 1\n- 2\n", "mapping");
  expectError("frame: map\n", "missing 'doors'");
  expectError("doors: 5\n", "must be a list");
  expectError("doors:\n- {position: [1, 2], width: 0.9, orientation: O}\n", "has no 'id'");
  expectError("doors:\n- {id: 1, width: 0.9, orientation: O}\n", "position: [x, y]");
  expectError("doors:\n- {id: 1, position: [.nan, 2], width: 0.9, orientation: O}\n", "position[0] is not finite");
  expectError("doors:\n- {id: 1, position: [a, 2], width: 0.9, orientation: O}\n", "not a number");
  expectError("doors:\n- {id: 1, position: [1, 2], width: -1, orientation: O}\n", "width must be positive");
  expectError("doors:\n- {id: 1, position: [1, 2], width: 0.9, orientation: X}\n", "(O or V)");
  expectError("doors:\n" + door + door, "used twice");
  expectError("doors:\n- {id: 1, position: [1, 2], width: 0.9, orientation: O, map_from_world: [1, 2]}\n",
              "map_from_world must be [x, y, yaw]");
  expectError("doors:\n- {id: 1, position: [1, 2], width: 0.9, orientation: O, map_from_world: [1, 2, .inf]}\n",
              "map_from_world[2] is not finite");
  EXPECT_THROW(loadDoors("/nonexistent/doors.yaml"), InputError);
  std::string crowd = "doors:\n";
  for (int id = 1; id <= 501; ++id)
    crowd += "- {id: " + std::to_string(id) + ", position: [1, 2], width: 0.9, orientation: O}\n";
  expectError(crowd, "the number of doors is 501, more than the limit of 500");
}

}  // namespace
}  // namespace hidden_rooms::common
