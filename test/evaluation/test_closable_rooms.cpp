// Closed-door cases from a map of one's own (closable_rooms.h): on the rendering of a corridor with two offices,
// each joined to it by one door, both offices are found closable, hidden, and given a closed door where the true
// door is; the case scores a prediction like the rendered case does.
#include <algorithm>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/evaluation/closable_rooms.h"
#include "hidden_rooms/segmentation/room_graph.h"
#include "test_util.h"

namespace hidden_rooms::evaluation {
namespace {

struct Floor {
  world::Environment environment;
  world::RenderedEnvironment rendered;
  segmentation::SegmentedFloor floor;
};

Floor corridorFloor() {
  Floor f;
  f.environment = world::parseEnvironment(testing::corridorWithTwoRoomsXml(), "corridor.xml");
  f.rendered = world::renderEnvironment(f.environment, {});  // every door open
  f.floor = segmentation::segmentFloor(f.rendered.map, {}, {}, {});
  return f;
}

TEST(ClosableRooms, TheOfficesBehindOneDoorAreHiddenWithAClosedDoorWhereTheTrueDoorIs) {
  const Floor f = corridorFloor();
  const ClosableRoomOptions options;
  const std::vector<int> labels = closableRooms(f.floor, options);
  ASSERT_EQ(labels.size(), 2u) << "room_a and room_b; the corridor has two doors";
  EXPECT_GT(f.floor.rooms[labels[0] - 1].area, f.floor.rooms[labels[1] - 1].area) << "largest first";
  const world::HiddenRoomsCase hidden = hideRooms(f.rendered.map, f.floor, labels, options);
  ASSERT_EQ(hidden.closed_doors.doors.size(), 2u);
  const common::OccupancyGrid& map = f.rendered.map;
  for (size_t k = 0; k < labels.size(); ++k) {
    const common::MapDoor& door = hidden.closed_doors.doors[k];
    EXPECT_EQ(door.id, static_cast<int>(k + 1));
    // The true room: the space it lies in, nearly all of it.
    const cv::Mat1b truth = hidden.true_rooms == k + 1;
    const common::Point2 centroid = map.toImage(f.floor.rooms[labels[k] - 1].centroid);
    const int true_space = f.rendered.space_labels(static_cast<int>(centroid.y()), static_cast<int>(centroid.x()));
    const cv::Mat1b true_space_cells = f.rendered.space_labels == true_space;
    const double overlap = cv::countNonZero(truth & true_space_cells);
    EXPECT_GT(overlap / cv::countNonZero(true_space_cells | truth), 0.9) << "room " << k + 1;
    // Hidden: no free cell of the room is left, and none of its far walls.
    EXPECT_EQ(cv::countNonZero(truth & (hidden.map.cells == common::OccupancyGrid::kFree)), 0);
    // The door: across the true door, along the corridor's wall (x), about its width.
    double nearest = 1e9;
    for (const world::Door& true_door : f.environment.doors)
      nearest = std::min(nearest, (true_door.centre - door.position).norm());
    EXPECT_LT(nearest, 0.3) << "door " << door.id;
    EXPECT_EQ(door.orientation, common::DoorOrientation::kAlongX);
    EXPECT_GT(door.width, 0.5);
    EXPECT_LT(door.width, 1.5);
  }
  // The corridor stays as it was, but in the doorways.
  cv::Mat1b changed = (f.rendered.space_labels == 1) & (hidden.map.cells != map.cells);
  for (const common::MapDoor& door : hidden.closed_doors.doors) {
    const common::Point2 at = map.toImage(door.position);
    cv::circle(changed, cv::Point(static_cast<int>(at.x()), static_cast<int>(at.y())),
               static_cast<int>(0.75 / map.resolution), cv::Scalar(0), cv::FILLED);
  }
  EXPECT_EQ(cv::countNonZero(changed), 0);
}

TEST(ClosableRooms, OnlyRoomsOneNarrowDoorwayJoinsAreClosable) {
  const Floor f = corridorFloor();
  ClosableRoomOptions options;
  options.max_door_width = 0.3;  // narrower than the doors
  EXPECT_TRUE(closableRooms(f.floor, options).empty());
  options = ClosableRoomOptions();
  options.min_area = 20.0;  // room_a is 16 m2, room_b 24 m2
  EXPECT_EQ(closableRooms(f.floor, options).size(), 1u);
  options = ClosableRoomOptions();
  options.max_rooms = 1;
  EXPECT_EQ(closableRooms(f.floor, options).size(), 1u);
  // Of two rooms joined only to each other (room_a already hidden), neither lies behind the other's door.
  common::OccupancyGrid two_rooms;
  common::DoorsFile doors;
  cv::Mat1w truth;
  testing::syntheticHiddenRoomA(&two_rooms, &doors, &truth);
  EXPECT_TRUE(closableRooms(segmentation::segmentFloor(two_rooms, {}, {}, {}), ClosableRoomOptions()).empty());
  // The corridor (the segment on most of the corridor space's cells) is not closable, nor a label that is no room,
  // nor a room twice.
  const ClosableRoomOptions defaults;
  const std::vector<int> labels = closableRooms(f.floor, defaults);
  std::vector<int> corridor_cells(f.floor.rooms.size() + 1, 0);
  for (int row = 0; row < f.floor.labels.rows; ++row)
    for (int col = 0; col < f.floor.labels.cols; ++col)
      if (f.rendered.space_labels(row, col) == 1) ++corridor_cells[f.floor.labels(row, col)];
  const int corridor = static_cast<int>(std::max_element(corridor_cells.begin() + 1, corridor_cells.end()) -
                                        corridor_cells.begin());
  ASSERT_EQ(std::count(labels.begin(), labels.end(), corridor), 0);
  EXPECT_THROW(hideRooms(f.rendered.map, f.floor, {corridor}, defaults), common::InputError);
  EXPECT_THROW(hideRooms(f.rendered.map, f.floor, {99}, defaults), common::InputError);
  EXPECT_THROW(hideRooms(f.rendered.map, f.floor, {labels[0], labels[0]}, defaults), common::InputError);
}

}  // namespace
}  // namespace hidden_rooms::evaluation
