#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/evaluation/evaluation.h"
#include "hidden_rooms/prediction/default_predictor.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/prediction/room_network.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "test_util.h"

namespace hidden_rooms::prediction {
namespace {

// A synthetic floor: a corridor with three adjacent hidden rooms above it (their shared walls unseen; a known
// service corridor beyond them) and, below it, an explored room, a hidden room and an explored room.
// Drawn in pixels (0 unknown, 1 free, 2 wall), optionally rotated by `degrees` about the image centre.
struct Synthetic {
  PredictionRequest request;
  cv::Mat1w truth;
};

Synthetic syntheticFloor(double degrees) {
  const cv::Size size(420, 300);
  cv::Mat1b states(size, 0);
  cv::Mat1w labels(size, 0);
  auto fill = [&](cv::Mat& image, const cv::Rect& r, int value) { image(r).setTo(value); };
  // Walls first, free space on top.
  fill(states, cv::Rect(37, 2, 326, 18), 2);     // around the service corridor
  fill(states, cv::Rect(37, 97, 326, 166), 2);   // around the corridor and the lower rooms
  fill(states, cv::Rect(40, 5, 320, 12), 1);     // service corridor
  fill(states, cv::Rect(40, 100, 320, 40), 1);   // main corridor
  fill(states, cv::Rect(40, 143, 100, 117), 1);  // explored room below, left
  fill(states, cv::Rect(246, 143, 114, 117), 1); // explored room below, right
  // Hidden rooms (unknown in the map), their true extents.
  const std::vector<cv::Rect> hidden{cv::Rect(40, 20, 100, 77), cv::Rect(143, 20, 100, 77),
                                     cv::Rect(246, 20, 114, 77), cv::Rect(143, 143, 100, 117)};
  for (size_t k = 0; k < hidden.size(); ++k) fill(labels, hidden[k], static_cast<int>(k + 1));
  fill(states, hidden[3], 0);
  // The walls between the hidden rooms above were never seen: unknown.
  fill(states, cv::Rect(140, 20, 3, 77), 0);
  fill(states, cv::Rect(243, 20, 3, 77), 0);
  // Door centres (pixels, on the wall rows) and orientations.
  std::vector<cv::Point2d> doors{{90, 98.5}, {193, 98.5}, {303, 98.5}, {193, 141.5}};

  cv::Mat1b rotated_states = states;
  cv::Mat1w rotated_labels = labels;
  if (degrees != 0.0) {
    const cv::Mat m = cv::getRotationMatrix2D(cv::Point2f(size.width / 2.0f, size.height / 2.0f), degrees, 1.0);
    cv::warpAffine(states, rotated_states, m, size, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
    cv::warpAffine(labels, rotated_labels, m, size, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
    const cv::Matx23d a(m);
    for (cv::Point2d& p : doors)
      p = cv::Point2d(a(0, 0) * p.x + a(0, 1) * p.y + a(0, 2), a(1, 0) * p.x + a(1, 1) * p.y + a(1, 2));
  }
  Synthetic result;
  common::OccupancyGrid& map = result.request.map;
  map.resolution = 0.05;
  map.cells = cv::Mat_<int8_t>(size, common::OccupancyGrid::kUnknown);
  for (int r = 0; r < size.height; ++r)
    for (int c = 0; c < size.width; ++c) {
      if (rotated_states(r, c) == 1) map.cells(r, c) = common::OccupancyGrid::kFree;
      if (rotated_states(r, c) == 2) map.cells(r, c) = common::OccupancyGrid::kOccupied;
    }
  rotated_labels.setTo(0, map.cells != common::OccupancyGrid::kUnknown);
  result.truth = rotated_labels;
  for (size_t k = 0; k < doors.size(); ++k) {
    common::MapDoor door;
    door.id = static_cast<int>(k + 1);
    door.width = 1.0;
    door.orientation = common::DoorOrientation::kAlongX;
    // Image point (column, row) -> map frame (y up, origin at the lower-left corner).
    door.position = common::Point2(doors[k].x * map.resolution, (size.height - doors[k].y) * map.resolution);
    result.request.doors.doors.push_back(door);
  }
  return result;
}

evaluation::RoomScores scoreOf(const Synthetic& s, const PredictionResult& result) {
  return evaluation::scoreRooms(roomLabels(s.request.map, s.request.doors, result.rooms), s.truth,
                                static_cast<int>(s.request.doors.doors.size()));
}

TEST(DefaultPredictor, RecoversAdjacentRoomsBehindClosedDoors) {
  const Synthetic s = syntheticFloor(0.0);
  const PredictionResult result = makeRoomPredictor("default")->predict(s.request);
  ASSERT_EQ(result.rooms.size(), 4u);
  const evaluation::RoomScores scores = scoreOf(s, result);
  for (size_t k = 0; k < scores.iou.size(); ++k) EXPECT_GT(scores.iou[k], 0.9) << "door " << k + 1;
}

TEST(DefaultPredictor, RecoversRoomsOfARotatedMap) {
  const Synthetic s = syntheticFloor(20.0);
  EXPECT_NEAR(std::abs(dominantWallAngle(s.request.map)) * 180.0 / CV_PI, 20.0, 1.5);
  const PredictionResult result = makeRoomPredictor("default")->predict(s.request);
  const evaluation::RoomScores scores = scoreOf(s, result);
  EXPECT_GT(scores.mean_iou, 0.8);
  for (size_t k = 0; k < scores.iou.size(); ++k) EXPECT_GT(scores.iou[k], 0.7) << "door " << k + 1;
}

TEST(DefaultPredictor, MeasuresDepthBehindARaggedWall) {
  // A SLAM map's wall, turned back by the dominant angle, is ragged: away from the door its pixels reach a row
  // or two past the door's first unknown row (here row 96 at door 1, in 3 of 4 columns). The depth is measured
  // behind them, not stopped on them.
  Synthetic s = syntheticFloor(0.0);
  for (int col = 40; col < 140; ++col)
    if ((col < 78 || col > 102) && col % 4 != 0) s.request.map.cells(96, col) = common::OccupancyGrid::kOccupied;
  s.truth.setTo(0, s.request.map.cells != common::OccupancyGrid::kUnknown);
  s.request.parameters = {{"default_network", 0}, {"default_grown_area_ratio", 1e9}};  // the rectangles only
  const PredictionResult result = makeRoomPredictor("default")->predict(s.request);
  EXPECT_NEAR(result.rooms[0].terms.at("depth"), 76 * 0.05, 0.1);
  EXPECT_GT(scoreOf(s, result).iou[0], 0.8);
}

TEST(DefaultPredictor, IsDeterministic) {
  const Synthetic s = syntheticFloor(7.0);
  const auto predictor = makeRoomPredictor("default");
  const PredictionResult a = predictor->predict(s.request), b = predictor->predict(s.request);
  ASSERT_EQ(a.rooms.size(), b.rooms.size());
  for (size_t k = 0; k < a.rooms.size(); ++k) EXPECT_EQ(cv::countNonZero(a.rooms[k].mask != b.rooms[k].mask), 0);
}

TEST(DefaultPredictor, ReportsADoorOutsideTheMapAndPredictsTheOthers) {
  Synthetic s = syntheticFloor(0.0);
  common::MapDoor outside;
  outside.id = 9;
  outside.position = common::Point2(-20.0, -20.0);
  s.request.doors.doors.push_back(outside);
  const PredictionResult result = makeRoomPredictor("default")->predict(s.request);
  ASSERT_EQ(result.rooms.size(), 5u);
  EXPECT_FALSE(result.rooms[4].placed);
  EXPECT_EQ(result.rooms[4].door_id, 9);
  EXPECT_FALSE(result.rooms[4].problem.empty());
  for (size_t k = 0; k < 4; ++k) EXPECT_TRUE(result.rooms[k].placed) << result.rooms[k].problem;
}

TEST(DefaultPredictor, NeverPredictsKnownCells) {
  for (double degrees : {0.0, 20.0}) {
    const Synthetic s = syntheticFloor(degrees);
    const PredictionResult result = makeRoomPredictor("default")->predict(s.request);
    for (const RoomPrediction& room : result.rooms) {
      EXPECT_EQ(cv::countNonZero(room.mask & (s.request.map.cells != common::OccupancyGrid::kUnknown)), 0);
      EXPECT_NEAR(room.area, cv::countNonZero(room.mask) * 0.0025, 1e-9);
    }
  }
}

TEST(DefaultPredictor, RejectsBadParameters) {
  const Synthetic s = syntheticFloor(0.0);
  PredictionRequest request = s.request;
  request.parameters["default_bounded_fraction"] = 2.0;
  EXPECT_THROW(makeRoomPredictor("default")->predict(request), common::InputError);
}

// Two hidden rooms above a corridor, their shared wall unseen; a pillar in the corridor marks where that wall
// meets the corridor's wall, and the doors sit off-centre, so that cutting between the doors misplaces the wall.
Synthetic corridorWithPillar() {
  const cv::Size size(300, 160);
  cv::Mat1b states(size, 0);
  states(cv::Rect(17, 2, 266, 18)).setTo(2);   // around the service corridor above the rooms
  states(cv::Rect(17, 97, 266, 46)).setTo(2);  // around the main corridor
  states(cv::Rect(20, 5, 260, 12)).setTo(1);
  states(cv::Rect(20, 100, 260, 40)).setTo(1);
  states(cv::Rect(148, 100, 7, 10)).setTo(2);  // the pillar, 0.5 m into the corridor
  Synthetic result;
  result.truth = cv::Mat1w::zeros(size);
  result.truth(cv::Rect(20, 20, 130, 77)).setTo(1);
  result.truth(cv::Rect(153, 20, 127, 77)).setTo(2);
  common::OccupancyGrid& map = result.request.map;
  map.resolution = 0.05;
  map.cells = cv::Mat_<int8_t>(size, common::OccupancyGrid::kUnknown);
  map.cells.setTo(common::OccupancyGrid::kFree, states == 1);
  map.cells.setTo(common::OccupancyGrid::kOccupied, states == 2);
  for (const auto& [id, column] : {std::pair<int, double>{1, 40.0}, {2, 175.0}}) {
    common::MapDoor door;
    door.id = id;
    door.width = 1.0;
    door.orientation = common::DoorOrientation::kAlongX;
    door.position = common::Point2(column * map.resolution, (size.height - 98.5) * map.resolution);
    result.request.doors.doors.push_back(door);
  }
  return result;
}

TEST(DefaultPredictor, WallStubsEndTheRoomsAlongTheirWall) {
  Synthetic s = corridorWithPillar();
  s.request.parameters["default_network"] = 0;  // the area rule, with:
  s.request.parameters["default_grown_area_ratio"] = 1000.0;  // the wall-fitted rectangles only
  const evaluation::RoomScores with_stubs = scoreOf(s, makeRoomPredictor("default")->predict(s.request));
  for (size_t k = 0; k < with_stubs.iou.size(); ++k) EXPECT_GT(with_stubs.iou[k], 0.9) << "door " << k + 1;
  s.request.parameters["default_stub_length"] = 0.0;  // stubs ignored: cut halfway between the doors
  EXPECT_LT(scoreOf(s, makeRoomPredictor("default")->predict(s.request)).iou[0], 0.8);
}

// Rectangle or grown room: the learned room model keeps the one agreeing more with the room it sees (default_network
// 1), and the three candidates' vote (3, the default) keeps that one too; by area alone (default_network 0), door 2
// gets its grown room, at least 1.25 times its rectangle and worse.
TEST(DefaultPredictor, TheLearnedModelChoosesBetweenRectangleAndGrownRoom) {
  Synthetic s = corridorWithPillar();
  for (const int network : {1, 3}) {
    s.request.parameters["default_network"] = network;
    const PredictionResult chosen = makeRoomPredictor("default")->predict(s.request);
    const double by_model = scoreOf(s, chosen).iou[1];
    std::printf("default_network %d, door 2: IoU %.3f (rectangle %g, model's room %g)\n", network, by_model,
                chosen.rooms[1].terms.at("rectangle"), chosen.rooms[1].terms.at("model_room"));
    EXPECT_GT(by_model, 0.95) << "default_network " << network;
  }
  s.request.parameters["default_network"] = 0;
  const PredictionResult by_area_rule = makeRoomPredictor("default")->predict(s.request);
  const double by_area = scoreOf(s, by_area_rule).iou[1];
  std::printf("door 2: IoU %.3f by area (rectangle %g)\n", by_area, by_area_rule.rooms[1].terms.at("rectangle"));
  EXPECT_LT(by_area, 0.8);
}

// The vote of default_network 3: the candidate with the highest summed IoU with the other two, among those
// present; ties to the grown room, then the rectangle.
TEST(DefaultPredictor, TheCandidateAgreeingMostWithTheOthersIsChosen) {
  constexpr std::array<bool, 3> kAll = {true, true, true};
  // Rectangle and grown room alike, the model's room nearer the rectangle: 1.5 against 1.1 and 1.0.
  EXPECT_EQ(mostAgreedCandidate({0.8, 0.7, 0.3}, kAll), RoomCandidate::kRectangle);
  // Rectangle and grown room apart, the model's room overlapping both: 1.3 against 0.8 and 0.9.
  EXPECT_EQ(mostAgreedCandidate({0.2, 0.6, 0.7}, kAll), RoomCandidate::kModel);
  EXPECT_EQ(mostAgreedCandidate({0.5, 0.1, 0.6}, kAll), RoomCandidate::kGrown);  // 0.6, 1.1, 0.7
  // Ties.
  EXPECT_EQ(mostAgreedCandidate({0.5, 0.5, 0.5}, kAll), RoomCandidate::kGrown);
  EXPECT_EQ(mostAgreedCandidate({0.5, 0.0, 0.0}, {true, true, false}), RoomCandidate::kGrown);
  EXPECT_EQ(mostAgreedCandidate({0.0, 0.4, 0.0}, {true, false, true}), RoomCandidate::kRectangle);
  // A missing candidate is never chosen, however its numbers read.
  EXPECT_EQ(mostAgreedCandidate({0.2, 0.6, 0.7}, {true, true, false}), RoomCandidate::kGrown);
  EXPECT_EQ(mostAgreedCandidate({0.9, 0.9, 0.0}, {false, true, true}), RoomCandidate::kGrown);
  EXPECT_EQ(mostAgreedCandidate({0.0, 0.0, 0.0}, {false, false, true}), RoomCandidate::kModel);
  EXPECT_EQ(mostAgreedCandidate({0.0, 0.0, 0.0}, {false, false, false}), RoomCandidate::kGrown);
}

// The learned model does not read maps finer than its window allows (9.4 mm; their windows would take gigabytes):
// there the area rule decides, as with default_network 0.
TEST(DefaultPredictor, MapsTooFineForTheLearnedModelUseTheAreaRule) {
  Synthetic s = corridorWithPillar();
  constexpr int kFactor = 6;  // the same map in pixels of 8.3 mm
  cv::resize(s.request.map.cells, s.request.map.cells, cv::Size(), kFactor, kFactor, cv::INTER_NEAREST);
  s.request.map.resolution /= kFactor;
  ASSERT_FALSE(networkReads(s.request.map.resolution));
  const PredictionResult by_default = makeRoomPredictor("default")->predict(s.request);
  s.request.parameters["default_network"] = 0;
  const PredictionResult by_area = makeRoomPredictor("default")->predict(s.request);
  ASSERT_EQ(by_default.rooms.size(), by_area.rooms.size());
  for (size_t i = 0; i < by_area.rooms.size(); ++i) {
    EXPECT_TRUE(by_area.rooms[i].placed) << by_area.rooms[i].problem;
    EXPECT_EQ(cv::countNonZero(by_default.rooms[i].mask != by_area.rooms[i].mask), 0) << "door " << i + 1;
  }
}

// A map drawn from a state image (0 unknown, 1 free, 2 wall) with doors on horizontal walls (image column, row).
Synthetic syntheticFromStates(const cv::Mat1b& states, const cv::Mat1w& truth,
                              const std::vector<cv::Point2d>& doors) {
  Synthetic result;
  result.truth = truth;
  common::OccupancyGrid& map = result.request.map;
  map.resolution = 0.05;
  map.cells = cv::Mat_<int8_t>(states.size(), common::OccupancyGrid::kUnknown);
  map.cells.setTo(common::OccupancyGrid::kFree, states == 1);
  map.cells.setTo(common::OccupancyGrid::kOccupied, states == 2);
  for (size_t k = 0; k < doors.size(); ++k) {
    common::MapDoor door;
    door.id = static_cast<int>(k + 1);
    door.width = 1.0;
    door.orientation = common::DoorOrientation::kAlongX;
    door.position = common::Point2(doors[k].x * map.resolution, (states.rows - doors[k].y) * map.resolution);
    result.request.doors.doors.push_back(door);
  }
  return result;
}

// A 240 x 160 state image: a corridor (rows 99 to 138) whose wall (rows 95 to 98) faces an unknown block, and a
// known service corridor above that block (rows 5 to 16), which bounds the depth of the rooms in it.
cv::Mat1b corridorUnderAnUnknownBlock() {
  cv::Mat1b states(cv::Size(240, 160), 0);
  states(cv::Rect(17, 95, 206, 48)).setTo(2);   // around the corridor
  states(cv::Rect(20, 99, 200, 40)).setTo(1);   // corridor
  states(cv::Rect(17, 2, 206, 18)).setTo(2);    // around the service corridor
  states(cv::Rect(20, 5, 200, 12)).setTo(1);
  return states;
}

// IoU of the first door's wall-fitted rectangle alone (default_network 0, no grown room) against the true room
// `room` (label 1 on its unknown cells).
double rectangleIou(const cv::Mat1b& states, const cv::Rect& room, const cv::Point2d& door) {
  cv::Mat1w truth = cv::Mat1w::zeros(states.size());
  truth(room).setTo(1);
  truth.setTo(0, states != 0);
  Synthetic s = syntheticFromStates(states, truth, {door});
  s.request.parameters["default_network"] = 0;
  s.request.parameters["default_grown_area_ratio"] = 1000.0;
  return scoreOf(s, makeRoomPredictor("default")->predict(s.request)).iou[0];
}

// A hidden room above a corridor whose door sits at the back of a shallow niche: the niche's side walls run
// from the door's line to the corridor's wall, which is not a pillar standing free; the room spans the wall.
TEST(DefaultPredictor, NicheSideWallsAreNotStubs) {
  cv::Mat1b states = corridorUnderAnUnknownBlock();
  states(cv::Rect(97, 89, 26, 10)).setTo(2);    // the niche's walls and the door's line
  states(cv::Rect(100, 92, 20, 7)).setTo(1);    // the niche
  EXPECT_GT(rectangleIou(states, cv::Rect(20, 20, 200, 75), {110, 90}), 0.9);
}

// A hidden room above a corridor and, beside it behind the same wall, an explored strip 0.3 m deep whose back wall
// lies between the rows that tell known space behind the wall: read cell by cell those rows missed the back wall,
// and the room ran on behind the strip to the wall's end (IoU 0.04; read within the wall drift 0.94).
TEST(DefaultPredictor, KnownSpaceBehindTheWallEndsTheRoomWithinTheWallDrift) {
  cv::Mat1b states = corridorUnderAnUnknownBlock();
  states(cv::Rect(118, 88, 102, 7)).setTo(2);   // the strip's walls: its back wall is row 88
  states(cv::Rect(120, 89, 100, 6)).setTo(1);   // the strip
  EXPECT_GT(rectangleIou(states, cv::Rect(20, 20, 98, 75), {70, 96}), 0.85);
}

// A block of unknown between a north corridor and a west corridor, bounded by known space to the south and
// east: a room behind a door in the north corridor, and below it a long room behind a door in the west corridor
// (their shared wall unseen). Stubs in the corridors mark where the rooms' walls meet the corridors. Both
// rectangles reach across the whole block; the overlap belongs to the west door, which opens right into it.
TEST(DefaultPredictor, OverlapOfPerpendicularDoorsGoesToTheNearerDoor) {
  const cv::Size size(260, 260);
  cv::Mat1b states(size, 2);
  states(cv::Rect(5, 5, 250, 40)).setTo(1);     // north corridor, rows 5..44
  states(cv::Rect(5, 5, 40, 250)).setTo(1);     // west corridor, columns 5..44
  states(cv::Rect(48, 48, 172, 172)).setTo(0);  // the unknown block, rows and columns 48..219
  states(cv::Rect(48, 223, 207, 32)).setTo(1);  // explored space south of the block
  states(cv::Rect(223, 48, 32, 207)).setTo(1);  // and east of it
  states(cv::Rect(110, 37, 6, 8)).setTo(2);     // stub in the north corridor at the rooms' west wall
  states(cv::Rect(37, 130, 8, 6)).setTo(2);     // stub in the west corridor at the rooms' shared wall
  cv::Mat1w truth = cv::Mat1w::zeros(size);
  truth(cv::Rect(113, 48, 107, 85)).setTo(1);   // behind the north door: rows 48..132
  truth(cv::Rect(48, 133, 172, 87)).setTo(2);   // behind the west door: rows 133..219, the block's width
  Synthetic s = syntheticFromStates(states, truth, {{165, 46}, {46, 190}});
  s.request.doors.doors[1].orientation = common::DoorOrientation::kAlongY;
  s.request.parameters["default_network"] = 0;  // the area rule, with:
  s.request.parameters["default_grown_area_ratio"] = 1000.0;  // the wall-fitted rectangles only
  const evaluation::RoomScores scores = scoreOf(s, makeRoomPredictor("default")->predict(s.request));
  for (size_t k = 0; k < scores.iou.size(); ++k) EXPECT_GT(scores.iou[k], 0.9) << "door " << k + 1;
}

// Working states (0 unknown, 1 free, 2 wall) of eight rooms (40 x 64 pixels, x from 8 every 48, y 8..71) side by
// side above a corridor (y 80..111), walls 8 pixels thick, on a 400 x 120 image of wall.
cv::Mat1b roomsAlongACorridor() {
  cv::Mat1b states(120, 400, static_cast<uint8_t>(2));
  states(cv::Rect(8, 80, 384, 32)).setTo(1);
  for (int x = 8; x + 40 <= 392; x += 48) states(cv::Rect(x, 8, 40, 64)).setTo(1);
  return states;
}

// Rooms side by side along a corridor, as a SLAM map draws them: each wall face a cell into the space it was seen
// from. Seen from both sides (the free corridor and free rooms) the walls cross 8 pixels, 6 of wall (0.3 m); a
// room behind a closed door shows only its corridor wall's near face (2 pixels, 1 of them wall) and the rest is
// unknown: 5 pixels (0.25 m) unseen. A map that draws whole walls shows none unseen.
TEST(DefaultPredictor, EstimatesTheUnseenWallThickness) {
  const auto floor = [](int shown) {
    cv::Mat1b states = roomsAlongACorridor();
    // The middle rooms are hidden: unknown behind the near `shown` rows of their corridor wall.
    for (int x : {152, 200}) states(cv::Rect(x, 8, 40, 64 + 8 - shown)).setTo(0);
    return syntheticFromStates(states, cv::Mat1w::zeros(states.size()), {});
  };
  EXPECT_NEAR(unseenWallThickness(floor(2).request.map), 0.25, 1e-9);
  EXPECT_NEAR(unseenWallThickness(floor(8).request.map), 0.0, 1e-9);
}

// The margin keeps the unseen part of the door's wall out of the room: with the walls of a hidden room shown only
// by their near faces, the room ends a wall's thickness from them.
TEST(DefaultPredictor, LeavesTheUnseenWallsOutOfTheRooms) {
  cv::Mat1b states = roomsAlongACorridor();
  states(cv::Rect(144, 0, 56, 78)).setTo(0);  // a hidden room (x 152..191, y 8..71) and its walls, but the near
  cv::Mat1w truth = cv::Mat1w::zeros(states.size());  // 2 rows of the corridor wall, unknown
  truth(cv::Rect(152, 8, 40, 64)).setTo(1);
  Synthetic s = syntheticFromStates(states, truth, {{172, 77}});
  s.request.parameters["default_network"] = 0;  // the wall-fitted rectangle alone, so that only the margin differs
  s.request.parameters["default_grown_area_ratio"] = 1000.0;
  const PredictionResult result = makeRoomPredictor("default")->predict(s.request);
  ASSERT_EQ(result.rooms.size(), 1u);
  EXPECT_NEAR(result.rooms[0].terms.at("wall_margin"), 0.25, 1e-9);
  const double with_margin = scoreOf(s, result).iou[0];
  s.request.parameters["default_wall_margin"] = 0.0;
  const double without = scoreOf(s, makeRoomPredictor("default")->predict(s.request)).iou[0];
  std::printf("IoU with the estimated margin %.3f, without %.3f\n", with_margin, without);
  EXPECT_GT(with_margin, 0.7);
  EXPECT_GT(with_margin, without + 0.05);
}

// Doors that share one place (their rectangles split the shared wall down to nothing) or crowd at the map's corner
// once failed the whole prediction with an OpenCV error; now each door gets its own room or its own problem.
TEST(DefaultPredictor, DoorsAtOnePlaceOrCrowdedAtTheEdgeArePredictedOneByOne) {
  cv::Mat1b states = roomsAlongACorridor();
  states(cv::Rect(144, 0, 56, 78)).setTo(0);  // the hidden room of the doors
  cv::Mat1w truth = cv::Mat1w::zeros(states.size());
  truth(cv::Rect(152, 8, 40, 64)).setTo(1);
  for (const std::vector<cv::Point2d>& doors :
       {std::vector<cv::Point2d>{{172, 77}, {172, 77}}, std::vector<cv::Point2d>{{172, 77}, {1, 1}, {2, 1}, {3, 2}}}) {
    const Synthetic s = syntheticFromStates(states, truth, doors);
    PredictionResult result;
    ASSERT_NO_THROW(result = makeRoomPredictor("default")->predict(s.request));
    ASSERT_EQ(result.rooms.size(), doors.size());
    EXPECT_TRUE(result.rooms[0].placed) << result.rooms[0].problem;
    for (const RoomPrediction& room : result.rooms) EXPECT_TRUE(room.placed || !room.problem.empty());
  }
}

TEST(DefaultPredictor, ClipsRoomsToTheKnownOutlineBesideThem) {
  cv::Mat1b known = cv::Mat1b::zeros(100, 100);
  known(cv::Rect(60, 20, 30, 60)).setTo(255);  // an explored room beside the hidden one, rows 20..79
  known(cv::Rect(0, 80, 100, 10)).setTo(255);  // the corridor below both
  cv::Mat1b room = cv::Mat1b::zeros(100, 100);
  room(cv::Rect(10, 0, 40, 80)).setTo(255);    // a hidden room predicted up to the image's edge
  clipToKnownOutline(known, cv::Point(30, 80), 20, 10, &room);
  EXPECT_EQ(cv::boundingRect(room), cv::Rect(10, 20, 40, 60));
  // Nothing known beyond the door on that side: no limit.
  cv::Mat1b alone = cv::Mat1b::zeros(100, 100);
  alone(cv::Rect(10, 0, 40, 80)).setTo(255);
  cv::Mat1b corridor_only = cv::Mat1b::zeros(100, 100);
  corridor_only(cv::Rect(0, 80, 100, 10)).setTo(255);
  clipToKnownOutline(corridor_only, cv::Point(30, 80), 20, 10, &alone);
  EXPECT_EQ(cv::boundingRect(alone), cv::Rect(10, 0, 40, 80));
}

// An unknown floor of `size` cells (0.05 m) to draw a case on, and a door (along x) at an image point.
Synthetic blankFloor(const cv::Size& size) {
  Synthetic s;
  s.request.map.resolution = 0.05;
  s.request.map.cells = cv::Mat_<int8_t>(size, common::OccupancyGrid::kUnknown);
  s.truth = cv::Mat1w::zeros(size);
  return s;
}

void addDoor(Synthetic* s, int id, double col, double row) {
  common::MapDoor door;
  door.id = id;
  door.orientation = common::DoorOrientation::kAlongX;
  door.position = common::Point2(col * s->request.map.resolution,
                                 (s->request.map.height() - row) * s->request.map.resolution);
  s->request.doors.doors.push_back(door);
}

// The synthetic case turned by `degrees` about the image centre (nearest cell, as a SLAM map of a turned building
// rasterizes its walls), doors with it.
Synthetic turned(const Synthetic& s, double degrees) {
  const cv::Size size = s.request.map.cells.size();
  const cv::Mat m = cv::getRotationMatrix2D(cv::Point2f(size.width / 2.0f, size.height / 2.0f), degrees, 1.0);
  Synthetic out = s;
  cv::Mat1b states(size, 0);
  states.setTo(1, s.request.map.cells == common::OccupancyGrid::kFree);
  states.setTo(2, s.request.map.cells == common::OccupancyGrid::kOccupied);
  cv::warpAffine(states, states, m, size, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  out.request.map.cells = cv::Mat_<int8_t>(size, common::OccupancyGrid::kUnknown);
  out.request.map.cells.setTo(common::OccupancyGrid::kFree, states == 1);
  out.request.map.cells.setTo(common::OccupancyGrid::kOccupied, states == 2);
  cv::warpAffine(s.truth, out.truth, m, size, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  out.truth.setTo(0, out.request.map.cells != common::OccupancyGrid::kUnknown);
  const cv::Matx23d a(m);
  for (common::MapDoor& door : out.request.doors.doors) {
    const common::Point2 p = s.request.map.toImage(door.position);
    const cv::Point2d q(a(0, 0) * p.x() + a(0, 1) * p.y() + a(0, 2), a(1, 0) * p.x() + a(1, 1) * p.y() + a(1, 2));
    door.position = common::Point2(q.x * s.request.map.resolution, (size.height - q.y) * s.request.map.resolution);
  }
  return out;
}

TEST(DefaultPredictor, FindsTheWallAngleOfSolidWallBlocks) {
  // Thick walls drawn solid give far more wall cells than the angle is measured on: thinned in the cells' raster
  // order they would form a sheared lattice, whose own rows would pass for the walls' direction.
  cv::Mat1b states(600, 600, static_cast<uint8_t>(1));
  cv::rectangle(states, cv::Rect(100, 100, 400, 400), 2, cv::FILLED);
  cv::rectangle(states, cv::Rect(200, 250, 200, 100), 1, cv::FILLED);
  const Synthetic block = syntheticFromStates(states, cv::Mat1w::zeros(states.size()), {});
  for (const double degrees : {0.0, 7.0, 20.0}) {
    const common::OccupancyGrid map = turned(block, degrees).request.map;
    ASSERT_GT(cv::countNonZero(map.cells == common::OccupancyGrid::kOccupied), 100000);
    EXPECT_NEAR(std::abs(dominantWallAngle(map)) * 180.0 / CV_PI, degrees, 0.5) << degrees << " degrees";
  }
}

// A hidden room beside an explored one, both shallower than wide, with the outside beyond their far walls: a
// corridor, an explored room 3 m deep and, beside it, the hidden room (6.2 m wide, 3 m deep) behind door `id`.
Synthetic roomBesideAnExploredOne(int id) {
  Synthetic s = blankFloor(cv::Size(300, 240));
  common::OccupancyGrid& map = s.request.map;
  map.cells(cv::Rect(17, 177, 266, 46)).setTo(common::OccupancyGrid::kOccupied);   // around the corridor
  map.cells(cv::Rect(147, 115, 126, 65)).setTo(common::OccupancyGrid::kOccupied);  // around the explored room
  map.cells(cv::Rect(20, 180, 260, 40)).setTo(common::OccupancyGrid::kFree);       // corridor
  map.cells(cv::Rect(150, 118, 120, 59)).setTo(common::OccupancyGrid::kFree);      // explored room, 3 m deep
  map.cells(cv::Rect(160, 177, 20, 3)).setTo(common::OccupancyGrid::kFree);        // its open door
  s.truth(cv::Rect(20, 118, 124, 59)).setTo(id);
  addDoor(&s, id, 85, 178.5);
  return s;
}

// Failure pattern 5 of the unseen maps: the explored room shows where the building ends, on a map turned by a
// few degrees too.
TEST(DefaultPredictor, ClipsToTheOutlineOnATurnedMap) {
  const Synthetic s = roomBesideAnExploredOne(1);
  const auto predictor = makeRoomPredictor("default");
  const double straight = scoreOf(s, predictor->predict(s.request)).iou[0];
  const Synthetic tilted = turned(s, 4.0);
  const PredictionResult result = predictor->predict(tilted.request);
  const double on_turned = scoreOf(tilted, result).iou[0];
  std::printf("IoU straight %.3f, turned by 4 degrees %.3f (estimated %.2f degrees)\n", straight, on_turned,
              result.rooms[0].terms.at("rotation"));
  EXPECT_GT(straight, 0.85);
  EXPECT_NEAR(std::abs(result.rooms[0].terms.at("rotation")), 4.0, 0.3);
  // Before the turned map was predicted straight (rectangles only, no outline clip, the angle estimated as
  // -1.89 degrees from gradient directions) it scored 0.862.
  EXPECT_GT(on_turned, 0.92);
}

// A turned map keeps the unseen wall thickness of the straight one. The rooms along a corridor, as explored:
// walls between explored spaces 8 pixels thick and thin partitions 2 pixels (both seen from both sides), the outer
// walls and the hidden room's corridor wall showing their 2-pixel near faces: 5 pixels (0.25 m) unseen. Measured
// on the map turned straight by linear resampling, which thickens the partitions to 3 pixels so that they win the
// count of walls seen from both sides, the margin came out 0 at 3 degrees.
TEST(DefaultPredictor, KeepsTheUnseenWallThicknessOnATurnedMap) {
  cv::Mat1b states(300, 560, static_cast<uint8_t>(0));
  const cv::Rect floor(80, 90, 400, 120);
  cv::Mat1b inside = states(floor);
  roomsAlongACorridor().copyTo(inside);
  for (int x = 20; x < 392; x += 24) inside(cv::Rect(x, 80, 2, 32)).setTo(2);  // thin partitions, 2 pixels
  for (int x = 8; x + 40 <= 392; x += 48) inside(cv::Rect(x, 40, 40, 2)).setTo(2);  // and across the rooms
  for (const cv::Rect& outside : {cv::Rect(0, 0, 400, 6), cv::Rect(0, 114, 400, 6), cv::Rect(0, 0, 6, 120),
                                  cv::Rect(394, 0, 6, 120)})
    inside(outside).setTo(0);  // the outer walls' unseen 6 pixels
  inside(cv::Rect(144, 0, 56, 78)).setTo(0);  // the hidden room (x 152..191, y 8..71) and its walls
  cv::Mat1w truth = cv::Mat1w::zeros(states.size());
  truth(cv::Rect(floor.x + 152, floor.y + 8, 40, 64)).setTo(1);
  Synthetic s = syntheticFromStates(states, truth, {{floor.x + 172.0, floor.y + 77.0}});
  s.request.parameters["default_network"] = 0;  // the wall-fitted rectangle alone
  s.request.parameters["default_grown_area_ratio"] = 1000.0;
  const auto predictor = makeRoomPredictor("default");
  EXPECT_NEAR(predictor->predict(s.request).rooms[0].terms.at("wall_margin"), 0.25, 1e-9);
  for (double degrees : {3.0, 7.0, 20.0}) {
    const Synthetic tilted = turned(s, degrees);
    const PredictionResult result = predictor->predict(tilted.request);
    ASSERT_TRUE(result.rooms[0].terms.count("wall_margin")) << degrees << " degrees";
    EXPECT_NEAR(result.rooms[0].terms.at("wall_margin"), 0.25, 0.051) << degrees << " degrees";
  }
}

// A hidden room between two explored rooms off a corridor (their walls known): 5.7 m wide, 3 m deep, behind
// door `id`.
Synthetic roomBetweenExploredOnes(int id) {
  Synthetic s = blankFloor(cv::Size(300, 240));
  common::OccupancyGrid& map = s.request.map;
  map.cells(cv::Rect(17, 115, 266, 108)).setTo(common::OccupancyGrid::kOccupied);  // around everything
  map.cells(cv::Rect(20, 180, 260, 40)).setTo(common::OccupancyGrid::kFree);       // corridor
  map.cells(cv::Rect(20, 118, 60, 59)).setTo(common::OccupancyGrid::kFree);        // explored room, left
  map.cells(cv::Rect(200, 118, 80, 59)).setTo(common::OccupancyGrid::kFree);       // explored room, right
  map.cells(cv::Rect(40, 177, 20, 3)).setTo(common::OccupancyGrid::kFree);         // their open doors
  map.cells(cv::Rect(220, 177, 20, 3)).setTo(common::OccupancyGrid::kFree);
  map.cells(cv::Rect(83, 118, 114, 59)).setTo(common::OccupancyGrid::kUnknown);    // the hidden room
  s.truth(cv::Rect(83, 118, 114, 59)).setTo(id);
  addDoor(&s, id, 140, 178.5);
  return s;
}

// A building with a wing at another angle (or a map bent by drift): the same hidden room, once straight and once
// in a wing turned by 30 degrees, side by side on one map. Each door is predicted in the frame of the walls
// around it; in the map's one frame the room of the other wing comes out askew (rectangles and grown rooms alone,
// default_network 0: the learned model's room, which needs no frame, can outvote an askew pair).
TEST(DefaultPredictor, PredictsEachDoorInTheFrameOfItsWalls) {
  const Synthetic straight = roomBetweenExploredOnes(1);
  const Synthetic wing = turned(roomBetweenExploredOnes(2), 30.0);
  Synthetic s = straight;
  cv::hconcat(straight.request.map.cells, wing.request.map.cells, s.request.map.cells);
  cv::hconcat(straight.truth, wing.truth, s.truth);
  common::MapDoor door = wing.request.doors.doors[0];
  door.position.x() += straight.request.map.width() * s.request.map.resolution;
  s.request.doors.doors.push_back(door);
  const auto predictor = makeRoomPredictor("default");
  const evaluation::RoomScores by_default = scoreOf(s, predictor->predict(s.request));
  EXPECT_GT(std::min(by_default.iou[0], by_default.iou[1]), 0.85);
  s.request.parameters["default_network"] = 0;
  const PredictionResult result = predictor->predict(s.request);
  const evaluation::RoomScores local = scoreOf(s, result);
  s.request.parameters["default_local_frame_radius"] = 0.0;  // the map's one frame for every door
  const evaluation::RoomScores global = scoreOf(s, predictor->predict(s.request));
  std::printf("IoU in each door's frame %.3f / %.3f (%.1f / %.1f degrees), in the map's frame %.3f / %.3f\n",
              local.iou[0], local.iou[1], result.rooms[0].terms.at("rotation"), result.rooms[1].terms.at("rotation"),
              global.iou[0], global.iou[1]);
  EXPECT_GT(std::min(local.iou[0], local.iou[1]), 0.85);
  EXPECT_LT(std::min(global.iou[0], global.iou[1]), 0.7);
}

// A corridor 2 m wide (40 cells, rows first_row to first_row + 39) across the whole floor, walled round, and above
// it a wall with a stub 0.5 m into the corridor at each side wall of a room spanning columns [room_left, room_right).
void addCorridorBelowARoom(Synthetic* s, int first_row, int room_left, int room_right) {
  common::OccupancyGrid& map = s->request.map;
  const int width = map.width();
  map.cells(cv::Rect(17, first_row - 3, width - 34, 46)).setTo(common::OccupancyGrid::kOccupied);
  map.cells(cv::Rect(20, first_row, width - 40, 40)).setTo(common::OccupancyGrid::kFree);
  for (int side : {room_left, room_right})
    map.cells(cv::Rect(side - 2, first_row, 4, 10)).setTo(common::OccupancyGrid::kOccupied);
}

// A door into a large unknown region (failure pattern 2 of the unseen maps): a 4 m wide room between two wall
// stubs of a corridor, 5 m deep, and beyond it 11 m more unknown up to a known corridor far away. That corridor
// is no evidence of the room's back wall: measured depths beyond default_max_aspect times the width give way to
// the priors (here the square).
TEST(DefaultPredictor, FarKnownSpaceDoesNotSetTheDepth) {
  Synthetic s = blankFloor(cv::Size(400, 460));
  addCorridorBelowARoom(&s, 397, 160, 240);
  common::OccupancyGrid& map = s.request.map;
  map.cells(cv::Rect(17, 17, 366, 46)).setTo(common::OccupancyGrid::kOccupied);   // around a far corridor
  map.cells(cv::Rect(20, 20, 360, 40)).setTo(common::OccupancyGrid::kFree);       // unknown from row 63 on
  s.truth(cv::Rect(160, 293, 80, 100)).setTo(1);  // the hidden room, rows 293..392
  addDoor(&s, 1, 200, 394.5);
  s.request.parameters["default_network"] = 0;  // the area rule, with:
  s.request.parameters["default_grown_area_ratio"] = 1000.0;  // the wall-fitted rectangle only
  const auto predictor = makeRoomPredictor("default");
  const PredictionResult result = predictor->predict(s.request);
  const double capped = scoreOf(s, result).iou[0];
  s.request.parameters["default_max_aspect"] = 100.0;  // any measured depth counts
  const double uncapped = scoreOf(s, predictor->predict(s.request)).iou[0];
  std::printf("IoU with the depth capped %.3f, uncapped %.3f\n", capped, uncapped);
  EXPECT_EQ(result.rooms[0].terms.at("depth_bounded"), 0.0);
  EXPECT_GT(capped, 0.75);
  EXPECT_LT(uncapped, 0.4);
}

// A stub that is no room's end: a hidden room 13 m wide (columns 20 to 279, the corridor's whole length) and 4.5 m
// deep behind a corridor with pilasters, stubs 0.5 m into it at columns 160 and 240; its door at 200, nothing known
// beyond it. The stubbed rectangle ends at the stubs (and so does the room without the learned model's say); the
// rectangle past them agrees more with the model's room and spans the room.
TEST(DefaultPredictor, TheLearnedModelDecidesWhetherAStubEndsARoom) {
  Synthetic s = blankFloor(cv::Size(300, 260));
  addCorridorBelowARoom(&s, 197, 160, 240);
  s.truth(cv::Rect(20, 103, 260, 91)).setTo(1);
  addDoor(&s, 1, 200, 195.5);
  const auto predictor = makeRoomPredictor("default");
  for (const int network : {1, 3}) {
    s.request.parameters["default_network"] = network;
    s.request.parameters["default_stub_by_model"] = 1;
    const PredictionResult by_model = predictor->predict(s.request);
    s.request.parameters["default_stub_by_model"] = 0;
    const double stubbed = scoreOf(s, predictor->predict(s.request)).iou[0];
    const double past_stubs = scoreOf(s, by_model).iou[0];
    std::printf("default_network %d: IoU %.3f with the model's say on stubs (rectangle %g), %.3f stubbed\n", network,
                past_stubs, by_model.rooms[0].terms.at("rectangle"), stubbed);
    EXPECT_GT(past_stubs, 0.85) << "default_network " << network;
    EXPECT_LT(stubbed, 0.4) << "default_network " << network;
  }
}

// Failure pattern 1 of the unseen maps: a room off a bare corridor, 3 m wide and 6 m deep, whose back wall, side
// walls and neighbours the map does not show. With nothing on the map to give its depth, the rectangle takes the
// depth of the learned model's room behind the door (default_model_depth) instead of the square's 3 m.
TEST(DefaultPredictor, ARoomWithNoDepthOnTheMapTakesTheDepthOfTheModelsRoom) {
  Synthetic s = blankFloor(cv::Size(500, 300));
  addCorridorBelowARoom(&s, 200, 220, 280);
  s.truth(cv::Rect(220, 77, 60, 120)).setTo(1);  // the hidden room, rows 77..196
  addDoor(&s, 1, 250, 198.5);
  s.request.doors.doors[0].width = 0.9;
  s.request.parameters["default_network"] = 1;  // the model chooses rectangle or grown room
  // The stubs bound this room; the model's room runs on along the bare corridor past them, so with its say on
  // stubs the rectangle spans the corridor (IoU 0.12). On real maps that say gains (docs/results.md).
  s.request.parameters["default_stub_by_model"] = 0;
  const auto predictor = makeRoomPredictor("default");
  const PredictionResult with_model = predictor->predict(s.request);
  s.request.parameters["default_model_depth"] = 0;
  const PredictionResult square = predictor->predict(s.request);
  ASSERT_EQ(with_model.rooms[0].terms.count("depth_source"), 1u) << "the rectangle was not kept";
  ASSERT_EQ(square.rooms[0].terms.count("depth_source"), 1u) << "the rectangle was not kept";
  const double with_iou = scoreOf(s, with_model).iou[0], square_iou = scoreOf(s, square).iou[0];
  std::printf("depth %.2f m from the model's room, IoU %.3f; as a square %.2f m, IoU %.3f\n",
              with_model.rooms[0].terms.at("depth"), with_iou, square.rooms[0].terms.at("depth"), square_iou);
  EXPECT_EQ(with_model.rooms[0].terms.at("depth_source"), 4.0);
  EXPECT_EQ(square.rooms[0].terms.at("depth_source"), 3.0);
  EXPECT_NEAR(with_model.rooms[0].terms.at("depth"), 6.0, 0.5);
  EXPECT_GT(with_iou, 0.85);
  EXPECT_LT(square_iou, 0.55);
}

// Mean IoU of `default` over the benchmark's 44 valid cases; the floor, a little under the measured mean (0.760),
// is the generalization issue's: not below 0.73.
TEST(DefaultPredictor, KeepsItsAccuracyOnTheBenchmark) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  int cases = 0;
  EXPECT_GE(testing::benchmarkMeanIou("default", &cases), 0.73);
  EXPECT_EQ(cases, 44);
}

}  // namespace
}  // namespace hidden_rooms::prediction
