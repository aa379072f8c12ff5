#pragma once

// Reading input files with errors that name the file: InputError(path, "cannot open <what>") when it cannot be
// opened, InputError(path, "malformed YAML: ...") when YAML does not parse.

#include <string>

#include <yaml-cpp/yaml.h>

namespace hidden_rooms {

std::string readTextFile(const std::string& path, const std::string& what);
YAML::Node loadYamlFile(const std::string& path, const std::string& what);

}  // namespace hidden_rooms
