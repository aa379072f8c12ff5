#include "hidden_rooms/common/file_io.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::common {

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

namespace {

constexpr const char* kTemporarySuffix = ".partial";

// Removes the temporaries of `path` (PATH.partialPID) whose writer no longer runs: a writer killed during the
// write leaves one behind.
void removeStaleTemporaries(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const std::string prefix = target.filename().string() + kTemporarySuffix;
  std::error_code error;
  for (fs::directory_iterator entry(folder, error), end; !error && entry != end; entry.increment(error)) {
    const std::string name = entry->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t writer = static_cast<pid_t>(std::stol(digits));
    if (writer > 0 && kill(writer, 0) == -1 && errno == ESRCH) {
      std::error_code ignored;
      fs::remove(entry->path(), ignored);
    }
  }
}

}  // namespace

void writeAtomically(const std::string& path, const std::function<void(const std::string& temporary_path)>& write) {
  removeStaleTemporaries(path);
  // Unique per process, in the target's folder (a rename within one file system is atomic).
  const std::string temporary = path + kTemporarySuffix + std::to_string(getpid());
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

void createOutputDirectory(const std::string& path) {
  std::error_code error;
  std::filesystem::create_directories(path, error);
  if (error || !std::filesystem::is_directory(path))
    throw InputError(path, "cannot create output folder" + (error ? ": " + error.message() : std::string()));
}

}  // namespace hidden_rooms::common
