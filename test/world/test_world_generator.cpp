#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"
#include "hidden_rooms/world/world_generator.h"
#include "test_util.h"

namespace hidden_rooms::world {
namespace {

const SizeClass kAllClasses[] = {SizeClass::kSmall, SizeClass::kMedium, SizeClass::kLarge};
const std::uint32_t kSeeds[] = {1, 2, 3, 7, 42, 1234567};

std::string describe(std::uint32_t seed, SizeClass size_class) {
  return std::string(toString(size_class)) + " seed " + std::to_string(seed);
}

int doorCountOfSpace(const Environment& environment, int space) {
  int count = 0;
  for (const Door& door : environment.doors)
    for (int index : door.space_indices) count += index == space ? 1 : 0;
  return count;
}

TEST(WorldGenerator, ClosableDoorCountsAreInTheRequestedClass) {
  for (SizeClass size_class : kAllClasses)
    for (std::uint32_t seed : kSeeds) {
      const Environment environment = generateWorld(seed, size_class);
      const int closable = static_cast<int>(closableDoors(environment).size());
      SCOPED_TRACE(describe(seed, size_class) + ": " + std::to_string(closable) + " closable doors");
      switch (size_class) {
        case SizeClass::kSmall: EXPECT_LT(closable, 10); EXPECT_GE(closable, 1); break;
        case SizeClass::kMedium: EXPECT_GE(closable, 10); EXPECT_LE(closable, 15); break;
        case SizeClass::kLarge: EXPECT_GE(closable, 16); break;
      }
      EXPECT_EQ(sizeClassOf(closable), size_class);
      EXPECT_EQ(sizeClassOf(environment), size_class);
    }
}

TEST(WorldGenerator, EverySpaceIsReachableWithAllDoorsOpen) {
  for (SizeClass size_class : kAllClasses)
    for (std::uint32_t seed : kSeeds) {
      SCOPED_TRACE(describe(seed, size_class));
      const Environment environment = generateWorld(seed, size_class);
      const RenderedEnvironment rendered = renderEnvironment(environment, {});

      int corridor = -1;
      for (size_t s = 0; s < environment.spaces.size() && corridor < 0; ++s)
        if (environment.spaces[s].label == "CORRIDOR") corridor = static_cast<int>(s);
      ASSERT_GE(corridor, 0) << "no corridor";
      cv::Point start(-1, -1);
      for (int row = 0; row < rendered.space_labels.rows && start.x < 0; ++row)
        for (int col = 0; col < rendered.space_labels.cols && start.x < 0; ++col)
          if (rendered.space_labels(row, col) == corridor + 1) start = {col, row};
      ASSERT_GE(start.x, 0) << "the corridor has no free cell";

      const cv::Mat1b reachable = common::reachableFreeCells(rendered.map, start.x, start.y);
      std::set<int> present, reached;
      for (int row = 0; row < reachable.rows; ++row)
        for (int col = 0; col < reachable.cols; ++col) {
          const int label = rendered.space_labels(row, col);
          if (label == 0) continue;
          present.insert(label);
          if (reachable(row, col) != 0) reached.insert(label);
        }
      EXPECT_EQ(present.size(), environment.spaces.size()) << "some space has no free cell";
      for (size_t s = 0; s < environment.spaces.size(); ++s)
        EXPECT_TRUE(reached.count(static_cast<int>(s) + 1))
            << "space " << environment.spaces[s].id << " (" << environment.spaces[s].label << ") is unreachable";
    }
}

TEST(WorldGenerator, IsDeterministic) {
  for (SizeClass size_class : kAllClasses) {
    SCOPED_TRACE(toString(size_class));
    const std::string first = environmentToXml(generateWorld(7, size_class));
    EXPECT_EQ(first, environmentToXml(generateWorld(7, size_class)));
    EXPECT_NE(first, environmentToXml(generateWorld(8, size_class)));
  }
  EXPECT_NE(environmentToXml(generateWorld(7, SizeClass::kSmall)),
            environmentToXml(generateWorld(7, SizeClass::kMedium)));
}

TEST(WorldGenerator, XmlRoundTripKeepsSpacesAndDoors) {
  for (SizeClass size_class : kAllClasses)
    for (std::uint32_t seed : {1u, 2u}) {
      SCOPED_TRACE(describe(seed, size_class));
      const Environment environment = generateWorld(seed, size_class);
      const std::string xml = environmentToXml(environment);
      const Environment reread = parseEnvironment(xml, "generated");
      ASSERT_EQ(reread.spaces.size(), environment.spaces.size());
      ASSERT_EQ(reread.doors.size(), environment.doors.size());
      for (size_t s = 0; s < environment.spaces.size(); ++s) {
        EXPECT_EQ(reread.spaces[s].id, environment.spaces[s].id);
        EXPECT_EQ(reread.spaces[s].label, environment.spaces[s].label);
        EXPECT_EQ(reread.spaces[s].segments.size(), environment.spaces[s].segments.size());
        EXPECT_NEAR(common::area(reread.spaces[s].outline), common::area(environment.spaces[s].outline), 1e-6);
      }
      for (size_t d = 0; d < environment.doors.size(); ++d) {
        EXPECT_EQ(reread.doors[d].id, environment.doors[d].id);
        EXPECT_EQ(reread.doors[d].number, environment.doors[d].number);
        EXPECT_EQ(reread.doors[d].space_indices, environment.doors[d].space_indices);
        EXPECT_NEAR((reread.doors[d].centre - environment.doors[d].centre).norm(), 0.0, 1e-6);
        EXPECT_EQ(reread.doors[d].orientation, environment.doors[d].orientation);
      }
      EXPECT_EQ(closableDoors(reread), closableDoors(environment));
      ASSERT_TRUE(reread.wall_thickness.has_value());
      EXPECT_DOUBLE_EQ(*reread.wall_thickness, *environment.wall_thickness);
      EXPECT_EQ(environmentToXml(reread), xml);
    }
}

TEST(WorldGenerator, SpacesDoNotOverlap) {
  constexpr double kCell = 0.05;  // the generator's grid: cell centres never lie on a boundary
  for (SizeClass size_class : kAllClasses)
    for (std::uint32_t seed : {1u, 3u, 42u}) {
      SCOPED_TRACE(describe(seed, size_class));
      const Environment environment = generateWorld(seed, size_class);
      const auto [low, high] = environment.bounds();
      const int cols = static_cast<int>(std::lround((high.x() - low.x()) / kCell));
      const int rows = static_cast<int>(std::lround((high.y() - low.y()) / kCell));
      cv::Mat1b coverage = cv::Mat1b::zeros(rows, cols);
      double sum_of_areas = 0.0;
      for (const Space& space : environment.spaces) {
        sum_of_areas += common::area(space.outline);
        std::vector<cv::Point2f> contour;
        for (const common::Point2& p : space.outline)
          contour.emplace_back(static_cast<float>((p.x() - low.x()) / kCell), static_cast<float>((p.y() - low.y()) / kCell));
        cv::Rect box = cv::boundingRect(contour) & cv::Rect(0, 0, cols, rows);
        for (int row = box.y; row < box.y + box.height; ++row)
          for (int col = box.x; col < box.x + box.width; ++col)
            if (cv::pointPolygonTest(contour, cv::Point2f(col + 0.5f, row + 0.5f), false) > 0)
              coverage(row, col) = cv::saturate_cast<uchar>(coverage(row, col) + 1);
      }
      double max_coverage = 0.0;
      cv::minMaxLoc(coverage, nullptr, &max_coverage);
      EXPECT_LE(max_coverage, 1.0) << "two spaces cover the same cell";
      const double union_area = cv::countNonZero(coverage) * kCell * kCell;
      EXPECT_NEAR(union_area, sum_of_areas, 1e-6);
    }
}

TEST(WorldGenerator, RoomsAndDoorsHaveSensibleGeometry) {
  int rooms = 0, rooms_with_two_doors = 0;
  for (SizeClass size_class : kAllClasses)
    for (std::uint32_t seed : kSeeds) {
      SCOPED_TRACE(describe(seed, size_class));
      const Environment environment = generateWorld(seed, size_class);
      ASSERT_TRUE(environment.wall_thickness.has_value());
      EXPECT_GE(*environment.wall_thickness, 0.10 - 1e-9);
      EXPECT_LE(*environment.wall_thickness, 0.25 + 1e-9);
      EXPECT_EQ(environment.name, "generated_" + std::string(toString(size_class)) + "_seed" + std::to_string(seed));
      EXPECT_TRUE(environment.building_type == "OFFICE" || environment.building_type == "SCHOOL");
      EXPECT_DOUBLE_EQ(environment.metres_per_pixel, 0.05);

      std::set<std::string> ids;
      for (const Space& space : environment.spaces) {
        EXPECT_TRUE(ids.insert(space.id).second) << "duplicate id " << space.id;
        for (const LineSegment& segment : space.segments) {
          if (segment.segment_class == SegmentClass::kWall) {
            EXPECT_TRUE(ids.insert(segment.id).second) << "duplicate id " << segment.id;
          }
        }
        for (const common::Point2& p : space.outline) {
          // Integer XML pixels, all >= 0.
          EXPECT_NEAR(p.x() / 0.05, std::round(p.x() / 0.05), 1e-6);
          EXPECT_NEAR(p.y() / 0.05, std::round(p.y() / 0.05), 1e-6);
          EXPECT_GE(p.x(), 0.0);
          EXPECT_GE(p.y(), 0.0);
          EXPECT_LE(p.y() / 0.05, environment.flip_v + 1e-6);
        }
      }
      for (const Door& door : environment.doors) {
        EXPECT_TRUE(ids.insert(door.id).second) << "duplicate id " << door.id;
        EXPECT_EQ(door.space_indices.size(), 2u) << "door " << door.id;
        for (int s : door.space_indices) {
          if (environment.spaces[s].label == "CORRIDOR") continue;
          for (const common::Point2& corner : environment.spaces[s].outline)
            EXPECT_GE((corner - door.centre).norm(), 0.6 - 1e-9) << "door " << door.id << " near a corner";
        }
      }
      for (size_t s = 0; s < environment.spaces.size(); ++s) {
        const Space& space = environment.spaces[s];
        if (space.label == "CORRIDOR") {
          EXPECT_EQ(space.type, "C");
          continue;
        }
        ++rooms;
        ASSERT_EQ(space.outline.size(), 4u) << space.id;
        const double width = std::abs(space.outline[1].x() - space.outline[0].x()) +
                             std::abs(space.outline[1].y() - space.outline[0].y());
        const double depth = std::abs(space.outline[2].x() - space.outline[1].x()) +
                             std::abs(space.outline[2].y() - space.outline[1].y());
        EXPECT_GE(std::min(width, depth), 2.5 - 1e-9) << space.id;
        EXPECT_LE(std::max(width, depth), 7.0 + 1e-9) << space.id;
        const int doors = doorCountOfSpace(environment, static_cast<int>(s));
        EXPECT_GE(doors, 1) << space.id << " has no door";
        if (doors >= 2) ++rooms_with_two_doors;
      }
    }
  // About 10-20% of rooms have a second door.
  EXPECT_GE(rooms_with_two_doors * 100, rooms * 5) << rooms_with_two_doors << " of " << rooms;
  EXPECT_LE(rooms_with_two_doors * 100, rooms * 30) << rooms_with_two_doors << " of " << rooms;
}

TEST(WorldGenerator, SizeClassNames) {
  for (SizeClass size_class : kAllClasses) EXPECT_EQ(parseSizeClass(toString(size_class)), size_class);
  EXPECT_THROW(parseSizeClass(""), common::InputError);
  EXPECT_NE(testing::inputErrorMessage([] { parseSizeClass("huge"); }).find("'huge'"), std::string::npos);
  EXPECT_EQ(sizeClassOf(0), SizeClass::kSmall);
  EXPECT_EQ(sizeClassOf(9), SizeClass::kSmall);
  EXPECT_EQ(sizeClassOf(10), SizeClass::kMedium);
  EXPECT_EQ(sizeClassOf(15), SizeClass::kMedium);
  EXPECT_EQ(sizeClassOf(16), SizeClass::kLarge);
}

// Runs a command line through the shell; returns its exit code and fills `output` with stdout + stderr.
int runCommand(const std::string& command, std::string* output) {
  const std::string log = testing::makeTempDir("generate_world_log") + "/output.txt";
  const int status = std::system((command + " > '" + log + "' 2>&1").c_str());
  std::ifstream file(log);
  std::stringstream text;
  text << file.rdbuf();
  *output = text.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(WorldGeneratorTool, WritesTheWorldOfTheLibrary) {
  const std::string dir = testing::makeTempDir("generate_world_tool");
  const std::string path = dir + "/world.xml";
  std::string output;
  ASSERT_EQ(runCommand(std::string(GENERATE_WORLD_BIN) + " --seed 5 --size medium --out " + path, &output), 0)
      << output;
  EXPECT_NE(output.find("medium"), std::string::npos) << output;
  EXPECT_NE(output.find("closable"), std::string::npos) << output;
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  EXPECT_EQ(text.str(), environmentToXml(generateWorld(5, SizeClass::kMedium)));
  EXPECT_EQ(sizeClassOf(loadEnvironment(path)), SizeClass::kMedium);
}

TEST(WorldGeneratorTool, RejectsBadCommandLines) {
  const std::string dir = testing::makeTempDir("generate_world_tool_errors");
  const std::string binary = GENERATE_WORLD_BIN;
  std::string output;
  EXPECT_EQ(runCommand(binary + " --seed 5 --out " + dir + "/a.xml", &output), 2) << output;
  EXPECT_NE(output.find("size"), std::string::npos) << output;
  EXPECT_EQ(runCommand(binary + " --seed 5 --size huge --out " + dir + "/a.xml", &output), 2) << output;
  EXPECT_NE(output.find("unknown size class 'huge'"), std::string::npos) << output;
  EXPECT_EQ(runCommand(binary + " --seed minus --size small --out " + dir + "/a.xml", &output), 2) << output;
  EXPECT_EQ(runCommand(binary + " --seed -3 --size small --out " + dir + "/a.xml", &output), 2) << output;
  std::ofstream(dir + "/plain_file") << "x";
  EXPECT_EQ(runCommand(binary + " --seed 5 --size small --out " + dir + "/plain_file/a.xml", &output), 2) << output;
  EXPECT_EQ(runCommand(binary + " --seed 5 --size small --out " + dir + "/new/a.xml", &output), 0) << output;
  EXPECT_EQ(runCommand(binary + " --help", &output), 0) << output;
}

}  // namespace
}  // namespace hidden_rooms::world
