#include <gtest/gtest.h>

#include <fstream>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/label_image.h"
#include "test_util.h"

namespace hidden_rooms::common {
namespace {

TEST(LabelImage, RoomsYamlBecomesLabels) {
  OccupancyGrid map;
  map.resolution = 0.1;
  map.cells = cv::Mat_<int8_t>(50, 50, OccupancyGrid::kUnknown);
  const std::string dir = testing::makeTempDir("label_image_rooms_yaml");
  std::ofstream(dir + "/rooms.yaml") << "rooms:\n"
                                        "  - {door_id: 4, label: 2, placed: true, polygon: [[1, 1], [2, 1], [2, 2], [1, 2]]}\n"
                                        "  - {door_id: 5, label: 1, placed: false, polygon: []}\n";
  const cv::Mat1w labels = roomLabelsFromYaml(dir + "/rooms.yaml", map);
  EXPECT_EQ(cv::countNonZero(labels == 2), 11 * 11);  // corners on cell centres: 1.05 .. 2.05 inclusive
  EXPECT_EQ(cv::countNonZero(labels == 1), 0);
  std::ofstream(dir + "/bad.yaml") << "rooms:\n  - {label: 1, polygon: [[1, 1], [2, x]]}\n";
  EXPECT_THROW(roomLabelsFromYaml(dir + "/bad.yaml", map), InputError);
  std::ofstream(dir + "/none.yaml") << "method: default\n";
  EXPECT_THROW(roomLabelsFromYaml(dir + "/none.yaml", map), InputError);
}

}  // namespace
}  // namespace hidden_rooms::common

