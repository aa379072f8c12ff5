// docs/ros_api.md and the shipped node configs against the nodes' option tables: every parameter of a table is
// documented in its node's section with the table's type and default, every parameter the section documents is in
// a table, and every key of a shipped config is a parameter of its node with a value of the parameter's type.

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "hidden_rooms/ros/explorer.h"
#include "hidden_rooms/ros/map_publisher.h"
#include "hidden_rooms/ros/mapper.h"
#include "hidden_rooms/ros/pose_logger.h"
#include "hidden_rooms/ros/room_predictor.h"
#include "hidden_rooms/ros/simulator.h"

namespace hidden_rooms {
namespace {

struct DocumentedParameter {
  std::string type;
  std::string default_value;
};

std::string trimmed(const std::string& text) {
  const size_t begin = text.find_first_not_of(" `\"");
  const size_t end = text.find_last_not_of(" `\"");
  return begin == std::string::npos ? "" : text.substr(begin, end - begin + 1);
}

std::vector<std::string> split(const std::string& text, const std::string& separator) {
  std::vector<std::string> parts;
  size_t start = 0;
  for (size_t at = text.find(separator); at != std::string::npos; at = text.find(separator, start)) {
    parts.push_back(text.substr(start, at - start));
    start = at + separator.size();
  }
  parts.push_back(text.substr(start));
  return parts;
}

// The rows "| `~a`, `~b` | type | default_a, default_b | meaning |" of the section "## `node`".
std::map<std::string, DocumentedParameter> documentedParameters(const std::string& node) {
  std::ifstream file(std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/docs/ros_api.md");
  std::map<std::string, DocumentedParameter> parameters;
  std::string line;
  bool in_section = false;
  while (std::getline(file, line)) {
    if (line.rfind("## ", 0) == 0) in_section = line == "## `" + node + "`";
    if (!in_section || line.rfind("| `~", 0) != 0) continue;
    const std::vector<std::string> columns = split(line.substr(1), " | ");
    if (columns.size() < 3) continue;
    std::vector<std::string> names;
    const std::regex name_pattern("`~(\\w+)`");
    for (std::sregex_iterator it(columns[0].begin(), columns[0].end(), name_pattern), end; it != end; ++it)
      names.push_back((*it)[1]);
    // One name: the whole column is its default (a list such as "[0.2, 0, 0]" included).
    const std::vector<std::string> defaults =
        names.size() == 1 ? std::vector<std::string>{columns[2]} : split(columns[2], ", ");
    for (size_t k = 0; k < names.size(); ++k)
      parameters[names[k]] = {trimmed(columns[1]), trimmed(defaults.size() == names.size() ? defaults[k] : "?")};
  }
  return parameters;
}

// Numbers compare by value (0.30 and 0.3 are the same default), anything else as text.
bool sameDefault(const std::string& documented, const std::string& actual) {
  char* end = nullptr;
  const double a = std::strtod(documented.c_str(), &end);
  if (end != documented.c_str() && *end == '\0') {
    const double b = std::strtod(actual.c_str(), &end);
    return *end == '\0' && a == b;
  }
  return documented == trimmed(actual);
}

void expectDocumented(const std::string& node, const std::vector<common::OptionDescription>& table) {
  const std::map<std::string, DocumentedParameter> documented = documentedParameters(node);
  ASSERT_FALSE(documented.empty()) << "no parameter rows in the section of " << node;
  std::map<std::string, bool> in_table;
  for (const common::OptionDescription& row : table) {
    in_table[row.name] = true;
    const auto found = documented.find(row.name);
    if (found == documented.end()) {
      ADD_FAILURE() << node << ": ~" << row.name << " is not in docs/ros_api.md";
      continue;
    }
    EXPECT_EQ(found->second.type, row.type) << node << ": type of ~" << row.name;
    EXPECT_TRUE(sameDefault(found->second.default_value, row.default_value))
        << node << ": ~" << row.name << " defaults to " << row.default_value << ", the docs say "
        << found->second.default_value;
  }
  for (const auto& [name, parameter] : documented)
    EXPECT_TRUE(in_table.count(name)) << node << ": docs/ros_api.md documents ~" << name << ", which it does not read";
}

TEST(ParameterDocs, ExplorerParametersAreDocumentedWithTheirTypesAndDefaults) {
  expectDocumented("explorer", explorerParameters());
}

TEST(ParameterDocs, SimulatorParametersAreDocumentedWithTheirTypesAndDefaults) {
  expectDocumented("simulator", simulatorParameters());
}

TEST(ParameterDocs, MapperParametersAreDocumentedWithTheirTypesAndDefaults) {
  expectDocumented("mapper", mapperParameters());
}

TEST(ParameterDocs, PoseLoggerParametersAreDocumentedWithTheirTypesAndDefaults) {
  expectDocumented("pose_logger", poseLoggerParameters());
}

TEST(ParameterDocs, MapPublisherParametersAreDocumentedWithTheirTypesAndDefaults) {
  expectDocumented("map_publisher", mapPublisherParameters());
}

TEST(ParameterDocs, RoomPredictorParametersAreDocumentedWithTheirTypesAndDefaults) {
  expectDocumented("room_predictor", roomPredictorParameters());
}

// cfg/RoomPredictor.cfg (rqt_reconfigure) offers every registered method and every parameter some method reads,
// each with a default that is some method's default.
TEST(ParameterDocs, RoomPredictorReconfiguresEveryMethodAndParameter) {
  std::map<std::string, std::set<double>> read;  // parameter -> the methods' defaults
  for (const std::string& name : prediction::roomPredictorNames())
    for (const auto& [parameter, value] : prediction::makeRoomPredictor(name)->defaultParameters())
      read[parameter].insert(value);
  dynamic_reconfigure::Config defaults;
  RoomPredictorConfig::__getDefault__().__toMessage__(defaults);
  std::set<std::string> reconfigurable;
  for (const dynamic_reconfigure::DoubleParameter& parameter : defaults.doubles) {
    reconfigurable.insert(parameter.name);
    EXPECT_TRUE(read.count(parameter.name) && read.at(parameter.name).count(parameter.value))
        << parameter.name << " = " << parameter.value << " is no method's default";
  }
  std::set<std::string> read_names;
  for (const auto& entry : read) read_names.insert(entry.first);
  EXPECT_EQ(reconfigurable, read_names);

  std::set<std::string> offered;  // the `method` enum's values
  for (const dynamic_reconfigure::Group& group : RoomPredictorConfig::__getDescriptionMessage__().groups)
    for (const dynamic_reconfigure::ParamDescription& parameter : group.parameters)
      if (parameter.name == "method") {
        const std::regex value("'value': '([a-z_]+)'");
        for (std::sregex_iterator it(parameter.edit_method.begin(), parameter.edit_method.end(), value), end;
             it != end; ++it)
          offered.insert((*it)[1]);
      }
  const std::vector<std::string> names = prediction::roomPredictorNames();
  EXPECT_EQ(offered, std::set<std::string>(names.begin(), names.end()));
}

// A YAML value as a parameter of `type` (OptionDescription::type) takes it.
bool fitsType(const YAML::Node& value, const std::string& type) {
  if (type == "[x, y, yaw]") return value.IsSequence() && (value.size() == 0 || value.size() == 3);
  if (!value.IsScalar()) return false;
  try {
    if (type == "double") value.as<double>();
    else if (type == "int") value.as<int>();
    else if (type == "bool") value.as<bool>();
    return true;
  } catch (const YAML::Exception&) {
    return false;
  }
}

TEST(ParameterDocs, ShippedConfigsSetKnownParametersOfTheirTypes) {
  const std::vector<std::pair<std::string, std::vector<common::OptionDescription>>> configs{
      {"explorer.yaml", explorerParameters()},         {"simulation.yaml", simulatorParameters()},
      {"mapper.yaml", mapperParameters()},             {"view_world.yaml", mapPublisherParameters()},
      {"predict.yaml", roomPredictorParameters()},
  };
  for (const auto& [file, parameters] : configs) {
    const YAML::Node root = YAML::LoadFile(std::string(HIDDEN_ROOMS_SOURCE_DIR) + "/config/" + file);
    ASSERT_TRUE(root.IsMap()) << file;
    for (const auto& entry : root) {
      const std::string name = entry.first.as<std::string>();
      const auto row = std::find_if(parameters.begin(), parameters.end(),
                                    [&](const common::OptionDescription& p) { return p.name == name; });
      if (row == parameters.end()) {
        ADD_FAILURE() << "config/" << file << ": " << name << " is no parameter of its node";
        continue;
      }
      EXPECT_TRUE(fitsType(entry.second, row->type)) << "config/" << file << ": " << name << " is no " << row->type;
    }
  }
}

}  // namespace
}  // namespace hidden_rooms
