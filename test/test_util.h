#pragma once

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/occupancy_grid.h"

namespace hidden_rooms::testing {

// The shared data folder (thesis environments, closed-door benchmark). Empty when it is absent; tests that
// need it skip then, unless HIDDEN_ROOMS_REQUIRE_SHARED=1 (set by scripts/test.sh), when they fail.
inline std::string sharedDir() {
  const char* from_env = std::getenv("HIDDEN_ROOMS_SHARED_DIR");
  std::string dir = from_env != nullptr ? from_env : HIDDEN_ROOMS_SHARED_DIR;
  if (std::filesystem::is_directory(dir + "/data")) return dir;
  return "";
}

inline bool sharedRequired() {
  const char* flag = std::getenv("HIDDEN_ROOMS_REQUIRE_SHARED");
  return flag != nullptr && std::string(flag) == "1";
}

#define HIDDEN_ROOMS_REQUIRE_SHARED_DATA()                                                  \
  do {                                                                                      \
    if (::hidden_rooms::testing::sharedDir().empty()) {                                     \
      if (::hidden_rooms::testing::sharedRequired()) FAIL() << "shared data folder missing"; \
      GTEST_SKIP() << "shared data folder not found";                                       \
    }                                                                                       \
  } while (0)

// All environment XML files of the shared data, sorted.
inline std::vector<std::string> sharedEnvironmentFiles() {
  std::vector<std::string> files;
  const std::string root = sharedDir() + "/data/environments";
  if (!std::filesystem::is_directory(root)) return files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root))
    if (entry.path().extension() == ".xml") files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

// The message of the InputError that `call` throws; "no error" when it returns (other exceptions pass through).
inline std::string inputErrorMessage(const std::function<void()>& call) {
  try {
    call();
  } catch (const common::InputError& error) {
    return error.what();
  }
  return "no error";
}

// A fresh empty temporary folder for one test.
inline std::string makeTempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("hidden_rooms_test_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace hidden_rooms::testing

namespace hidden_rooms::testing {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a shell command and captures its output and exit code.
CommandResult runCommand(const std::string& command);

// Starts `arguments` (the program first, no shell) with stdout and stderr going to `log_path`; the child's pid.
int startProcess(const std::vector<std::string>& arguments, const std::string& log_path);
// SIGKILLs the child `pid` and reaps it; true when it was still running then (it died of the signal).
bool killProcess(int pid);
// Waits for the child `pid`; its exit code, -1 when it died of a signal.
int waitProcess(int pid);
// The names of the files in `dir` (not recursive), sorted.
std::vector<std::string> fileNames(const std::string& dir);
// The whole content of a file (empty when it cannot be read).
std::string readFile(const std::string& path);
// Starts `attempts` runs with `start` (returns the child's pid) and SIGKILLs the k-th after (k + 0.5) / attempts of
// `seconds`, calling `after_kill(k)` once it is dead; how many runs were still running when killed.
int killSpreadOver(const std::function<int()>& start, double seconds, int attempts,
                   const std::function<void(int)>& after_kill);

// A tiny environment in the thesis schema (0.05 m per pixel): a 10 m x 2 m corridor (pixels x 0..200,
// y 0..40) under two rooms, A (x 0..80, y 40..120) and B (x 80..200, y 40..120), each with one door to the
// corridor (door 1 at (40, 40) into A, door 2 at (140, 40) into B). `extra_portal` adds a PORTAL segment at a
// pixel position to room A (to build files with a door on no wall).
std::string corridorWithTwoRoomsXml(const std::string& door1_status = "", const std::string& extra_portal = "");

// That environment rendered with door 1 closed and room A's free cells unknown: the map a robot exploring the
// corridor would build, its closed door, and the true room (label 1 on room A).
void syntheticHiddenRoomA(common::OccupancyGrid* map, common::DoorsFile* doors, cv::Mat1w* truth);

// Mean IoU of a prediction method over the valid cases of the shared closed-door benchmark, scored as
// scripts/benchmark_closed_doors.py does (rooms.png labels, mean over each case's doors, then over cases).
// Counts the cases in `cases` when given.
double benchmarkMeanIou(const std::string& method, int* cases = nullptr);

// Room-by-room agreement of a method with the thesis implementation's rooms (reference_rooms.png) over the valid
// benchmark cases that have them, as scripts/benchmark_closed_doors.py --agreement scores it: per door the IoU of the
// two rooms, 1 when both are empty, then the mean over all rooms. Counts the rooms in `rooms` when given.
double benchmarkAgreement(const std::string& method, int* rooms = nullptr);

}  // namespace hidden_rooms::testing
