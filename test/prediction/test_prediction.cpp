// The prediction interface, the baselines, insertion, evaluation and the offline command.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/input_limits.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/evaluation/evaluation.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"
#include "test_util.h"

namespace hidden_rooms::prediction {
namespace {

std::pair<PredictionRequest, cv::Mat1w> hiddenRoomA() {
  PredictionRequest request;
  cv::Mat1w truth;
  testing::syntheticHiddenRoomA(&request.map, &request.doors, &truth);
  return {request, truth};
}

TEST(Evaluation, ScoresHandMadeLabelImages) {
  cv::Mat1b predicted = cv::Mat1b::zeros(4, 6), truth = cv::Mat1b::zeros(4, 6);
  predicted(cv::Rect(0, 0, 2, 2)).setTo(1);  // 4 cells, 2 of them right
  truth(cv::Rect(0, 0, 1, 2)).setTo(1);
  truth(cv::Rect(4, 0, 2, 2)).setTo(2);      // door 2: nothing predicted
  predicted(cv::Rect(4, 2, 1, 1)).setTo(3);  // door 3: predicted, no truth
  const evaluation::RoomScores scores = evaluation::scoreRooms(predicted, truth, 3);
  ASSERT_EQ(scores.iou.size(), 3u);
  EXPECT_DOUBLE_EQ(scores.iou[0], 2.0 / 4.0);
  EXPECT_DOUBLE_EQ(scores.iou[1], 0.0);
  EXPECT_DOUBLE_EQ(scores.iou[2], 0.0);
  EXPECT_DOUBLE_EQ(scores.mean_iou, 0.5 / 3.0);
  // Union of all predictions: 5 cells; of all truths: 6; together 2 common of 9.
  EXPECT_DOUBLE_EQ(scores.iou_total, 2.0 / 9.0);
  EXPECT_DOUBLE_EQ(evaluation::scoreRooms(truth, truth, 2).mean_iou, 1.0);
  cv::Mat1w wide = cv::Mat1w::zeros(4, 6);
  wide(0, 0) = 300;
  EXPECT_DOUBLE_EQ(evaluation::scoreRooms(wide, wide, 300).iou[299], 1.0);
  EXPECT_THROW(evaluation::scoreRooms(predicted, cv::Mat1b::zeros(5, 6), 3), common::InputError);
  EXPECT_THROW(evaluation::scoreRooms(cv::Mat3b::zeros(4, 6), truth, 3), common::InputError);
}

TEST(Prediction, MethodsAreChosenByName) {
  for (const std::string& name : roomPredictorNames()) EXPECT_EQ(makeRoomPredictor(name)->name(), name);
  EXPECT_NE(testing::inputErrorMessage([] { makeRoomPredictor("oracle"); })
                .find("unknown prediction method 'oracle' (known: "),
            std::string::npos);
}

TEST(Prediction, ParametersAreResolvedPerMethod) {
  const auto unstructured = makeRoomPredictor("unstructured");
  const auto resolved = resolveParameters(*unstructured, {{"start_search_radius", 2.0}, {"skewnormal_sigma", 1.0}});
  EXPECT_DOUBLE_EQ(resolved.at("start_search_radius"), 2.0);
  EXPECT_EQ(resolved.count("skewnormal_sigma"), 0u);  // another method's parameter: ignored
  EXPECT_THROW(resolveParameters(*unstructured, {{"start_serach_radius", 2.0}}), common::InputError);
  EXPECT_THROW(resolveParameters(*unstructured, {{"start_search_radius", std::nan("")}}), common::InputError);
}

TEST(Prediction, ShippedParameterFileEqualsTheDefaults) {
  const auto file = common::loadParameterFile(std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/config/prediction.yaml");
  std::map<std::string, double> defaults;
  for (const std::string& name : roomPredictorNames())
    for (const auto& [key, value] : makeRoomPredictor(name)->defaultParameters())
      defaults[key] = value;
  for (const auto& [key, value] : file) {
    ASSERT_TRUE(defaults.count(key)) << key << " is in config/prediction.yaml but no method reads it";
    EXPECT_DOUBLE_EQ(value, defaults[key]) << key;
  }
}

TEST(Prediction, BaselinesNeverPredictKnownCells) {
  const auto [request, truth] = hiddenRoomA();
  for (const std::string& name : roomPredictorNames()) {
    SCOPED_TRACE(name);
    const PredictionResult result = makeRoomPredictor(name)->predict(request);
    ASSERT_EQ(result.rooms.size(), 1u);
    const RoomPrediction& room = result.rooms[0];
    EXPECT_TRUE(room.placed) << room.problem;
    EXPECT_EQ(room.door_id, 1);
    EXPECT_EQ(cv::countNonZero(room.mask & (request.map.cells != common::OccupancyGrid::kUnknown)), 0);
    EXPECT_NEAR(room.area, cv::countNonZero(room.mask) * 0.0025, 1e-9);
    EXPECT_GE(room.polygon.size(), 3u);
  }
}

TEST(Prediction, UnstructuredRecoversAWalledHiddenRoom) {
  const auto [request, truth] = hiddenRoomA();
  const PredictionResult result = makeRoomPredictor("unstructured")->predict(request);
  const evaluation::RoomScores scores =
      evaluation::scoreRooms(roomLabels(request.map, request.doors, result.rooms), truth, 1);
  EXPECT_GT(scores.mean_iou, 0.9);
}

TEST(Prediction, SkewNormalExtrapolatesIntoTheUnknownSide) {
  auto [request, truth] = hiddenRoomA();
  const PredictionResult result = makeRoomPredictor("skewnormal")->predict(request);
  const cv::Mat1b& mask = result.rooms[0].mask;
  EXPECT_GT(cv::countNonZero(mask & (truth == 1)), 0.2 * cv::countNonZero(truth == 1));
  // A higher threshold keeps a smaller region.
  request.parameters["skewnormal_p_th"] = 0.8;
  EXPECT_LT(cv::countNonZero(makeRoomPredictor("skewnormal")->predict(request).rooms[0].mask), cv::countNonZero(mask));
  request.parameters["skewnormal_p_th"] = 1.5;
  EXPECT_THROW(makeRoomPredictor("skewnormal")->predict(request), common::InputError);
}

TEST(Prediction, DoorsThatCannotBePlacedAreReportedAndTheOthersStillPredicted) {
  auto [request, truth] = hiddenRoomA();
  common::MapDoor outside = request.doors.doors[0];
  outside.id = 9;
  outside.position = common::Point2(100.0, 100.0);
  common::MapDoor in_the_open = request.doors.doors[0];
  in_the_open.id = 10;
  in_the_open.position = common::Point2(7.0, 2.3);  // inside room B: no unknown cell within 2 m
  request.doors.doors = {outside, request.doors.doors[0], in_the_open};
  for (const std::string& name : roomPredictorNames()) {
    SCOPED_TRACE(name);
    const PredictionResult result = makeRoomPredictor(name)->predict(request);
    ASSERT_EQ(result.rooms.size(), 3u);
    EXPECT_FALSE(result.rooms[0].placed);
    EXPECT_NE(result.rooms[0].problem.find("outside the map"), std::string::npos) << result.rooms[0].problem;
    EXPECT_TRUE(result.rooms[1].placed);
    EXPECT_FALSE(result.rooms[2].placed);
    EXPECT_EQ(cv::countNonZero(result.rooms[2].mask), 0);
  }
}

TEST(Prediction, EmptyOrUnknownMapsAreRejected) {
  PredictionRequest request;
  for (const std::string& name : roomPredictorNames())
    EXPECT_THROW(makeRoomPredictor(name)->predict(request), common::InputError);
  request.map.cells = cv::Mat_<int8_t>(10, 10, common::OccupancyGrid::kUnknown);
  for (const std::string& name : roomPredictorNames())
    EXPECT_THROW(makeRoomPredictor(name)->predict(request), common::InputError);
}

// Sizes beyond common/input_limits.h are refused by every method before any work, naming the limit.
TEST(Prediction, RequestsBeyondTheLimitsAreRefused) {
  auto [request, truth] = hiddenRoomA();
  PredictionRequest many_doors = request;
  for (int id = 100; many_doors.doors.doors.size() <= common::kMaxDoors; ++id) {
    common::MapDoor door = request.doors.doors[0];
    door.id = id;
    many_doors.doors.doors.push_back(door);
  }
  PredictionRequest huge_map = request;
  huge_map.map.cells = cv::Mat_<int8_t>(5001, 5000, common::OccupancyGrid::kFree);
  PredictionRequest doors_on_a_large_map = huge_map;
  doors_on_a_large_map.map.cells = cv::Mat_<int8_t>(4000, 4000, common::OccupancyGrid::kFree);
  doors_on_a_large_map.doors.doors.resize(100, request.doors.doors[0]);
  for (const std::string& name : roomPredictorNames()) {
    SCOPED_TRACE(name);
    const std::unique_ptr<RoomPredictor> predictor = makeRoomPredictor(name);
    EXPECT_NE(testing::inputErrorMessage([&] { predictor->predict(many_doors); })
                  .find("the number of doors is 501, more than the limit of 500"),
              std::string::npos);
    EXPECT_NE(testing::inputErrorMessage([&] { predictor->predict(huge_map); })
                  .find("the number of cells is 25005000, more than the limit of 25000000"),
              std::string::npos);
    EXPECT_NE(testing::inputErrorMessage([&] { predictor->predict(doors_on_a_large_map); })
                  .find("doors x map cells is 1600000000"),
              std::string::npos);
  }
}

TEST(Prediction, InsertionFillsTheRoomAndOpensItsDoor) {
  const auto [request, truth] = hiddenRoomA();
  const PredictionResult result = makeRoomPredictor("unstructured")->predict(request);
  const common::OccupancyGrid completed = insertRooms(request.map, request.doors, result.rooms);
  EXPECT_EQ(cv::countNonZero((completed.cells == common::OccupancyGrid::kFree) & result.rooms[0].mask),
            cv::countNonZero(result.rooms[0].mask));
  // The door is open: from the corridor the flood reaches the inserted room.
  int col = 0, row = 0;
  ASSERT_TRUE(completed.cellOf(common::Point2(5.0, 5.0), &col, &row));
  const cv::Mat1b reached = common::reachableFreeCells(completed, col, row);
  EXPECT_GT(cv::countNonZero(reached & result.rooms[0].mask), 0.9 * cv::countNonZero(result.rooms[0].mask));
  // Nothing known in the input is lost except the door's own cells (within its half width of its centre, plus a
  // cell), and the input map is left as it was.
  std::vector<cv::Point> opened;
  cv::findNonZero((request.map.cells == common::OccupancyGrid::kOccupied) &
                      (completed.cells == common::OccupancyGrid::kFree),
                  opened);
  EXPECT_GT(opened.size(), 0u);
  const common::MapDoor& door = request.doors.doors[0];
  for (const cv::Point& cell : opened)
    EXPECT_LE((request.map.cellCentre(cell.x, cell.y) - door.position).norm(),
              0.5 * door.width + 1.5 * request.map.resolution);
  EXPECT_EQ(cv::countNonZero((request.map.cells == common::OccupancyGrid::kUnknown) & result.rooms[0].mask),
            cv::countNonZero(result.rooms[0].mask));
}

// Two overlapping square rooms on a 20 x 10 unknown map (0.1 m cells): room 1 covers columns 2..11, room 2
// columns 8..17; the doors sit on the left and right edges.
struct OverlappingRooms {
  common::OccupancyGrid map;
  common::DoorsFile doors;
  std::vector<RoomPrediction> rooms;
};

OverlappingRooms overlappingRooms() {
  OverlappingRooms s;
  s.map.cells = cv::Mat_<int8_t>(10, 20, common::OccupancyGrid::kUnknown);
  s.map.cells(cv::Rect(0, 0, 20, 1)).setTo(common::OccupancyGrid::kFree);
  s.map.resolution = 0.1;
  s.doors.doors = {{1, common::Point2(0.2, 0.5), 0.9, common::DoorOrientation::kAlongY, std::nullopt},
                   {2, common::Point2(1.8, 0.5), 0.9, common::DoorOrientation::kAlongY, std::nullopt}};
  for (int k = 0; k < 2; ++k) {
    RoomPrediction room;
    room.door_id = k + 1;
    room.mask = cv::Mat1b::zeros(s.map.cells.size());
    room.mask(cv::Rect(k == 0 ? 2 : 8, 2, 10, 6)).setTo(255);
    finishPrediction(s.map, &room);
    s.rooms.push_back(room);
  }
  return s;
}

TEST(Prediction, OverlappingCellsAreLabelledWithTheNearestDoor) {
  const OverlappingRooms s = overlappingRooms();
  const cv::Mat1w labels = roomLabels(s.map, s.doors, s.rooms);
  EXPECT_EQ(labels(4, 2), 1);
  EXPECT_EQ(labels(4, 17), 2);
  EXPECT_EQ(labels(4, 9), 1);   // overlap, x 0.95 m: 0.75 m from door 1, 0.85 m from door 2
  EXPECT_EQ(labels(4, 10), 2);  // overlap, x 1.05 m: 0.85 m and 0.75 m
  EXPECT_EQ(labels(4, 11), 2);
  EXPECT_EQ(labels(0, 5), 0);
  EXPECT_EQ(cv::countNonZero(labels), 16 * 6);
}

TEST(Prediction, FinishingWithinABoxEqualsFinishingOnTheWholeImage) {
  OverlappingRooms s = overlappingRooms();
  RoomPrediction boxed = s.rooms[1];
  finishPrediction(s.map, &boxed, cv::Rect(5, 0, 15, 10));
  EXPECT_TRUE(boxed.placed);
  EXPECT_DOUBLE_EQ(boxed.area, s.rooms[1].area);
  EXPECT_EQ(boxed.polygon, s.rooms[1].polygon);
  boxed.mask.setTo(0);
  finishPrediction(s.map, &boxed, cv::Rect(5, 0, 15, 10));
  EXPECT_FALSE(boxed.placed);
  EXPECT_EQ(boxed.problem, "no room predicted");
}

TEST(Prediction, OverlayTintsPredictedRoomsAndOutlinesTheTrueOnes) {
  const OverlappingRooms s = overlappingRooms();
  const cv::Mat1w labels = roomLabels(s.map, s.doors, s.rooms);
  const cv::Mat1b grey = s.map.toGreyImage();
  const cv::Mat3b tinted = renderPredictionOverlay(s.map, labels, cv::Mat());
  ASSERT_EQ(tinted.size(), s.map.cells.size());
  for (const cv::Point& cell : {cv::Point(0, 0), cv::Point(0, 9), cv::Point(19, 5)})  // no room there
    EXPECT_EQ(tinted(cell), cv::Vec3b(grey(cell), grey(cell), grey(cell)));
  for (const cv::Point& cell : {cv::Point(2, 2), cv::Point(9, 7), cv::Point(10, 2), cv::Point(17, 7)}) {
    const cv::Vec3b colour = common::roomColour(labels(cell));
    for (int channel = 0; channel < 3; ++channel)
      EXPECT_NEAR(tinted(cell)[channel], 0.4 * grey(cell) + 0.6 * colour[channel], 1.0) << cell;
  }
  // With true rooms: each is outlined in green, its middle is not; the tint elsewhere stays.
  cv::Mat1b truth = cv::Mat1b::zeros(s.map.cells.size());
  truth(cv::Rect(1, 1, 8, 8)).setTo(1);
  truth(cv::Rect(11, 1, 8, 8)).setTo(2);
  const cv::Mat3b outlined = renderPredictionOverlay(s.map, labels, truth);
  const cv::Vec3b green(0, 160, 0);
  for (const cv::Point& cell : {cv::Point(1, 1), cv::Point(8, 8), cv::Point(11, 4), cv::Point(18, 8)})
    EXPECT_EQ(outlined(cell), green) << cell;
  for (const cv::Point& cell : {cv::Point(5, 5), cv::Point(15, 4)}) {
    EXPECT_NE(outlined(cell), green) << cell;
    EXPECT_EQ(outlined(cell), tinted(cell)) << cell;
  }
}

// Floors a little under the measured means (unstructured 0.477, structured 0.447, skewnormal 0.220 over the 44
// valid cases), so that a regression fails.
TEST(Prediction, BaselinesKeepTheirAccuracyOnTheBenchmark) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  int cases = 0;
  EXPECT_GE(testing::benchmarkMeanIou("unstructured", &cases), 0.46);
  EXPECT_EQ(cases, 44);
  EXPECT_GE(testing::benchmarkMeanIou("structured"), 0.43);
  EXPECT_GE(testing::benchmarkMeanIou("skewnormal"), 0.21);
}

}  // namespace
}  // namespace hidden_rooms::prediction
