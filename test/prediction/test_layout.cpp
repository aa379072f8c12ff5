#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/prediction/layout.h"
#include "hidden_rooms/prediction/layout_debug.h"
#include "hidden_rooms/prediction/structured_predictor.h"
#include "hidden_rooms/prediction/thesis_predictor.h"
#include "test_util.h"

namespace hidden_rooms::prediction {
namespace {

// ---------------------------------------------------------------------------------------------------------
// A synthetic floor, drawn in "base pixels" of 0.05 m and rendered at `scale` pixels per base pixel
// (resolution 0.05 / scale), 300 x 200 base pixels. Walls are 4 base pixels thick:
//   room A: interior x [20, 140), y [20, 116), open door to the corridor at x [60, 78)
//   room B: interior x [144, 280), y [20, 116), hidden: interior and the walls only it sees erased to unknown;
//           its closed door is part of the corridor's top wall, centred at (212, 118)
//   corridor: interior x [20, 280), y [120, 160)
struct SyntheticFloor {
  common::OccupancyGrid map;
  common::DoorsFile doors;
  cv::Mat1b hidden_room;  // true interior of room B
  int scale = 1;
  // Centre of a base-pixel position in image coordinates.
  common::Point2 image(double x, double y) const { return common::Point2(x * scale, y * scale); }
};

SyntheticFloor makeFloor(int scale) {
  SyntheticFloor floor;
  floor.scale = scale;
  const auto rect = [scale](int x0, int y0, int x1, int y1) {
    return cv::Rect(x0 * scale, y0 * scale, (x1 - x0) * scale, (y1 - y0) * scale);
  };
  cv::Mat1b grey(200 * scale, 300 * scale, uint8_t(205));
  grey(rect(16, 16, 284, 164)).setTo(0);      // outer walls and everything in between
  grey(rect(20, 20, 140, 116)).setTo(254);    // room A
  grey(rect(144, 20, 280, 116)).setTo(254);   // room B (erased below)
  grey(rect(20, 120, 280, 160)).setTo(254);   // corridor
  grey(rect(60, 116, 78, 120)).setTo(254);    // room A's open door
  // Room B hidden behind its closed door: its interior and the walls seen only from it become unknown.
  grey(rect(144, 20, 280, 116)).setTo(205);
  grey(rect(144, 16, 284, 20)).setTo(205);    // top wall
  grey(rect(280, 16, 284, 116)).setTo(205);   // right wall
  floor.hidden_room = cv::Mat1b::zeros(grey.size());
  floor.hidden_room(rect(144, 20, 280, 116)).setTo(255);

  floor.map.resolution = 0.05 / scale;
  floor.map.origin = common::Point2(-2.0, 1.0);
  floor.map.cells.create(grey.size());
  for (int r = 0; r < grey.rows; ++r)
    for (int c = 0; c < grey.cols; ++c)
      floor.map.cells(r, c) = grey(r, c) == 0     ? common::OccupancyGrid::kOccupied
                              : grey(r, c) == 254 ? common::OccupancyGrid::kFree
                                                  : common::OccupancyGrid::kUnknown;
  common::MapDoor door;
  door.id = 7;
  door.width = 0.9;
  door.orientation = common::DoorOrientation::kAlongX;
  const common::Point2 door_image = floor.image(212, 118);
  door.position = floor.map.origin + floor.map.resolution * common::Point2(door_image.x(), grey.rows - door_image.y());
  floor.doors.doors.push_back(door);
  return floor;
}

double iou(const cv::Mat1b& a, const cv::Mat1b& b) {
  const double united = cv::countNonZero(a | b);
  return united > 0 ? cv::countNonZero(a & b) / united : 0.0;
}

// Distance in pixels from `position` to the nearest extended line of `axis` that comes from a wall.
double distanceToWallLine(const Layout& layout, LineAxis axis, double position) {
  double best = 1e9;
  for (const ExtendedLine& line : layout.lines)
    if (line.axis == axis && line.source == LineSource::kWall)
      best = std::min(best, std::abs(line.position - position));
  return best;
}

TEST(Layout, SyntheticFloorGivesWallLinesCellsRoomsAndStartCell) {
  for (int scale : {1, 2}) {
    SCOPED_TRACE("scale " + std::to_string(scale));
    const SyntheticFloor floor = makeFloor(scale);
    const Layout layout = analyzeLayout(floor.map, floor.doors.doors);
    ASSERT_FALSE(layout.segments.empty());

    // Axis-aligned lines at the walls' centres (within 2 base pixels): vertical at x = 18, 142, 282 and
    // horizontal at y = 18, 118, 162; every wall line is at one of those walls.
    const double tolerance = 2.0 * scale;
    for (double x : {18, 142, 282})
      EXPECT_LE(distanceToWallLine(layout, LineAxis::kVertical, x * scale), tolerance) << x;
    for (double y : {18, 118, 162})
      EXPECT_LE(distanceToWallLine(layout, LineAxis::kHorizontal, y * scale), tolerance) << y;
    for (const ExtendedLine& line : layout.lines) {
      if (line.source != LineSource::kWall) continue;
      const std::vector<double> walls = line.axis == LineAxis::kVertical ? std::vector<double>{18, 142, 282}
                                                                         : std::vector<double>{18, 118, 162};
      double nearest = 1e9;
      for (double wall : walls) nearest = std::min(nearest, std::abs(line.position - wall * scale));
      EXPECT_LE(nearest, tolerance) << "stray wall line at " << line.position;
    }
    // Exactly four boundary lines, outside the walls.
    EXPECT_EQ(std::count_if(layout.lines.begin(), layout.lines.end(),
                            [](const ExtendedLine& line) { return line.source == LineSource::kBoundary; }),
              4);

    const CellGrid& grid = layout.grid;
    const int room_a = grid.cellAt(floor.image(80, 68));
    const int room_b = grid.cellAt(floor.image(212, 68));
    const int corridor_left = grid.cellAt(floor.image(80, 140));
    const int corridor_right = grid.cellAt(floor.image(212, 140));
    const int outside = grid.cellAt(floor.image(2, 2));
    ASSERT_TRUE(room_a >= 0 && room_b >= 0 && corridor_left >= 0 && corridor_right >= 0 && outside >= 0);
    EXPECT_FALSE(grid.cells[room_a].out);
    EXPECT_TRUE(grid.cells[room_b].out);
    EXPECT_FALSE(grid.cells[room_b].border);
    EXPECT_FALSE(grid.cells[corridor_left].out);
    EXPECT_FALSE(grid.cells[corridor_right].out);
    EXPECT_TRUE(grid.cells[outside].out);
    EXPECT_TRUE(grid.cells[outside].border);
    // Room A is walled off from the corridor (its door is narrow); the corridor is one room.
    EXPECT_NE(grid.cells[room_a].room, grid.cells[corridor_left].room);
    EXPECT_EQ(grid.cells[corridor_left].room, grid.cells[corridor_right].room);
    EXPECT_GT(grid.wallFraction(room_a, corridor_left), 0.5);

    // The closed door starts in room B's cell, entered from the corridor, on the wall line.
    ASSERT_EQ(layout.doors.size(), 1u);
    const DoorStart& start = layout.doors[0];
    EXPECT_EQ(start.door_id, 7);
    ASSERT_TRUE(start.found) << start.problem;
    EXPECT_EQ(start.start_cell, room_b);
    EXPECT_EQ(start.explored_cell, corridor_right);
    EXPECT_LT(start.distance, 0.15);
    EXPECT_LT((start.position - floor.doors.doors[0].position).norm(), 0.2);
  }
}

TEST(Structured, RecoversTheErasedRectangularRoom) {
  for (int scale : {1, 2}) {
    SCOPED_TRACE("scale " + std::to_string(scale));
    const SyntheticFloor floor = makeFloor(scale);
    PredictionRequest request;
    request.map = floor.map;
    request.doors = floor.doors;
    const PredictionResult result = StructuredPredictor().predict(request);
    ASSERT_EQ(result.rooms.size(), 1u);
    const RoomPrediction& room = result.rooms[0];
    EXPECT_EQ(room.door_id, 7);
    ASSERT_TRUE(room.placed) << room.problem;
    EXPECT_GT(iou(room.mask, floor.hidden_room), 0.9);
    EXPECT_EQ(cv::countNonZero(room.mask & (floor.map.cells != common::OccupancyGrid::kUnknown)), 0);
    EXPECT_NEAR(room.area, cv::countNonZero(room.mask) * floor.map.resolution * floor.map.resolution, 1e-9);
    // Room B's interior is 6.8 m x 4.8 m; the prediction adds the erased walls' cells on the cell's edges.
    EXPECT_GT(room.area, 6.8 * 4.8);
    EXPECT_LT(room.area, 1.1 * 6.8 * 4.8);
    EXPECT_NEAR(common::area(room.polygon), room.area, 0.05 * room.area);
    EXPECT_EQ(room.terms.at("cells"), 1.0);
  }
}

TEST(Structured, DoorOutsideTheMapOrFarFromUnknownIsNotPlacedOthersAre) {
  SyntheticFloor floor = makeFloor(1);
  common::MapDoor outside;
  outside.id = 8;
  outside.position = floor.map.origin + common::Point2(-5.0, -5.0);
  common::MapDoor in_room_a;  // the middle of room A: no unknown cell edge within 2 m
  in_room_a.id = 9;
  in_room_a.position = floor.map.origin + 0.05 * common::Point2(80, 200 - 68);
  floor.doors.doors.insert(floor.doors.doors.begin(), outside);
  floor.doors.doors.push_back(in_room_a);

  PredictionRequest request;
  request.map = floor.map;
  request.doors = floor.doors;
  const PredictionResult result = StructuredPredictor().predict(request);
  ASSERT_EQ(result.rooms.size(), 3u);
  EXPECT_EQ(result.rooms[0].door_id, 8);
  EXPECT_FALSE(result.rooms[0].placed);
  EXPECT_NE(result.rooms[0].problem.find("outside the map"), std::string::npos) << result.rooms[0].problem;
  EXPECT_EQ(cv::countNonZero(result.rooms[0].mask), 0);
  EXPECT_EQ(result.rooms[1].door_id, 7);
  EXPECT_TRUE(result.rooms[1].placed);
  EXPECT_GT(iou(result.rooms[1].mask, floor.hidden_room), 0.9);
  EXPECT_EQ(result.rooms[2].door_id, 9);
  EXPECT_FALSE(result.rooms[2].placed);
  EXPECT_NE(result.rooms[2].problem.find("within 2 m"), std::string::npos) << result.rooms[2].problem;
}

TEST(Structured, RejectsUnknownParametersAndEmptyMapsAndAppliesLayoutParameters) {
  const SyntheticFloor floor = makeFloor(1);
  PredictionRequest request;
  request.map = floor.map;
  request.doors = floor.doors;
  const StructuredPredictor predictor;
  EXPECT_EQ(predictor.name(), "structured");

  request.parameters = {{"no_such_parameter", 1.0}};
  try {
    predictor.predict(request);
    FAIL() << "unknown parameter accepted";
  } catch (const common::InputError& error) {
    EXPECT_EQ(error.source(), "parameters");
    EXPECT_NE(error.problem().find("no_such_parameter"), std::string::npos) << error.what();
  }
  request.parameters = {{"canny_aperture", 4.0}};
  EXPECT_THROW(predictor.predict(request), common::InputError);

  // Layout parameters take effect: with every cell counted IN and no fallback, no door finds unknown space.
  request.parameters = {{"out_unknown_fraction", 1.0}, {"door_start_fallback", 0.0}};
  const PredictionResult all_in = predictor.predict(request);
  ASSERT_EQ(all_in.rooms.size(), 1u);
  EXPECT_FALSE(all_in.rooms[0].placed);

  PredictionRequest empty;
  empty.doors = floor.doors;
  EXPECT_THROW(predictor.predict(empty), common::InputError);
  EXPECT_THROW(analyzeLayout(common::OccupancyGrid(), {}), common::InputError);

  // The predictor reads exactly the layout parameters.
  std::map<std::string, double> defaults = predictor.defaultParameters();
  EXPECT_EQ(defaults, layoutParameters(LayoutOptions()));
}

// No segments: the boundary lines surround the image, one border cell (pixels past the image count as unknown).
TEST(Layout, MapsWithoutWallsGiveOneBorderCellAndNoStart) {
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(7, 5), cv::Size(40, 30)})
    for (const int8_t value : {common::OccupancyGrid::kUnknown, common::OccupancyGrid::kFree}) {
      SCOPED_TRACE(std::to_string(size.width) + "x" + std::to_string(size.height) + " of " + std::to_string(value));
      common::OccupancyGrid map;
      map.cells = cv::Mat_<int8_t>(size, value);
      common::MapDoor door;
      door.id = 1;
      door.position = map.cellCentre(0, 0);
      const Layout layout = analyzeLayout(map, {door});
      EXPECT_TRUE(layout.segments.empty());
      ASSERT_EQ(layout.grid.size(), 1);
      EXPECT_TRUE(layout.grid.cells[0].border);
      EXPECT_TRUE(value != common::OccupancyGrid::kUnknown || layout.grid.cells[0].out);
      ASSERT_EQ(layout.doors.size(), 1u);
      EXPECT_FALSE(layout.doors[0].found);
      EXPECT_FALSE(layout.doors[0].problem.empty());
    }
}

// A free map of 200 x 200 pixels of 0.05 m with the given wall pixels.
common::OccupancyGrid freeMapWithWalls(const std::function<void(cv::Mat1b*)>& draw) {
  cv::Mat1b walls = cv::Mat1b::zeros(200, 200);
  draw(&walls);
  common::OccupancyGrid map;
  map.resolution = 0.05;
  map.cells = cv::Mat_<int8_t>(walls.size(), common::OccupancyGrid::kFree);
  map.cells.setTo(common::OccupancyGrid::kOccupied, walls);
  return map;
}

int verticalWallLinesBetween(const Layout& layout, int x0, int x1) {
  return static_cast<int>(std::count_if(layout.lines.begin(), layout.lines.end(), [&](const ExtendedLine& line) {
    return line.source == LineSource::kWall && line.axis == LineAxis::kVertical && line.position >= x0 &&
           line.position <= x1;
  }));
}

// Angular clustering: a horizontal wall and one turned by 2 degrees (0.035 rad) are one angular cluster under the
// reference code's kernel (its bandwidth 0.023 is 1 - cos of the angle: it reaches 12.3 degrees) and two under a
// flat window of 0.023 rad.
TEST(Layout, TheReferenceKernelMeasuresItsBandwidthAsOneMinusCosine) {
  const common::OccupancyGrid map = freeMapWithWalls([](cv::Mat1b* walls) {
    cv::line(*walls, cv::Point(20, 50), cv::Point(180, 50), 255, 3);
    const double slope = std::tan(2.0 * CV_PI / 180.0);
    cv::line(*walls, cv::Point(20, 140), cv::Point(180, static_cast<int>(std::lround(140 + 160 * slope))), 255, 3);
  });
  LayoutOptions options;
  options.angular_kernel = 0;
  EXPECT_EQ(analyzeLayout(map, {}, options).angular_modes.size(), 2u);
  options.angular_kernel = 1;
  const Layout layout = analyzeLayout(map, {}, options);
  ASSERT_EQ(layout.angular_modes.size(), 1u);
  EXPECT_LT(std::abs(std::remainder(layout.angular_modes[0], CV_PI)), 2.0 * CV_PI / 180.0);
}

// Wall clustering: faces at x = 100, 106 (a 6 px wall) and 112, 114 (a 2 px wall beside it). Chained (the reference
// code's), each face is less than 10 px (0.5 m) from the previous one: one wall, at one of the two middle faces
// (106 or 112). With a bounded spread, the faces within 10 px of the first make a wall (100, 106) and the rest
// another: two lines, farther apart than line_merge_distance.
TEST(Layout, ChainedWallsJoinFacesThatFollowEachOtherClosely) {
  const common::OccupancyGrid map = freeMapWithWalls([](cv::Mat1b* walls) {
    (*walls)(cv::Rect(100, 30, 6, 140)).setTo(255);
    (*walls)(cv::Rect(112, 30, 2, 140)).setTo(255);
  });
  LayoutOptions options;
  options.wall_chaining = false;
  EXPECT_EQ(verticalWallLinesBetween(analyzeLayout(map, {}, options), 95, 120), 2);
  options.wall_chaining = true;
  const Layout chained = analyzeLayout(map, {}, options);
  ASSERT_EQ(verticalWallLinesBetween(chained, 95, 120), 1);
  EXPECT_EQ(verticalWallLinesBetween(chained, 105, 112), 1);
}

// A wall at 45 degrees gives no line with diagonal_limit 0.15 rad (the reference code deletes its segments) and
// one along an axis without it.
TEST(Layout, DiagonalWallsAreDroppedBeyondTheLimit) {
  const common::OccupancyGrid map = freeMapWithWalls([](cv::Mat1b* walls) {
    cv::line(*walls, cv::Point(40, 40), cv::Point(160, 160), 255, 3);
  });
  const auto wall_lines = [&](double limit) {
    LayoutOptions options;
    options.diagonal_limit = limit;
    const Layout layout = analyzeLayout(map, {}, options);
    return std::count_if(layout.lines.begin(), layout.lines.end(),
                         [](const ExtendedLine& line) { return line.source == LineSource::kWall; });
  };
  EXPECT_GT(wall_lines(0.0), 0);
  EXPECT_EQ(wall_lines(0.15), 0);
}

// A door whose hidden room shows only as a small unknown pocket in a cell that is mostly free (IN, counting unknown
// pixels only): no IN/OUT edge is near it, so it is not placed; with door_start_fallback it starts at the pocket's
// cell, across the edge it lies on from the corridor.
TEST(Layout, ADoorBesideNoOutCellStartsAtTheMoreUnknownCellWithTheFallback) {
  SyntheticFloor floor = makeFloor(1);
  floor.map.cells(cv::Rect(144, 20, 136, 96)).setTo(common::OccupancyGrid::kFree);      // room B seen ...
  floor.map.cells(cv::Rect(190, 100, 50, 16)).setTo(common::OccupancyGrid::kUnknown);  // ... but a pocket
  LayoutOptions options;
  options.explored_outline = false;
  options.door_start_fallback = false;
  const Layout without = analyzeLayout(floor.map, floor.doors.doors, options);
  ASSERT_EQ(without.doors.size(), 1u);
  EXPECT_FALSE(without.doors[0].found);
  const int room_b = without.grid.cellAt(floor.image(212, 68));
  ASSERT_GE(room_b, 0);
  EXPECT_FALSE(without.grid.cells[room_b].out);
  options.door_start_fallback = true;
  const Layout with = analyzeLayout(floor.map, floor.doors.doors, options);
  ASSERT_TRUE(with.doors[0].found) << with.doors[0].problem;
  EXPECT_EQ(with.doors[0].start_cell, with.grid.cellAt(floor.image(212, 68)));
  EXPECT_EQ(with.doors[0].explored_cell, with.grid.cellAt(floor.image(212, 140)));
  // The thesis method (fallback on by default) then grows the room from that cell: all of the pocket, and no known
  // pixel.
  PredictionRequest request;
  request.map = floor.map;
  request.doors = floor.doors;
  request.parameters["explored_outline"] = 0;
  const PredictionResult result = ThesisPredictor().predict(request);
  ASSERT_EQ(result.rooms.size(), 1u);
  ASSERT_TRUE(result.rooms[0].placed) << result.rooms[0].problem;
  cv::Mat1b pocket = cv::Mat1b::zeros(floor.map.cells.size());
  pocket(cv::Rect(190, 100, 50, 16)).setTo(255);
  EXPECT_EQ(cv::countNonZero(pocket & ~result.rooms[0].mask), 0);
  EXPECT_EQ(cv::countNonZero(result.rooms[0].mask & (floor.map.cells != common::OccupancyGrid::kUnknown)), 0);
}

// The explored outline: room B seen apart from the explored corridor (through no open door) does not make its cell
// IN, so the closed door between them starts there with no fallback; an unknown pocket inside the outline (a
// closed room the corridor runs around) stays outside, so its cell is OUT.
TEST(Layout, OnlyFreeSpaceInsideTheExploredOutlineMakesACellIn) {
  SyntheticFloor floor = makeFloor(1);
  floor.map.cells(cv::Rect(144, 20, 136, 96)).setTo(common::OccupancyGrid::kFree);      // room B seen apart
  floor.map.cells(cv::Rect(190, 100, 50, 16)).setTo(common::OccupancyGrid::kUnknown);  // with a pocket
  LayoutOptions options;
  options.door_start_fallback = false;
  ASSERT_TRUE(options.explored_outline);
  const Layout layout = analyzeLayout(floor.map, floor.doors.doors, options);
  ASSERT_TRUE(layout.doors[0].found) << layout.doors[0].problem;
  const int room_b = layout.grid.cellAt(floor.image(212, 68));
  EXPECT_EQ(layout.doors[0].start_cell, room_b);
  EXPECT_TRUE(layout.grid.cells[room_b].out);
  EXPECT_LT(layout.grid.cells[room_b].unknown_fraction, 0.2);  // IN by its unknown pixels alone
  EXPECT_FALSE(layout.grid.cells[layout.doors[0].explored_cell].out);

  // A closed square room in the middle of a free hall: inside the hall's outline, but unknown, so OUT.
  common::OccupancyGrid hall;
  hall.resolution = 0.05;
  hall.cells = cv::Mat_<int8_t>(200, 200, common::OccupancyGrid::kUnknown);
  hall.cells(cv::Rect(20, 20, 160, 160)).setTo(common::OccupancyGrid::kOccupied);
  hall.cells(cv::Rect(24, 24, 152, 152)).setTo(common::OccupancyGrid::kFree);
  hall.cells(cv::Rect(70, 70, 60, 60)).setTo(common::OccupancyGrid::kOccupied);
  hall.cells(cv::Rect(74, 74, 52, 52)).setTo(common::OccupancyGrid::kUnknown);
  const Layout around = analyzeLayout(hall, {}, options);
  const int inner = around.grid.cellAt(common::Point2(100, 100));
  ASSERT_GE(inner, 0);
  EXPECT_TRUE(around.grid.cells[inner].out);
  EXPECT_FALSE(around.grid.cells[around.grid.cellAt(common::Point2(40, 100))].out);
}

TEST(Layout, ParametersByNameValidateAndRejectUnknownNames) {
  const std::vector<std::string>& names = layoutParameterNames();
  const std::map<std::string, double> defaults = layoutParameters(LayoutOptions());
  ASSERT_EQ(names.size(), defaults.size());
  for (const std::string& name : names) EXPECT_EQ(defaults.count(name), 1u) << name;

  const LayoutOptions options = layoutOptionsFromParameters({{"wall_cluster_distance", 0.35}, {"dbscan_eps", 0.5}});
  EXPECT_DOUBLE_EQ(options.wall_cluster_distance, 0.35);
  EXPECT_DOUBLE_EQ(options.dbscan_eps, 0.5);
  try {
    layoutOptionsFromParameters({{"x", 1.0}});
    FAIL() << "unknown parameter accepted";
  } catch (const common::InputError& error) {
    EXPECT_EQ(error.source(), "parameters");
    EXPECT_EQ(error.problem(), "unknown parameter 'x'");
  }
  // applyLayoutParameters skips other methods' names but still validates values.
  LayoutOptions applied;
  applyLayoutParameters({{"skewnormal_sigma", 3.0}, {"boundary_offset", 2.0}}, &applied);
  EXPECT_DOUBLE_EQ(applied.boundary_offset, 2.0);
  EXPECT_THROW(applyLayoutParameters({{"dbscan_eps", 1.5}}, &applied), common::InputError);
  EXPECT_THROW(layoutOptionsFromParameters({{"dbscan_min_points", 0.5}}), common::InputError);
  EXPECT_THROW(layoutOptionsFromParameters({{"door_pair_lines", 2}}), common::InputError);
  EXPECT_THROW(layoutOptionsFromParameters({{"hough_threshold", -1}}), common::InputError);
}

TEST(Layout, ConfigFileEqualsCodeDefaults) {
  const std::string path = std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/config/layout.yaml";
  const YAML::Node root = YAML::LoadFile(path);
  ASSERT_TRUE(root.IsMap());
  const std::map<std::string, double> defaults = layoutParameters(LayoutOptions());
  std::map<std::string, double> in_file;
  for (const auto& entry : root) in_file[entry.first.as<std::string>()] = entry.second.as<double>();
  for (const auto& [name, value] : defaults) {
    ASSERT_EQ(in_file.count(name), 1u) << name << " missing from " << path;
    EXPECT_NEAR(in_file[name], value, 1e-12 * std::max(1.0, std::abs(value))) << name;
  }
  for (const auto& [name, value] : in_file)
    EXPECT_EQ(defaults.count(name), 1u) << name << " is not a layout parameter";
  // Same order as layoutParameterNames().
  std::vector<std::string> file_order;
  for (const auto& entry : root) file_order.push_back(entry.first.as<std::string>());
  EXPECT_EQ(file_order, layoutParameterNames());
}

TEST(Layout, WritesEveryDebugImageAndFailsOnAnUnwritableFolder) {
  const SyntheticFloor floor = makeFloor(1);
  const std::string dir = testing::makeTempDir("layout_debug") + "/stages";
  analyzeLayout(floor.map, floor.doors.doors, LayoutOptions(), dir);
  ASSERT_EQ(layoutDebugImageNames().size(), 9u);
  for (const std::string& name : layoutDebugImageNames()) {
    const cv::Mat image = cv::imread(dir + "/" + name, cv::IMREAD_UNCHANGED);
    EXPECT_FALSE(image.empty()) << name;
    EXPECT_GE(image.cols, floor.map.width()) << name;
  }
  const std::string file = testing::makeTempDir("layout_debug_blocked") + "/a_file";
  std::ofstream(file) << "not a folder";
  EXPECT_THROW(analyzeLayout(floor.map, floor.doors.doors, LayoutOptions(), file + "/stages"), common::InputError);
}

// ---------------------------------------------------------------------------------------------------------
// The closed-door benchmark (shared data).

std::string benchmarkDir() { return testing::sharedDir() + "/data/closed_door_benchmark"; }

struct BenchmarkCase {
  std::string name;  // env/case
  std::string dir;
};

std::vector<BenchmarkCase> validBenchmarkCases() {
  std::vector<BenchmarkCase> cases;
  std::ifstream csv(benchmarkDir() + "/cases.csv");
  std::string line;
  std::getline(csv, line);  // header: env,case,closed_doors_nominal,doors_found,valid,...
  while (std::getline(csv, line)) {
    std::vector<std::string> fields;
    std::stringstream stream(line);
    for (std::string field; std::getline(stream, field, ',');) fields.push_back(field);
    if (fields.size() < 5 || fields[4] != "1") continue;
    cases.push_back({fields[0] + "/" + fields[1], benchmarkDir() + "/" + fields[0] + "/" + fields[1]});
  }
  return cases;
}

std::vector<std::string> benchmarkFullMaps() {
  std::vector<std::string> maps;
  for (const auto& entry : std::filesystem::directory_iterator(benchmarkDir()))
    if (std::filesystem::exists(entry.path() / "full_map.yaml"))
      maps.push_back((entry.path() / "full_map.yaml").string());
  std::sort(maps.begin(), maps.end());
  return maps;
}

TEST(LayoutBenchmark, HoughSegmentsLieOnOccupiedPixels) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::vector<std::string> maps = benchmarkFullMaps();
  ASSERT_FALSE(maps.empty());
  for (const std::string& path : maps) {
    SCOPED_TRACE(path);
    const common::OccupancyGrid map = common::loadMap(path);
    const Layout layout = analyzeLayout(map, {});
    ASSERT_GT(layout.segments.size(), 50u);
    cv::Mat1f distance;  // pixels to the nearest occupied pixel
    cv::distanceTransform(cv::Mat1b(map.cells != common::OccupancyGrid::kOccupied), distance, cv::DIST_L2, 3);
    int samples = 0, near_wall = 0;
    for (const ImageSegment& segment : layout.segments) {
      const int steps = std::max(1, static_cast<int>(std::ceil(segment.length())));
      for (int k = 0; k <= steps; ++k) {
        const common::Point2 p = segment.a + (segment.b - segment.a) * (static_cast<double>(k) / steps);
        const int c = std::clamp(static_cast<int>(std::floor(p.x())), 0, map.width() - 1);
        const int r = std::clamp(static_cast<int>(std::floor(p.y())), 0, map.height() - 1);
        ++samples;
        near_wall += distance(r, c) <= 2.0f;
      }
    }
    EXPECT_GT(static_cast<double>(near_wall) / samples, 0.9);
    // Real rooms come out of the segmentation, and every grid line lies inside the boundary.
    EXPECT_GT(layout.room_count, 5);
    EXPECT_GT(layout.grid.columns(), 4);
    EXPECT_GT(layout.grid.rows(), 4);
  }
}

TEST(LayoutBenchmark, EveryClosedDoorOfValidCasesGetsAStartCell) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::vector<BenchmarkCase> cases = validBenchmarkCases();
  ASSERT_GE(cases.size(), 40u);
  int doors_placed = 0, fallback_starts = 0;
  for (const BenchmarkCase& benchmark : cases) {
    SCOPED_TRACE(benchmark.name);
    const common::OccupancyGrid map = common::loadMap(benchmark.dir + "/map.yaml");
    const common::DoorsFile doors = common::loadDoors(benchmark.dir + "/doors.yaml");
    const Layout layout = analyzeLayout(map, doors.doors);
    ASSERT_EQ(layout.doors.size(), doors.doors.size());
    for (const DoorStart& start : layout.doors) {
      ASSERT_TRUE(start.found) << "door " << start.door_id << ": " << start.problem;
      EXPECT_LE(start.distance, 2.0);
      ++doors_placed;
      const bool in_out = layout.grid.cells[start.start_cell].out && !layout.grid.cells[start.explored_cell].out;
      if (!in_out) ++fallback_starts;
    }
  }
  // The door-start fallback is for the odd door (a pocket of unknown space in a mostly explored cell).
  std::printf("benchmark doors: %d placed, %d of them by the fallback\n", doors_placed, fallback_starts);
  EXPECT_LE(fallback_starts * 20, doors_placed);
}

TEST(StructuredBenchmark, NeverPredictsKnownCellsAndReportsIoU) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::vector<BenchmarkCase> cases = validBenchmarkCases();
  ASSERT_GE(cases.size(), 40u);
  const StructuredPredictor predictor;
  std::map<int, std::vector<double>> by_door_count;
  std::vector<double> case_scores, seconds;
  for (const BenchmarkCase& benchmark : cases) {
    SCOPED_TRACE(benchmark.name);
    PredictionRequest request;
    request.map = common::loadMap(benchmark.dir + "/map.yaml");
    request.doors = common::loadDoors(benchmark.dir + "/doors.yaml");
    const auto start = std::chrono::steady_clock::now();
    const PredictionResult result = predictor.predict(request);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    const cv::Mat truth = cv::imread(benchmark.dir + "/gt_rooms.png", cv::IMREAD_UNCHANGED);
    ASSERT_EQ(truth.size(), request.map.cells.size());
    ASSERT_EQ(result.rooms.size(), request.doors.doors.size());
    const cv::Mat1b known = request.map.cells != common::OccupancyGrid::kUnknown;
    double total = 0;
    for (size_t k = 0; k < result.rooms.size(); ++k) {
      const RoomPrediction& room = result.rooms[k];
      EXPECT_TRUE(room.placed) << "door " << room.door_id << ": " << room.problem;
      EXPECT_EQ(cv::countNonZero(room.mask & known), 0) << "door " << room.door_id;
      total += iou(room.mask, cv::Mat1b(truth == static_cast<int>(k + 1)));
    }
    const double score = total / result.rooms.size();
    case_scores.push_back(score);
    by_door_count[static_cast<int>(result.rooms.size())].push_back(score);
  }
  const auto mean = [](const std::vector<double>& values) {
    double sum = 0;
    for (double v : values) sum += v;
    return values.empty() ? 0.0 : sum / values.size();
  };
  std::sort(seconds.begin(), seconds.end());
  std::printf("[ structured ] mean IoU %.3f over %zu valid cases; median %.3f s per case\n", mean(case_scores),
              case_scores.size(), seconds[seconds.size() / 2]);
  for (const auto& [doors, scores] : by_door_count)
    std::printf("[ structured ]   %2d closed doors: mean IoU %.3f (%zu cases)\n", doors, mean(scores), scores.size());
}

}  // namespace
}  // namespace hidden_rooms::prediction
