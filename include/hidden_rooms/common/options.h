#pragma once

// Options structs described by one typed table each: for every field its name, type (double, int, bool or
// string), valid range and one-line meaning; its default is the field's value in a default-constructed struct.
// The table drives reading the options (ROS parameters: hidden_rooms/ros/parameters.h), their validation with a
// message that names the parameter and its range, and the parameter tables of the documentation (a test holds
// docs/ros_api.md against describeOptions()).

#include <limits>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/parameter_table.h"

namespace hidden_rooms::common {

// Ranges of the tables: values >= low, values > low, values in [low, high], any finite value.
inline ParameterRange atLeast(double low) { return {low, std::numeric_limits<double>::infinity(), false, true}; }
inline ParameterRange above(double low) { return {low, std::numeric_limits<double>::infinity(), true, true}; }
inline ParameterRange between(double low, double high) { return {low, high, false, false}; }
inline ParameterRange anyFinite() {
  return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(), true, true};
}

template <typename Options>
struct Option {
  using Member = std::variant<double Options::*, int Options::*, bool Options::*, std::string Options::*>;
  std::string name;
  Member member;
  std::string meaning;     // one line
  ParameterRange range = anyFinite();  // doubles and ints: the valid values
  bool non_empty = false;  // strings: the empty string is not valid
};

template <typename Options>
using OptionTable = std::vector<Option<Options>>;

// A table row as the documentation shows it.
struct OptionDescription {
  std::string name;
  std::string type;           // "double", "int", "bool" or "string"
  std::string default_value;  // formatNumber() for numbers, true/false, the string in double quotes
  std::string meaning;
};

// Throws InputError(prefix + name, "must be in [low, high], got value") for the first field outside its range
// (non-finite doubles included), InputError(prefix + name, "must not be empty") for an empty non-empty string.
template <typename Options>
void validateOptions(const OptionTable<Options>& table, const Options& options, const std::string& prefix = "") {
  for (const Option<Options>& option : table) {
    std::visit(
        [&](auto member) {
          using Value = std::decay_t<decltype(options.*member)>;
          const Value& value = options.*member;
          if constexpr (std::is_same_v<Value, double> || std::is_same_v<Value, int>) {
            try {
              requireParameterInRange(option.name, static_cast<double>(value), option.range);
            } catch (const InputError& error) {
              const std::string problem = error.problem();
              throw InputError(prefix + option.name, problem.substr(problem.find("must")));
            }
          } else if constexpr (std::is_same_v<Value, std::string>) {
            if (option.non_empty && value.empty()) throw InputError(prefix + option.name, "must not be empty");
          }
        },
        option.member);
  }
}

template <typename Options>
std::vector<OptionDescription> describeOptions(const OptionTable<Options>& table) {
  const Options defaults{};
  std::vector<OptionDescription> rows;
  for (const Option<Options>& option : table) {
    OptionDescription row{option.name, "", "", option.meaning};
    std::visit(
        [&](auto member) {
          using Value = std::decay_t<decltype(defaults.*member)>;
          const Value& value = defaults.*member;
          if constexpr (std::is_same_v<Value, double>) {
            row.type = "double";
            row.default_value = formatNumber(value);
          } else if constexpr (std::is_same_v<Value, int>) {
            row.type = "int";
            row.default_value = std::to_string(value);
          } else if constexpr (std::is_same_v<Value, bool>) {
            row.type = "bool";
            row.default_value = value ? "true" : "false";
          } else {
            row.type = "string";
            row.default_value = "\"" + value + "\"";
          }
        },
        option.member);
    rows.push_back(row);
  }
  return rows;
}

}  // namespace hidden_rooms::common
