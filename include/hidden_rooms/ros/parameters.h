#pragma once

// Reading an options struct from ROS parameters through its table (hidden_rooms/common/options.h).

#include <optional>
#include <string>
#include <type_traits>
#include <variant>

#include <ros/node_handle.h>

#include "hidden_rooms/common/options.h"

namespace hidden_rooms {

// Reads the parameter `name` of `nh` into `value` when it is set; leaves `value` as it is otherwise. Throws
// InputError("~name", "must be a number" / "an integer" / "true or false" / "a string") for a value of another
// type (an integer is a number too).
void readParameter(const ros::NodeHandle& nh, const std::string& name, double* value);
void readParameter(const ros::NodeHandle& nh, const std::string& name, int* value);
void readParameter(const ros::NodeHandle& nh, const std::string& name, bool* value);
void readParameter(const ros::NodeHandle& nh, const std::string& name, std::string* value);
// Text that roslaunch types as an integer when it is a lone number (a single door number: "3" -> 3): an integer
// is read as its text. Throws InputError("~name", "must be text or an integer") for another type.
void readTextParameter(const ros::NodeHandle& nh, const std::string& name, std::string* value);
// An optional positive number (a wall thickness): set only when the parameter is set and > 0; 0 or less leaves
// `value` as it is. Throws InputError("~name", "must be a number") for another type.
void readPositiveParameter(const ros::NodeHandle& nh, const std::string& name, std::optional<double>* value);

// Sets every field of `options` whose parameter is set (private names, ~name) and validates the table's ranges;
// throws InputError("~name", ...) naming the first bad one.
template <typename Options>
void readParameters(const ros::NodeHandle& nh, const common::OptionTable<Options>& table, Options* options) {
  for (const common::Option<Options>& option : table)
    std::visit([&](auto member) { readParameter(nh, option.name, &(options->*member)); }, option.member);
  common::validateOptions(table, *options, "~");
}

}  // namespace hidden_rooms
