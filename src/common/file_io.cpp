#include "hidden_rooms/common/file_io.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::common {

bool isFile(const std::string& path) {
  std::error_code error;
  return std::filesystem::is_regular_file(path, error);
}

bool isFolder(const std::string& path) {
  std::error_code error;
  return std::filesystem::is_directory(path, error);
}

std::vector<std::string> listFiles(const std::string& folder, const std::string& suffix, bool recursive) {
  namespace fs = std::filesystem;
  if (!isFolder(folder)) throw InputError(folder, "is not a folder");
  std::vector<std::string> files;
  const auto take = [&](const fs::directory_entry& entry) {
    const std::string path = entry.path().string();
    if (entry.is_regular_file() && path.size() > suffix.size() &&
        path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0)
      files.push_back(path);
  };
  if (recursive)
    for (const auto& entry : fs::recursive_directory_iterator(folder)) take(entry);
  else
    for (const auto& entry : fs::directory_iterator(folder)) take(entry);
  std::sort(files.begin(), files.end());
  return files;
}

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

// Removes the entries of `folder` named PREFIX<PID> (files or folders) whose writer no longer runs: a writer killed
// during its write leaves one behind.
void removeStaleTemporaries(const std::filesystem::path& folder, const std::string& prefix) {
  namespace fs = std::filesystem;
  std::error_code error;
  for (fs::directory_iterator entry(folder, error), end; !error && entry != end; entry.increment(error)) {
    const std::string name = entry->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t writer = static_cast<pid_t>(std::stol(digits));
    if (writer > 0 && kill(writer, 0) == -1 && errno == ESRCH) {
      std::error_code ignored;
      fs::remove_all(entry->path(), ignored);
    }
  }
}

}  // namespace

void writeAtomically(const std::string& path, const std::function<void(const std::string& temporary_path)>& write) {
  const std::filesystem::path target(path);
  const std::filesystem::path folder = target.has_parent_path() ? target.parent_path() : ".";
  createOutputDirectory(folder.string());
  removeStaleTemporaries(folder, target.filename().string() + kTemporarySuffix);
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
  if (error || !isFolder(path))
    throw InputError(path, "cannot create output folder" + (error ? ": " + error.message() : std::string()));
}

OutputFolder::OutputFolder(const std::string& out, const std::vector<std::string>& inputs) : out_(out) {
  namespace fs = std::filesystem;
  std::error_code missing;
  created_ = !fs::exists(out, missing);
  createOutputDirectory(out);
  const fs::path folder(out);
  lock_fd_ = open(out.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (lock_fd_ < 0) throw InputError(out, std::string("cannot open the output folder: ") + std::strerror(errno));
  if (flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    close(lock_fd_);
    throw InputError(out, "another run is writing into this output folder (it holds the folder's lock)");
  }
  // The staging folder is the temporary of a nameless file: OUT/.partialPID.
  removeStaleTemporaries(folder, kTemporarySuffix);
  staging_ = (folder / (kTemporarySuffix + std::to_string(getpid()))).string();
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
  createOutputDirectory(staging_);
  for (const std::string& input : inputs) {
    if (input.empty()) continue;  // an optional input not given
    std::error_code error;
    const fs::path canonical = fs::weakly_canonical(input, error);
    if (!error) inputs_.push_back(canonical.string());
  }
}

OutputFolder::~OutputFolder() {
  std::error_code ignored;
  if (!staging_.empty()) std::filesystem::remove_all(staging_, ignored);
  if (created_ && !committed_) std::filesystem::remove(out_, ignored);  // only when empty
  if (lock_fd_ >= 0) close(lock_fd_);  // releases the lock
}

std::string OutputFolder::file(const std::string& name) const {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path final_path = fs::weakly_canonical(fs::path(out_) / name, error);
  for (const std::string& input : inputs_)
    if (!error && final_path.string() == input)
      throw InputError(out_, "the output " + name + " would replace the input " + input +
                                 ": choose an --out that does not hold the inputs");
  return (fs::path(staging_) / name).string();
}

std::string OutputFolder::mapPrefix(const std::string& stem, const std::string& image_extension) const {
  file(stem + image_extension);
  file(stem + ".yaml");
  return file(stem);
}

void OutputFolder::commit() {
  namespace fs = std::filesystem;
  std::vector<fs::path> staged;
  std::error_code error;
  for (fs::directory_iterator entry(staging_, error), end; !error && entry != end; entry.increment(error))
    staged.push_back(entry->path());
  if (error) throw InputError(out_, "cannot list the staged outputs: " + error.message());
  for (const fs::path& file : staged)
    if (isFolder((fs::path(out_) / file.filename()).string()))
      throw InputError((fs::path(out_) / file.filename()).string(), "is a folder: the output of that name cannot "
                                                                     "replace it (nothing was written)");
  for (const fs::path& file : staged) {
    fs::rename(file, fs::path(out_) / file.filename(), error);
    if (error) throw InputError((fs::path(out_) / file.filename()).string(), "cannot be written: " + error.message());
  }
  committed_ = true;
}

std::map<std::string, double> loadParameterFile(const std::string& path) {
  const YAML::Node root = common::loadYamlFile(path, "parameters file");
  std::map<std::string, double> parameters;
  if (root.IsNull()) return parameters;
  if (!root.IsMap()) throw common::InputError(path, "parameters file must be a mapping of names to numbers");
  for (const auto& entry : root) {
    if (!entry.first.IsScalar()) throw common::InputError(path, "a parameter name is not a plain name");
    const std::string name = entry.first.Scalar();
    double value = 0.0;
    try {
      value = entry.second.as<double>();
    } catch (const YAML::Exception&) {
      throw common::InputError(path, "parameter '" + name + "' is not a number");
    }
    if (!std::isfinite(value)) throw common::InputError(path, "parameter '" + name + "' is not finite");
    parameters[name] = value;
  }
  return parameters;
}

}  // namespace hidden_rooms::common
