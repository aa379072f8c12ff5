#pragma once

// Options structs described by one typed table each: for every field its name, type (double, int, bool or
// string), valid range and one-line meaning; its default is the field's value in a default-constructed struct.
// The table drives reading the options (ROS parameters: hidden_rooms/ros/parameters.h; the prediction's named
// parameters from config files, --params and service requests: optionValues / applyOptionValues), their
// validation with a message that names the parameter and its range, and the parameter tables of the
// documentation (tests hold docs/ros_api.md and the shipped configs against describeOptions()).

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::common {

// The valid values of a number: an interval whose ends are each open or closed, optionally integers only.
struct ParameterRange {
  double low = -std::numeric_limits<double>::infinity();
  double high = std::numeric_limits<double>::infinity();
  bool low_open = false;
  bool high_open = false;
  bool integer = false;
};

// Ranges of the tables: values >= low, values > low, values in [low, high], any finite value.
inline ParameterRange atLeast(double low) { return {low, std::numeric_limits<double>::infinity(), false, true}; }
inline ParameterRange above(double low) { return {low, std::numeric_limits<double>::infinity(), true, true}; }
inline ParameterRange between(double low, double high) { return {low, high, false, false}; }
inline ParameterRange anyFinite() {
  return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(), true, true};
}

// Throws InputError(source, "must be [an integer ]in [LOW, HIGH), got VALUE") when `value` is outside `range`
// (NaN always is).
void requireInRange(const std::string& source, double value, const ParameterRange& range);

template <typename Options>
struct Option {
  using Member = std::variant<double Options::*, int Options::*, bool Options::*, std::string Options::*>;
  std::string name;
  Member member;
  std::string meaning;                 // one line
  ParameterRange range = anyFinite();  // doubles and ints: the valid values
  bool non_empty = false;              // strings: the empty string is not valid
};

template <typename Options>
using OptionTable = std::vector<Option<Options>>;

// Throws InputError(prefix + name, "must be ...") for the first field outside its range (non-finite doubles
// included) or an empty non-empty string.
template <typename Options>
void validateOptions(const OptionTable<Options>& table, const Options& options, const std::string& prefix = "") {
  for (const Option<Options>& option : table) {
    std::visit(
        [&](auto member) {
          using Value = std::decay_t<decltype(options.*member)>;
          const Value& value = options.*member;
          if constexpr (std::is_same_v<Value, double> || std::is_same_v<Value, int>) {
            requireInRange(prefix + option.name, static_cast<double>(value), option.range);
          } else if constexpr (std::is_same_v<Value, std::string>) {
            if (option.non_empty && value.empty()) throw InputError(prefix + option.name, "must not be empty");
          }
        },
        option.member);
  }
}

template <typename Options>
std::vector<std::string> optionNames(const OptionTable<Options>& table) {
  std::vector<std::string> names;
  for (const Option<Options>& option : table) names.push_back(option.name);
  return names;
}

// The numeric fields as named numbers (bools as 0 and 1), the form of the prediction's parameters; strings are
// left out.
template <typename Options>
std::map<std::string, double> optionValues(const OptionTable<Options>& table, const Options& options) {
  std::map<std::string, double> values;
  for (const Option<Options>& option : table) {
    std::visit(
        [&](auto member) {
          using Value = std::decay_t<decltype(options.*member)>;
          if constexpr (!std::is_same_v<Value, std::string>) values[option.name] = options.*member;
        },
        option.member);
  }
  return values;
}

// Sets the fields named in `values`; names of other tables are left alone. Throws InputError(prefix + name, ...)
// for a value that does not fit the field's type: an int needs an integer, a bool 0 or 1.
template <typename Options>
void applyOptionValues(const OptionTable<Options>& table, const std::map<std::string, double>& values,
                       Options* options, const std::string& prefix = "") {
  for (const Option<Options>& option : table) {
    const auto found = values.find(option.name);
    if (found == values.end()) continue;
    const double value = found->second;
    std::visit(
        [&](auto member) {
          using Value = std::decay_t<decltype(options->*member)>;
          if constexpr (std::is_same_v<Value, double>) {
            options->*member = value;
          } else if constexpr (std::is_same_v<Value, int>) {
            if (!(value == std::floor(value) && std::abs(value) <= std::numeric_limits<int>::max()))
              throw InputError(prefix + option.name, "must be an integer, got " + formatNumber(value));
            options->*member = static_cast<int>(value);
          } else if constexpr (std::is_same_v<Value, bool>) {
            if (value != 0.0 && value != 1.0)
              throw InputError(prefix + option.name, "must be 0 or 1, got " + formatNumber(value));
            options->*member = value == 1.0;
          } else {
            throw InputError(prefix + option.name, "is text, not a number");
          }
        },
        option.member);
  }
}

// A table row as the documentation shows it.
struct OptionDescription {
  std::string name;
  std::string type;           // "double", "int", "bool" or "string"
  std::string default_value;  // formatNumber() for numbers, true/false, the string in double quotes
  std::string meaning;
};

template <typename Options>
std::vector<OptionDescription> describeOptions(const OptionTable<Options>& table) {
  static const Options defaults{};  // static: GCC 12 warns of padding bytes in a local
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
