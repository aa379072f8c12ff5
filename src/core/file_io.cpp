#include "hidden_rooms/file_io.h"

#include <unistd.h>

#include <filesystem>
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

void writeAtomically(const std::string& path, const std::function<void(const std::string& temporary_path)>& write) {
  // Unique per process, in the target's folder (a rename within one file system is atomic).
  const std::string temporary = path + ".partial" + std::to_string(getpid());
  std::error_code ignored;
  try {
    write(temporary);
  } catch (...) {
    std::filesystem::remove(temporary, ignored);
    throw;
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::filesystem::remove(temporary, ignored);
    throw InputError(path, "cannot be written: " + error.message());
  }
}

void writeTextAtomically(const std::string& path, const std::string& text, const std::string& what) {
  writeAtomically(path, [&](const std::string& temporary) {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    file << text;
    file.close();
    if (!file) throw InputError(path, "cannot write " + what);
  });
}

}  // namespace hidden_rooms
