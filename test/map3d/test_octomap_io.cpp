// OctoMap export of 2D maps and slicing of 3D maps back to 2D: round trip, room colours, coarser voxels,
// prediction on a sliced map, bad input.
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/label_image.h"
#include "hidden_rooms/map3d/octomap_io.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "test_util.h"

namespace hidden_rooms::map3d {
namespace {

using testing::inputErrorMessage;

// The map cut to the bounding box of its known cells (what a slice of its extrusion covers).
common::OccupancyGrid cropToKnown(const common::OccupancyGrid& map) {
  const cv::Rect box = cv::boundingRect(map.cells != common::OccupancyGrid::kUnknown);
  common::OccupancyGrid cropped;
  cropped.resolution = map.resolution;
  cropped.cells = map.cells(box).clone();
  cropped.origin = map.origin + map.resolution * common::Point2(box.x, map.height() - box.y - box.height);
  return cropped;
}

void expectSameMap(const common::OccupancyGrid& actual, const common::OccupancyGrid& expected) {
  ASSERT_EQ(actual.cells.size(), expected.cells.size());
  EXPECT_NEAR(actual.resolution, expected.resolution, 1e-9);
  EXPECT_NEAR((actual.origin - expected.origin).norm(), 0.0, 1e-4);
  EXPECT_EQ(cv::countNonZero(actual.cells != expected.cells), 0);
}

TEST(OctomapIo, ExportThenSliceGivesTheMapBack) {
  common::OccupancyGrid map;
  common::DoorsFile doors;
  cv::Mat1w truth;
  testing::syntheticHiddenRoomA(&map, &doors, &truth);
  const common::OccupancyGrid known = cropToKnown(map);
  const std::string dir = testing::makeTempDir("octomap_round_trip");
  for (const std::string name : {"map.bt", "map.ot"}) {
    exportOctomap(map, cv::Mat1w(), ExtrusionOptions(), dir + "/" + name);
    SCOPED_TRACE(name);
    expectSameMap(sliceOctomap(dir + "/" + name, SliceOptions()), known);
  }
  // A band above the walls' height sees nothing known.
  SliceOptions above;
  above.z_min = 3.0;
  above.z_max = 4.0;
  const common::OccupancyGrid empty = sliceOctomap(dir + "/map.bt", above);
  EXPECT_EQ(cv::countNonZero(empty.cells != common::OccupancyGrid::kUnknown), 0);
}

TEST(OctomapIo, ColoursThePredictedRoomsInTheColorOcTree) {
  common::OccupancyGrid map;
  common::DoorsFile doors;
  cv::Mat1w truth;
  testing::syntheticHiddenRoomA(&map, &doors, &truth);
  prediction::PredictionRequest request{map, doors, {}, ""};
  const prediction::PredictionResult result = prediction::makeRoomPredictor("default")->predict(request);
  const common::OccupancyGrid completed = prediction::insertRooms(map, doors, result.rooms);
  const cv::Mat1w labels = prediction::roomLabels(map, doors, result.rooms);
  const std::string path = testing::makeTempDir("octomap_colours") + "/completed.ot";
  exportOctomap(completed, labels, ExtrusionOptions(), path);

  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(path));
  auto* tree = dynamic_cast<octomap::ColorOcTree*>(read.get());
  ASSERT_NE(tree, nullptr);
  cv::Point room_cell;
  cv::minMaxLoc(labels, nullptr, nullptr, nullptr, &room_cell);
  const common::Point2 centre = completed.cellCentre(room_cell.x, room_cell.y);
  const octomap::ColorOcTreeNode* node = tree->search(centre.x(), centre.y(), 1.0);
  ASSERT_NE(node, nullptr);
  EXPECT_FALSE(tree->isNodeOccupied(node));
  const cv::Vec3b colour = common::roomColour(1);
  EXPECT_EQ(node->getColor(), octomap::ColorOcTreeNode::Color(colour[2], colour[1], colour[0]));
  // Outside the room: grey.
  int corridor_col = 0, corridor_row = 0;
  ASSERT_TRUE(completed.cellOf(common::Point2(5.0, 1.0), &corridor_col, &corridor_row));
  ASSERT_EQ(labels(corridor_row, corridor_col), 0);
  const octomap::ColorOcTreeNode* corridor = tree->search(5.0, 1.0, 1.0);
  ASSERT_NE(corridor, nullptr);
  EXPECT_EQ(corridor->getColor().r, corridor->getColor().g);
}

TEST(OctomapIo, CoarserVoxelsKeepTheWalls) {
  common::OccupancyGrid map;
  map.resolution = 0.05;
  map.cells = cv::Mat_<int8_t>(40, 40, common::OccupancyGrid::kFree);
  map.cells.col(21).setTo(common::OccupancyGrid::kOccupied);  // a one-cell wall
  const std::string path = testing::makeTempDir("octomap_coarse") + "/map.bt";
  ExtrusionOptions extrusion;
  extrusion.resolution = 0.1;
  exportOctomap(map, cv::Mat1w(), extrusion, path);
  const common::OccupancyGrid sliced = sliceOctomap(path, SliceOptions());
  ASSERT_EQ(sliced.width(), 20);
  EXPECT_DOUBLE_EQ(sliced.resolution, 0.1);
  EXPECT_EQ(cv::countNonZero(sliced.cells == common::OccupancyGrid::kOccupied), 20);  // the wall's column survives
  EXPECT_EQ(cv::countNonZero(sliced.cells.col(10) == common::OccupancyGrid::kOccupied), 20);
}

TEST(OctomapIo, PredictionOnASlicedMapEqualsPredictionOnTheMap) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  const std::string case_dir = testing::sharedDir() + "/data/closed_door_benchmark/office1_fs/15_doors";
  const common::OccupancyGrid known = cropToKnown(common::loadMap(case_dir + "/map.yaml"));
  const common::DoorsFile doors = common::loadDoors(case_dir + "/doors.yaml");
  const std::string path = testing::makeTempDir("octomap_predict") + "/map.bt";
  exportOctomap(known, cv::Mat1w(), ExtrusionOptions(), path);
  const common::OccupancyGrid sliced = sliceOctomap(path, SliceOptions());
  expectSameMap(sliced, known);
  const auto predictor = prediction::makeRoomPredictor("default");
  const prediction::PredictionResult on_map = predictor->predict({known, doors, {}, ""});
  const prediction::PredictionResult on_slice = predictor->predict({sliced, doors, {}, ""});
  const cv::Mat1w labels_map = prediction::roomLabels(known, doors, on_map.rooms);
  const cv::Mat1w labels_slice = prediction::roomLabels(sliced, doors, on_slice.rooms);
  EXPECT_GT(cv::countNonZero(labels_map), 0);
  EXPECT_EQ(cv::countNonZero(labels_map != labels_slice), 0);
}

TEST(OctomapIo, BadInputGivesClearErrors) {
  const std::string dir = testing::makeTempDir("octomap_bad");
  EXPECT_NE(inputErrorMessage([&] { sliceOctomap(dir + "/missing.bt", SliceOptions()); }).find("no such file"),
            std::string::npos);
  std::ofstream(dir + "/garbage.bt") << "not an octree";
  EXPECT_NE(inputErrorMessage([&] { sliceOctomap(dir + "/garbage.bt", SliceOptions()); }).find("garbage.bt"),
            std::string::npos);
  std::ofstream(dir + "/garbage.ot") << "# Octomap OcTree file\nid NoSuchTree\n";
  EXPECT_NE(inputErrorMessage([&] { sliceOctomap(dir + "/garbage.ot", SliceOptions()); }).find("garbage.ot"),
            std::string::npos);
  std::ofstream(dir + "/map.png") << "x";
  EXPECT_NE(inputErrorMessage([&] { sliceOctomap(dir + "/map.png", SliceOptions()); })
                .find("unknown OctoMap file type"),
            std::string::npos);
  SliceOptions inverted;
  inverted.z_min = 2.0;
  inverted.z_max = 1.0;
  EXPECT_NE(inputErrorMessage([&] { sliceOctomap(dir + "/garbage.bt", inverted); }).find("z_min < z_max"),
            std::string::npos);

  common::OccupancyGrid map;
  map.cells = cv::Mat_<int8_t>(10, 10, common::OccupancyGrid::kFree);
  EXPECT_THROW(exportOctomap(map, cv::Mat1w(), ExtrusionOptions(), dir + "/map.txt"), common::InputError);
  EXPECT_THROW(exportOctomap(map, cv::Mat1w::zeros(3, 3), ExtrusionOptions(), dir + "/map.ot"), common::InputError);
  ExtrusionOptions flat;
  flat.height = 0.0;
  EXPECT_THROW(exportOctomap(map, cv::Mat1w(), flat, dir + "/map.bt"), common::InputError);
  EXPECT_THROW(exportOctomap(common::OccupancyGrid(), cv::Mat1w(), ExtrusionOptions(), dir + "/map.bt"),
               common::InputError);
  exportOctomap(map, cv::Mat1w(), ExtrusionOptions(), dir + "/new/folder/map.bt");  // missing parents are created
  EXPECT_TRUE(std::filesystem::is_regular_file(dir + "/new/folder/map.bt"));
  // Heights beyond the voxel limit (export_octomap --height 100 used to take 23 GB) or OctoMap's extent.
  ExtrusionOptions tall;
  tall.height = 1e9;
  EXPECT_NE(inputErrorMessage([&] { exportOctomap(map, cv::Mat1w(), tall, dir + "/tall.bt"); })
                .find("the number of voxels (100 known cells x 2e+10 per column) is 2e+12, more than the limit"),
            std::string::npos);
  common::OccupancyGrid one_cell;
  one_cell.cells = cv::Mat_<int8_t>(1, 1, common::OccupancyGrid::kFree);
  tall.height = 5000.0;
  EXPECT_NE(inputErrorMessage([&] { exportOctomap(one_cell, cv::Mat1w(), tall, dir + "/tall.bt"); })
                .find("the height 5000 m reaches beyond OctoMap's extent"),
            std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir + "/tall.bt"));
}

// OctoMap's readers follow a file's child bits past its end and to any depth (the fuzzer's out-of-memory input
// is kept in test/fuzz/regressions/octomap): such files are refused before OctoMap reads them.
TEST(OctomapIo, DamagedTreesAreRefusedBeforeOctomapReadsThem) {
  const std::string dir = testing::makeTempDir("octomap_damaged");
  common::OccupancyGrid map;
  common::DoorsFile doors;
  cv::Mat1w truth;
  testing::syntheticHiddenRoomA(&map, &doors, &truth);
  const auto error = [](const std::string& path) {
    return inputErrorMessage([&] { sliceOctomap(path, SliceOptions()); });
  };
  const auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(dir + "/" + name, std::ios::binary) << bytes;
    return dir + "/" + name;
  };
  for (const std::string extension : {".bt", ".ot"}) {
    SCOPED_TRACE(extension);
    exportOctomap(map, cv::Mat1w(), ExtrusionOptions(), dir + "/map" + extension);
    std::ifstream file(dir + "/map" + extension, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    EXPECT_NE(error(write("cut" + extension, bytes.substr(0, bytes.size() - 7))).find("ends inside its tree"),
              std::string::npos);
    const size_t size_line = bytes.find("\nsize ");
    const std::string miscounted =
        bytes.substr(0, size_line) + "\nsize 3" + bytes.substr(bytes.find('\n', size_line + 1));
    EXPECT_NE(error(write("miscounted" + extension, miscounted)).find("declares 3 nodes but holds"), std::string::npos);
    // Trailing bytes are not part of the tree.
    expectSameMap(sliceOctomap(write("trailing" + extension, bytes + "extra"), SliceOptions()), cropToKnown(map));
  }
  // A .ot whose every node has all eight children: 17 nodes reach below OctoMap's 16 levels.
  std::string deep = "# Octomap OcTree file\nid OcTree\nsize 137\nres 0.1\ndata\n";
  for (int level = 0; level <= 16; ++level) deep += std::string(4, '\0') + '\xff';
  EXPECT_NE(error(write("deep.ot", deep)).find("deeper than OctoMap's 16 levels"), std::string::npos);
  const std::string counting = "# Octomap OcTree file\nid CountingOcTree\nres 0.1\nsize 1\ndata\n";
  EXPECT_NE(error(write("counting.ot", counting)).find("'CountingOcTree', not an OcTree"), std::string::npos);
  // Two voxels 3 km apart: a grid of 4e9 cells is refused, a coarser one is sliced.
  octomap::OcTree far(0.05);
  far.updateNode(octomap::point3d(-1500.0, -1500.0, 0.5), true);
  far.updateNode(octomap::point3d(1500.0, 1500.0, 0.5), true);
  ASSERT_TRUE(far.writeBinary(dir + "/far.bt"));
  EXPECT_NE(error(dir + "/far.bt").find("slice it at a coarser resolution"), std::string::npos);
  SliceOptions coarse;
  coarse.resolution = 1.0;
  EXPECT_NEAR(sliceOctomap(dir + "/far.bt", coarse).width(), 3000, 1);
}

}  // namespace
}  // namespace hidden_rooms::map3d
