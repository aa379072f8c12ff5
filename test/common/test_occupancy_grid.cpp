#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "test_util.h"

namespace hidden_rooms::common {
namespace {

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

std::string mapYaml(const std::string& image, const std::string& extra = "") {
  return "image: " + image + "\nresolution: 0.1\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
         "free_thresh: 0.196\n" + extra;
}

TEST(OccupancyGrid, SaveThenLoadKeepsCellsOriginAndResolution) {
  const std::string dir = testing::makeTempDir("grid_round_trip");
  OccupancyGrid grid;
  grid.resolution = 0.05;
  grid.origin = Point2(-3.5, 1.25);
  grid.cells.create(7, 11);
  grid.cells.setTo(OccupancyGrid::kUnknown);
  grid.cells(0, 0) = OccupancyGrid::kFree;
  grid.cells(6, 10) = OccupancyGrid::kOccupied;
  grid.cells(3, 4) = OccupancyGrid::kFree;
  const std::string yaml = saveMap(grid, dir + "/saved");
  EXPECT_TRUE(std::filesystem::exists(dir + "/saved.pgm"));
  const OccupancyGrid loaded = loadMap(yaml);
  EXPECT_EQ(cv::countNonZero(loaded.cells != grid.cells), 0);
  EXPECT_DOUBLE_EQ(loaded.resolution, 0.05);
  EXPECT_LT((loaded.origin - grid.origin).norm(), 1e-12);
}

TEST(OccupancyGrid, FollowsMapServerTrinaryScaleRawAndNegate) {
  const std::string dir = testing::makeTempDir("grid_modes");
  // Grey levels: 254 free, 0 occupied, 205 unknown, 128 in between (occupancy 0.498).
  cv::Mat1b image(1, 4);
  image << 254, 0, 205, 128;
  cv::imwrite(dir + "/map.png", image);
  writeText(dir + "/trinary.yaml", mapYaml("map.png"));
  writeText(dir + "/scale.yaml", mapYaml("map.png", "mode: scale\n"));
  writeText(dir + "/raw.yaml", mapYaml("map.png", "mode: raw\n"));
  writeText(dir + "/negate.yaml", "image: map.png\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 1\n"
                                  "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const OccupancyGrid trinary = loadMap(dir + "/trinary.yaml");
  EXPECT_EQ(trinary.cells(0, 0), OccupancyGrid::kFree);
  EXPECT_EQ(trinary.cells(0, 1), OccupancyGrid::kOccupied);
  EXPECT_EQ(trinary.cells(0, 2), OccupancyGrid::kUnknown);
  EXPECT_EQ(trinary.cells(0, 3), OccupancyGrid::kUnknown);
  const OccupancyGrid scale = loadMap(dir + "/scale.yaml");
  EXPECT_EQ(scale.cells(0, 0), OccupancyGrid::kFree);
  EXPECT_EQ(scale.cells(0, 3), static_cast<int8_t>(1 + 98 * (127.0 / 255.0 - 0.196) / (0.65 - 0.196)));
  const OccupancyGrid raw = loadMap(dir + "/raw.yaml");
  EXPECT_EQ(raw.cells(0, 1), 0);
  EXPECT_EQ(raw.cells(0, 3), static_cast<int8_t>(128));
  const OccupancyGrid negated = loadMap(dir + "/negate.yaml");
  EXPECT_EQ(negated.cells(0, 0), OccupancyGrid::kOccupied);
  EXPECT_EQ(negated.cells(0, 1), OccupancyGrid::kFree);
}

TEST(OccupancyGrid, CellsAndCoordinatesAgree) {
  OccupancyGrid grid;
  grid.resolution = 0.5;
  grid.origin = Point2(10, 20);
  grid.cells.create(4, 6);
  // Row 3 is the bottom row: its first cell's centre is origin + half a cell.
  EXPECT_LT((grid.cellCentre(0, 3) - Point2(10.25, 20.25)).norm(), 1e-12);
  int col = -1, row = -1;
  ASSERT_TRUE(grid.cellOf(Point2(12.9, 21.9), &col, &row));
  EXPECT_EQ(col, 5);
  EXPECT_EQ(row, 0);
  EXPECT_FALSE(grid.cellOf(Point2(9.9, 21.0), &col, &row));
  EXPECT_FALSE(grid.cellOf(Point2(std::nan(""), 21.0), &col, &row));
  EXPECT_FALSE(grid.cellOf(Point2(1e308, 21.0), &col, &row));
  // The map's edges belong to it: the origin is in the bottom-left cell, the far corner in the top-right one.
  ASSERT_TRUE(grid.cellOf(Point2(10, 20), &col, &row));
  EXPECT_EQ(col, 0);
  EXPECT_EQ(row, 3);
  ASSERT_TRUE(grid.cellOf(Point2(13, 22), &col, &row));
  EXPECT_EQ(col, 5);
  EXPECT_EQ(row, 0);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 6; ++c) {
      ASSERT_TRUE(grid.cellOf(grid.cellCentre(c, r), &col, &row));
      EXPECT_EQ(col, c);
      EXPECT_EQ(row, r);
    }
}

TEST(OccupancyGrid, LoadsEveryBenchmarkMapCellForCell) {
  HIDDEN_ROOMS_REQUIRE_SHARED_DATA();
  int maps = 0;
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(testing::sharedDir() + "/data/closed_door_benchmark")) {
    if (entry.path().filename() != "map.yaml" && entry.path().filename() != "full_map.yaml") continue;
    SCOPED_TRACE(entry.path().string());
    const OccupancyGrid grid = loadMap(entry.path().string());
    const cv::Mat1b image = cv::imread((entry.path().parent_path() / entry.path().stem()).string() + ".png",
                                       cv::IMREAD_GRAYSCALE);
    ASSERT_EQ(grid.cells.size(), image.size());
    EXPECT_DOUBLE_EQ(grid.resolution, 0.05);
    EXPECT_EQ(cv::countNonZero(grid.cells == OccupancyGrid::kFree), cv::countNonZero(image == 254));
    EXPECT_EQ(cv::countNonZero(grid.cells == OccupancyGrid::kOccupied), cv::countNonZero(image == 0));
    EXPECT_EQ(cv::countNonZero(grid.cells == OccupancyGrid::kUnknown), cv::countNonZero(image == 205));
    EXPECT_EQ(cv::countNonZero(grid.toGreyImage() != image), 0);
    ++maps;
  }
  EXPECT_GE(maps, 40);
}

// Bad input: the error names the yaml and the problem.
void expectLoadError(const std::string& yaml_path, const std::string& expected_problem) {
  try {
    loadMap(yaml_path);
    FAIL() << "no error for: " << expected_problem;
  } catch (const InputError& error) {
    EXPECT_EQ(error.source(), yaml_path);
    EXPECT_NE(std::string(error.what()).find(expected_problem), std::string::npos) << error.what();
  }
}

TEST(OccupancyGrid, BadMapFilesGiveClearErrors) {
  const std::string dir = testing::makeTempDir("grid_errors");
  cv::imwrite(dir + "/ok.png", cv::Mat1b(3, 3, uchar(254)));
  writeText(dir + "/not_an_image.png", "this is text, not a PNG");
  writeText(dir + "/missing_image.yaml", mapYaml("nowhere.png"));
  writeText(dir + "/unreadable_image.yaml", mapYaml("not_an_image.png"));
  writeText(dir + "/negative_resolution.yaml",
            "image: ok.png\nresolution: -0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
  writeText(dir + "/malformed.yaml", "image: [ok.png\nresolution: 0.05\n");
  writeText(dir + "/no_image_key.yaml", "resolution: 0.05\norigin: [0, 0, 0]\n");
  writeText(dir + "/rotated.yaml", "image: ok.png\nresolution: 0.05\norigin: [0, 0, 0.5]\noccupied_thresh: 0.65\n"
                                   "free_thresh: 0.196\n");
  writeText(dir + "/thresholds.yaml", mapYaml("ok.png").replace(mapYaml("ok.png").find("0.196"), 5, "0.9"));
  writeText(dir + "/bad_origin.yaml", "image: ok.png\nresolution: 0.05\norigin: [0, .nan, 0]\n"
                                      "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  writeText(dir + "/bad_mode.yaml", mapYaml("ok.png", "mode: fancy\n"));
  writeText(dir + "/negate_7.yaml", "image: ok.png\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 7\n");
  expectLoadError(dir + "/negate_7.yaml", "negate is 7 (0 or 1)");
  expectLoadError(dir + "/missing_image.yaml", "does not exist");
  expectLoadError(dir + "/unreadable_image.yaml", "cannot be read as an image");
  expectLoadError(dir + "/negative_resolution.yaml", "resolution must be positive");
  expectLoadError(dir + "/malformed.yaml", "malformed YAML");
  expectLoadError(dir + "/no_image_key.yaml", "missing key 'image'");
  expectLoadError(dir + "/rotated.yaml", "yaw");
  expectLoadError(dir + "/thresholds.yaml", "free_thresh < occupied_thresh");
  expectLoadError(dir + "/bad_origin.yaml", "not finite");
  expectLoadError(dir + "/bad_mode.yaml", "mode 'fancy'");
  expectLoadError(dir + "/absent.yaml", "cannot open");
}

TEST(OccupancyGrid, RefusesToSaveAnEmptyMap) {
  EXPECT_THROW(saveMap(OccupancyGrid(), testing::makeTempDir("grid_empty") + "/empty"), InputError);
}

TEST(OccupancyGrid, TrinaryIsWhatMapSaverSavesAndMapServerReadsBack) {
  OccupancyGrid probabilities;
  probabilities.cells = (cv::Mat_<int8_t>(1, 8) << -1, 0, 19, 20, 50, 64, 65, 100);
  const cv::Mat_<int8_t> expected = (cv::Mat_<int8_t>(1, 8) << -1, 0, 0, -1, -1, -1, 100, 100);
  EXPECT_EQ(cv::countNonZero(trinary(probabilities).cells != expected), 0) << cv::Mat(trinary(probabilities).cells);
  const std::string prefix = testing::makeTempDir("grid_trinary") + "/map";
  saveMap(probabilities, prefix);
  EXPECT_EQ(cv::countNonZero(loadMap(prefix + ".yaml").cells != trinary(probabilities).cells), 0);
}

}  // namespace
}  // namespace hidden_rooms::common
