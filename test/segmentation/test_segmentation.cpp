#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/segmentation/floor_output.h"
#include "hidden_rooms/segmentation/room_graph.h"
#include "hidden_rooms/segmentation/room_segmenter.h"
#include "hidden_rooms/segmentation/room_types.h"
#include "hidden_rooms/segmentation/segmentation_metrics.h"
#include "hidden_rooms/world/environment.h"
#include "test_util.h"

namespace hidden_rooms::segmentation {
namespace {

constexpr double kResolution = 0.05;

// A drawn floor: unknown everywhere, then free rectangles (rooms, in metres from the grid's lower-left corner),
// each also labelled in `truth` with its own room number; walls are the unknown cells between them, openings
// are free rectangles labelled 0 in `truth` (they belong to no room's ground truth).
struct DrawnFloor {
  common::OccupancyGrid map;
  cv::Mat1w truth;

  DrawnFloor(double width, double height) {
    map.resolution = kResolution;
    map.cells = cv::Mat_<int8_t>(static_cast<int>(height / kResolution), static_cast<int>(width / kResolution),
                                 common::OccupancyGrid::kOccupied);
    truth = cv::Mat1w::zeros(map.cells.size());
  }
  // Cells of the rectangle [x0, x1] x [y0, y1] (metres, y up).
  cv::Rect cells(double x0, double y0, double x1, double y1) const {
    const int rows = map.height();
    return cv::Rect(cv::Point(static_cast<int>(x0 / kResolution), rows - static_cast<int>(y1 / kResolution)),
                    cv::Point(static_cast<int>(x1 / kResolution), rows - static_cast<int>(y0 / kResolution)));
  }
  void room(int label, double x0, double y0, double x1, double y1) {
    map.cells(cells(x0, y0, x1, y1)).setTo(common::OccupancyGrid::kFree);
    truth(cells(x0, y0, x1, y1)).setTo(label);
  }
  void opening(double x0, double y0, double x1, double y1) {
    map.cells(cells(x0, y0, x1, y1)).setTo(common::OccupancyGrid::kFree);
  }
  SegmentationInput input() const { return {map.cells == common::OccupancyGrid::kFree, kResolution}; }
};

// A corridor of 20 m x 2 m with four 4 m x 4 m rooms above it, each behind a 0.9 m doorway.
DrawnFloor corridorWithRooms() {
  DrawnFloor floor(22.0, 8.0);
  floor.room(1, 1.0, 1.0, 21.0, 3.0);
  for (int k = 0; k < 4; ++k) {
    const double x0 = 1.0 + 5.0 * k;
    floor.room(2 + k, x0, 3.2, x0 + 4.0, 7.2);
    floor.opening(x0 + 1.5, 3.0, x0 + 2.4, 3.2);
  }
  return floor;
}

SegmentationScores scoresOf(const std::string& method, const DrawnFloor& floor) {
  return scoreSegmentation(segmentRooms(*makeRoomSegmenter(method), floor.input()), floor.truth);
}

TEST(Segmentation, EveryMethodFindsTheRoomsOffACorridor) {
  const DrawnFloor floor = corridorWithRooms();
  for (const std::string& method : roomSegmenterNames()) {
    SCOPED_TRACE(method);
    const cv::Mat1w labels = segmentRooms(*makeRoomSegmenter(method), floor.input());
    const SegmentationScores scores = scoreSegmentation(labels, floor.truth);
    EXPECT_GT(scores.precision_micro, 0.97);  // no segment spans two rooms
    // Every free cell has a room and no wall cell has one.
    EXPECT_EQ(cv::countNonZero((labels > 0) != floor.input().free), 0);
    if (method == "voronoi") {
      // The survey's Voronoi method cuts a long corridor into pieces (its merge rules keep a 2 m wide corridor
      // longer than about 16 m split); the rooms are still found whole.
      EXPECT_GT(scores.recall_micro, 0.9);
      continue;
    }
    EXPECT_EQ(scores.found_rooms, 5);
    EXPECT_GT(scores.recall_micro, 0.97);
    EXPECT_GT(scores.mcc, 0.95);
  }
}

TEST(Segmentation, AnLShapedRoomStaysOneRoom) {
  DrawnFloor floor(12.0, 12.0);
  floor.room(1, 1.0, 1.0, 11.0, 5.0);
  floor.room(1, 1.0, 5.0, 5.0, 11.0);
  const SegmentationScores scores = scoresOf("default", floor);
  EXPECT_EQ(scores.found_rooms, 1);
  EXPECT_GT(scores.recall_micro, 0.99);
}

TEST(Segmentation, TwoRoomsJoinedByAWideOpeningAreTwoRooms) {
  DrawnFloor floor(14.0, 8.0);
  floor.room(1, 1.0, 1.0, 6.5, 7.0);
  floor.room(2, 6.7, 1.0, 13.0, 7.0);
  floor.opening(6.5, 3.0, 6.7, 4.5);  // 1.5 m wide
  const SegmentationScores scores = scoresOf("default", floor);
  EXPECT_EQ(scores.found_rooms, 2);
  EXPECT_GT(scores.recall_micro, 0.97);
  EXPECT_GT(scores.precision_micro, 0.97);
}

TEST(Segmentation, ARoomWithAWideOpenEndIsNotCutFromItsCorridor) {
  // A 2.5 m wide corridor that widens to 3 m: no constriction, one room.
  DrawnFloor floor(20.0, 6.0);
  floor.room(1, 1.0, 1.0, 10.0, 3.5);
  floor.room(1, 10.0, 1.0, 19.0, 4.0);
  EXPECT_EQ(scoresOf("default", floor).found_rooms, 1);
}

TEST(RoomSegmentation, ShippedParameterFileEqualsTheDefaults) {
  const auto file = common::loadParameterFile(std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/config/segmentation.yaml");
  std::map<std::string, double> defaults;
  for (const std::string& name : roomSegmenterNames())
    for (const auto& [key, value] : makeRoomSegmenter(name)->defaultParameters()) defaults[key] = value;
  EXPECT_EQ(file.size(), defaults.size());
  for (const auto& [key, value] : file) {
    ASSERT_TRUE(defaults.count(key)) << key << " is in config/segmentation.yaml but no method reads it";
    EXPECT_DOUBLE_EQ(value, defaults[key]) << key;
  }
}

TEST(SegmentationMetrics, HandMadeLabelImagesGiveTheSurveysScores) {
  cv::Mat1w truth = cv::Mat1w::zeros(20, 40);
  truth(cv::Rect(0, 0, 20, 20)).setTo(1);
  truth(cv::Rect(20, 0, 20, 20)).setTo(2);

  const SegmentationScores same = scoreSegmentation(truth, truth);
  EXPECT_DOUBLE_EQ(same.recall_micro, 1.0);
  EXPECT_DOUBLE_EQ(same.precision_micro, 1.0);
  EXPECT_DOUBLE_EQ(same.recall_macro, 1.0);
  EXPECT_DOUBLE_EQ(same.precision_macro, 1.0);
  EXPECT_DOUBLE_EQ(same.mcc, 1.0);

  // One segment over both rooms: every room fully found, the segment half right.
  const cv::Mat1w merged = cv::Mat1w(truth > 0) / 255;
  const SegmentationScores under = scoreSegmentation(merged, truth);
  EXPECT_DOUBLE_EQ(under.recall_micro, 1.0);
  EXPECT_DOUBLE_EQ(under.precision_micro, 0.5);
  EXPECT_DOUBLE_EQ(under.precision_macro, 0.5);
  EXPECT_EQ(under.found_rooms, 1);

  // Room 1 split into a 15-column and a 5-column segment (100 cells: left out as too small).
  cv::Mat1w split = truth.clone();
  split(cv::Rect(15, 0, 5, 20)).setTo(3);
  const SegmentationScores over = scoreSegmentation(split, truth);
  EXPECT_EQ(over.found_rooms, 2);
  EXPECT_DOUBLE_EQ(over.recall_micro, (300.0 / 400.0 + 1.0) / 2.0);
  EXPECT_DOUBLE_EQ(over.recall_macro, 700.0 / 800.0);
  EXPECT_DOUBLE_EQ(over.precision_micro, 1.0);
  // Pairs: 2 x C(400, 2) in the truth; the split loses the 300 x 100 pairs across it.
  const double truth_pairs = 2 * 400.0 * 399.0 / 2, found_pairs = truth_pairs - 300.0 * 100.0;
  const double all = 800.0 * 799.0 / 2, tn = all - truth_pairs, fn = truth_pairs - found_pairs;
  const double mcc = (found_pairs * tn) / std::sqrt(found_pairs * truth_pairs * tn * (tn + fn));
  EXPECT_NEAR(over.mcc, mcc, 1e-12);

  EXPECT_THROW(scoreSegmentation(cv::Mat1w::zeros(5, 5), truth), common::InputError);
  EXPECT_THROW(scoreSegmentation(truth, cv::Mat1w::zeros(20, 40)), common::InputError);
}

TEST(SegmentationMetrics, LabelsAreScoredByTheGroundTruthRoomEachRoomOverlapsMost) {
  cv::Mat1w truth = cv::Mat1w::zeros(20, 60);
  truth(cv::Rect(0, 0, 20, 20)).setTo(1);
  truth(cv::Rect(20, 0, 20, 20)).setTo(2);
  truth(cv::Rect(40, 0, 20, 20)).setTo(3);
  cv::Mat1w found = truth.clone();
  found(cv::Rect(15, 0, 10, 20)).setTo(1);  // room 1 reaches into room 2, still mostly room 1
  const LabelScores scores =
      scoreRoomLabels(found, {"corridor", "room", "room"}, truth, {"corridor", "corridor", ""});
  EXPECT_EQ(scores.rooms, 2);  // the third ground-truth room has no label
  EXPECT_EQ(scores.correct, 1);
  EXPECT_DOUBLE_EQ(scores.recall("corridor"), 0.5);
  EXPECT_DOUBLE_EQ(scores.recall("office"), 1.0);
  EXPECT_THROW(scoreRoomLabels(found, {"room"}, truth, {"room", "room", "room"}), common::InputError);
}

TEST(SegmentationMetrics, BorderImagesGiveOneRoomPerRegion) {
  cv::Mat1b image(30, 60, uchar(255));
  cv::line(image, {30, 0}, {30, 29}, cv::Scalar(0));
  image(cv::Rect(50, 0, 10, 30)).setTo(0);
  const cv::Mat1w rooms = roomsFromBorderImage(image);
  double count = 0.0;
  cv::minMaxLoc(rooms, nullptr, &count);
  EXPECT_EQ(count, 2.0);
  EXPECT_EQ(cv::countNonZero(rooms == 0), 30 + 300);
}

// The floor of corridorWithRooms with the third room's doorway closed by a door of the doors file, and the fourth
// room unexplored behind a closed door, with a predicted room there.
struct FloorWithDoors {
  DrawnFloor drawn = corridorWithRooms();
  common::DoorsFile doors;
  cv::Mat1w predicted;
  FloorWithDoors() {
    doors.doors.push_back({7, {12.95, 3.1}, 0.9, common::DoorOrientation::kAlongX, std::nullopt});
    doors.doors.push_back({8, {17.95, 3.1}, 0.9, common::DoorOrientation::kAlongX, std::nullopt});
    const cv::Rect hidden = drawn.cells(16.0, 3.2, 20.0, 7.2);
    drawn.map.cells(hidden).setTo(common::OccupancyGrid::kUnknown);
    drawn.map.cells(drawn.cells(17.5, 3.0, 18.4, 3.2)).setTo(common::OccupancyGrid::kOccupied);
    predicted = cv::Mat1w::zeros(drawn.map.cells.size());
    predicted(drawn.cells(16.2, 3.3, 19.8, 7.0)).setTo(1);
  }
};

TEST(RoomGraph, ClosedDoorsAreBordersAndPredictedRoomsAreNodes) {
  const FloorWithDoors input;
  const SegmentedFloor floor = segmentFloor(input.drawn.map, input.doors, input.predicted, {});
  ASSERT_EQ(floor.rooms.size(), 5u);  // corridor, three explored rooms, one predicted
  int corridors = 0;
  for (const Room& room : floor.rooms) corridors += room.kind == RoomKind::kCorridor;
  EXPECT_EQ(corridors, 1);
  EXPECT_TRUE(floor.rooms.back().predicted);
  EXPECT_NEAR(floor.rooms.back().area, 3.6 * 3.7, 0.5);
  int open = 0;
  const Passage* closed = nullptr;
  const Passage* predicted = nullptr;
  for (const Passage& passage : floor.passages) {
    if (passage.kind == PassageKind::kOpen) ++open;
    if (passage.kind == PassageKind::kClosed) closed = &passage;
    if (passage.kind == PassageKind::kPredicted) predicted = &passage;
  }
  EXPECT_EQ(open, 2);
  ASSERT_NE(closed, nullptr);
  ASSERT_NE(predicted, nullptr);
  EXPECT_EQ(closed->door_id, 7);
  EXPECT_EQ(predicted->door_id, 8);
  // The closed door joins the corridor and the room behind it; the predicted one the corridor and the prediction.
  const int corridor = floor.labels(input.drawn.cells(2.0, 2.0, 2.1, 2.1).tl());
  EXPECT_EQ(closed->room_a == corridor || closed->room_b == corridor, true);
  EXPECT_NE(closed->room_a, closed->room_b);
  EXPECT_NE(closed->room_b, 0);
  EXPECT_EQ(predicted->room_a, corridor);
  EXPECT_EQ(predicted->room_b, floor.rooms.back().label);
}

// A room is a corridor only when most trees say so. On features that tell nothing (noise), each tree votes for
// about the type of a random training room: with a fifth of them corridors and the rest split evenly among the six
// room types, a plurality over seven types would call most rooms corridors; most trees never agree on it.
TEST(RoomTypes, ACorridorNeedsMostOfTheVotes) {
  cv::RNG noise(7);
  const auto noiseRows = [&](int rows) {
    cv::Mat1f features(rows, static_cast<int>(roomFeatureNames().size()));
    noise.fill(features, cv::RNG::UNIFORM, 0.0, 1.0);
    return features;
  };
  std::vector<int> types;
  for (int type = 0; type < static_cast<int>(roomTypeNames().size()); ++type)
    types.insert(types.end(), type == 0 ? 60 : 40, type);
  const RoomTypeClassifier classifier = RoomTypeClassifier::train(noiseRows(static_cast<int>(types.size())), types);
  const std::vector<int> found = classifier.classify(noiseRows(200));
  ASSERT_EQ(found.size(), 200u);
  const int corridors = static_cast<int>(std::count(found.begin(), found.end(), 0));
  EXPECT_LT(corridors, 20) << "rooms called corridors on noise: " << corridors;
  for (const int type : found) EXPECT_LT(type, static_cast<int>(roomTypeNames().size()));
}

// Betweenness on a hand-made graph: rooms 1 to 4 in a ring, room 5 off room 1. Of the six pairs of the other rooms,
// room 1 lies on every shortest path of 5-2, 5-4, 5-3 and on one of the two of 2-4 (3.5 / 6); room 2 on one of two
// of 1-3 and of 5-3 (1 / 6); room 3 on one of two of 2-4 (0.5 / 6); room 5 on none.
TEST(RoomTypes, BetweennessIsTheShareOfShortestPathsThroughARoom) {
  SegmentedFloor floor;
  for (int label = 1; label <= 5; ++label) {
    Room room;
    room.label = label;
    room.area = 4.0;
    room.width = 2.0;
    room.outline = {{0.0, 0.0}, {2.0, 0.0}, {2.0, 2.0}, {0.0, 2.0}};
    floor.rooms.push_back(room);
  }
  for (const auto& [a, b] : std::vector<std::pair<int, int>>{{1, 2}, {2, 3}, {3, 4}, {4, 1}, {1, 5}}) {
    Passage passage;
    passage.room_a = a;
    passage.room_b = b;
    passage.width = 0.9;
    floor.passages.push_back(passage);
  }
  const auto& names = roomFeatureNames();
  const int column = static_cast<int>(std::find(names.begin(), names.end(), "betweenness") - names.begin());
  ASSERT_LT(column, static_cast<int>(names.size()));
  const cv::Mat1f features = roomFeatures(floor);
  const std::vector<double> expected = {3.5 / 6.0, 1.0 / 6.0, 0.5 / 6.0, 1.0 / 6.0, 0.0};
  for (int room = 0; room < 5; ++room) EXPECT_NEAR(features(room, column), expected[room], 1e-6) << "room " << room + 1;
}

TEST(RoomGraph, TheEnvironmentXmlReadsBackWithTheSameRoomsAndDoors) {
  const FloorWithDoors input;
  const SegmentedFloor floor = segmentFloor(input.drawn.map, input.doors, input.predicted, {});
  const world::Environment written = floorToEnvironment(floor, input.drawn.map, "synthetic");
  const world::Environment read = world::parseEnvironment(world::environmentToXml(written), "rooms.xml");
  ASSERT_EQ(read.spaces.size(), floor.rooms.size());
  ASSERT_EQ(read.doors.size(), floor.passages.size());
  for (size_t i = 0; i < floor.rooms.size(); ++i) {
    EXPECT_NEAR(common::area(read.spaces[i].outline), floor.rooms[i].area, 0.05 * floor.rooms[i].area);
    EXPECT_EQ(read.spaces[i].type, floor.rooms[i].kind == RoomKind::kCorridor ? "C" : "R");
  }
  int closed = 0;
  for (const world::Door& door : read.doors) {
    EXPECT_EQ(door.space_indices.size(), 2u);
    closed += door.status == world::DoorStatus::kClosed;
  }
  EXPECT_EQ(closed, 2);
}

TEST(RoomSegmentation, BadInputGivesClearErrors) {
  const auto method = makeRoomSegmenter("default");
  EXPECT_NE(testing::inputErrorMessage([&] { segmentRooms(*method, {cv::Mat1b(), 0.05}); }).find("empty"),
            std::string::npos);
  EXPECT_NE(testing::inputErrorMessage([&] { segmentRooms(*method, {cv::Mat1b::zeros(10, 10), 0.05}); })
                .find("no free cell"),
            std::string::npos);
  EXPECT_NE(testing::inputErrorMessage([&] { segmentRooms(*method, {cv::Mat1b(10, 10, 255), 0.0}); })
                .find("resolution"),
            std::string::npos);
  EXPECT_NE(testing::inputErrorMessage([&] { makeRoomSegmenter("nonsense"); }).find("known: default"),
            std::string::npos);
  EXPECT_NE(testing::inputErrorMessage([&] { segmentRooms(*method, {cv::Mat1b(10, 10, 255), 0.05}, {{"x", 1}}); })
                .find("'x'"),
            std::string::npos);

  FloorWithDoors input;
  input.doors.doors.push_back({9, {100.0, 3.0}, 0.9, common::DoorOrientation::kAlongX, std::nullopt});
  EXPECT_NE(testing::inputErrorMessage([&] { segmentFloor(input.drawn.map, input.doors, {}, {}); })
                .find("door 9: position (100, 3) is outside the map"),
            std::string::npos);
  EXPECT_NE(testing::inputErrorMessage([&] { segmentFloor(input.drawn.map, {}, cv::Mat1w::zeros(3, 3), {}); })
                .find("predicted rooms"),
            std::string::npos);
  EXPECT_NE(testing::inputErrorMessage([&] { segmentFloor(common::OccupancyGrid(), {}, {}, {}); }).find("empty"),
            std::string::npos);
}

// The survey's maps in ../shared: floors a little below what the methods score today (docs/results.md).
TEST(RoomSegmentation, AccuracyOnTheSurveysMaps) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::string folder = testing::sharedDir() + "/data/room_segmentation/";
  const std::vector<std::string> names = {"Freiburg79_scan", "NLB",      "lab_a_scan", "lab_c_scan", "lab_intel",
                                          "lab_ipa",         "office_a", "office_c",   "office_e",   "office_g"};
  const std::map<std::string, std::pair<double, double>> floors = {
      {"default", {0.97, 0.94}}, {"morphological", {0.97, 0.89}}, {"voronoi", {0.95, 0.94}}};
  for (const auto& [method, floor] : floors) {
    double recall = 0.0, precision = 0.0;
    for (const std::string& name : names) {
      const cv::Mat1b map = common::readGreyImage(folder + name + ".png");
      const cv::Mat1b truth = common::readGreyImage(folder + name + "_gt_segmentation.png");
      const SegmentationScores scores = scoreSegmentation(
          segmentRooms(*makeRoomSegmenter(method), {map > 250, 0.05}), roomsFromBorderImage(truth));
      recall += scores.recall_micro / names.size();
      precision += scores.precision_micro / names.size();
    }
    EXPECT_GE(recall, floor.first) << method;
    EXPECT_GE(precision, floor.second) << method;
  }
}

}  // namespace
}  // namespace hidden_rooms::segmentation
