#include <gtest/gtest.h>

#include "hidden_rooms/common/options.h"
#include "test_util.h"

namespace hidden_rooms::common {
namespace {

struct ExampleOptions {
  double radius = 0.5;
  int count = 3;
  bool enabled = true;
  std::string frame = "map";
};

const OptionTable<ExampleOptions>& exampleTable() {
  using O = ExampleOptions;
  static const OptionTable<O> table{
      {"radius", &O::radius, "metres", above(0)},
      {"count", &O::count, "how many", between(1, 10)},
      {"enabled", &O::enabled, "on or off"},
      {"frame", &O::frame, "a frame", anyFinite(), true},
  };
  return table;
}

TEST(Options, ValuesRoundTripWithTheirTypes) {
  ExampleOptions options;
  applyOptionValues(exampleTable(), {{"radius", 2.0}, {"count", 7}, {"enabled", 0}, {"other", 1.0}}, &options);
  EXPECT_DOUBLE_EQ(options.radius, 2.0);
  EXPECT_EQ(options.count, 7);
  EXPECT_FALSE(options.enabled);
  const std::map<std::string, double> values = optionValues(exampleTable(), options);
  EXPECT_EQ(values, (std::map<std::string, double>{{"radius", 2.0}, {"count", 7.0}, {"enabled", 0.0}}));
  EXPECT_EQ(optionNames(exampleTable()), (std::vector<std::string>{"radius", "count", "enabled", "frame"}));
}

TEST(Options, IntegersAndBooleansRefuseOtherNumbers) {
  ExampleOptions options;
  EXPECT_EQ(testing::inputErrorMessage([&] { applyOptionValues(exampleTable(), {{"count", 2.5}}, &options, "p "); }),
            "p count: must be an integer, got 2.5");
  EXPECT_EQ(testing::inputErrorMessage([&] { applyOptionValues(exampleTable(), {{"enabled", 2}}, &options); }),
            "enabled: must be 0 or 1, got 2");
  EXPECT_EQ(options.count, 3);
  EXPECT_TRUE(options.enabled);
}

TEST(Options, ValidationNamesTheParameterAndItsRange) {
  ExampleOptions options;
  EXPECT_NO_THROW(validateOptions(exampleTable(), options));
  options.radius = 0.0;
  EXPECT_EQ(testing::inputErrorMessage([&] { validateOptions(exampleTable(), options, "~"); }),
            "~radius: must be in (0, inf), got 0");
  options.radius = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(testing::inputErrorMessage([&] { validateOptions(exampleTable(), options); }), "no error");
  options.radius = 1.0;
  options.count = 11;
  EXPECT_EQ(testing::inputErrorMessage([&] { validateOptions(exampleTable(), options); }),
            "count: must be in [1, 10], got 11");
  options.count = 1;
  options.frame.clear();
  EXPECT_EQ(testing::inputErrorMessage([&] { validateOptions(exampleTable(), options); }),
            "frame: must not be empty");
}

TEST(Options, DescriptionsShowTypesAndDefaults) {
  const std::vector<OptionDescription> rows = describeOptions(exampleTable());
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].type, "double");
  EXPECT_EQ(rows[0].default_value, "0.5");
  EXPECT_EQ(rows[1].type, "int");
  EXPECT_EQ(rows[1].default_value, "3");
  EXPECT_EQ(rows[2].type, "bool");
  EXPECT_EQ(rows[2].default_value, "true");
  EXPECT_EQ(rows[3].type, "string");
  EXPECT_EQ(rows[3].default_value, "\"map\"");
  EXPECT_EQ(rows[3].meaning, "a frame");
}

TEST(SplitList, TrimsItemsAndKeepsEmptyOnes) {
  EXPECT_EQ(splitList(""), std::vector<std::string>{});
  EXPECT_EQ(splitList("mapper"), std::vector<std::string>{"mapper"});
  EXPECT_EQ(splitList(" a, b\t,,c,"), (std::vector<std::string>{"a", "b", "", "c", ""}));
  EXPECT_EQ(splitList("  "), std::vector<std::string>{""});
  EXPECT_EQ(splitList("1;2", ';'), (std::vector<std::string>{"1", "2"}));
}

}  // namespace
}  // namespace hidden_rooms::common
