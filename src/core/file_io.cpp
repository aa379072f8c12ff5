#include "hidden_rooms/file_io.h"

#include <fstream>
#include <sstream>

#include "hidden_rooms/input_error.h"

namespace hidden_rooms {

std::string readTextFile(const std::string& path, const std::string& what) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path, "cannot open " + what);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

YAML::Node loadYamlFile(const std::string& path, const std::string& what) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path, "cannot open " + what);
  } catch (const YAML::Exception& error) {
    throw InputError(path, std::string("malformed YAML: ") + error.what());
  }
}

}  // namespace hidden_rooms
