#include "hidden_rooms/common/pose_log.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/range_scan.h"

namespace hidden_rooms::common {

namespace {

// Reads "parent -> child" from a "# frame: parent -> child" comment; leaves the frames alone otherwise.
void readFrames(const std::string& comment, PoseLog* log) {
  const std::string key = "frame:";
  const size_t at = comment.find(key);
  if (at == std::string::npos) return;
  std::istringstream frames(comment.substr(at + key.size()));
  std::string parent, arrow, child;
  if (frames >> parent >> arrow >> child && arrow == "->") {
    log->parent_frame = parent;
    log->child_frame = child;
  }
}

}  // namespace

PoseLog parsePoseLog(const std::string& text, const std::string& source_name) {
  PoseLog log;
  std::istringstream lines(text);
  std::string line;
  int line_number = 0;
  while (std::getline(lines, line)) {
    ++line_number;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    if (line[first] == '#') {
      if (log.poses.empty()) readFrames(line, &log);
      continue;
    }
    std::istringstream fields(line);
    TimedPose entry;
    std::string extra;
    const std::string where = "line " + std::to_string(line_number);
    if (!(fields >> entry.time >> entry.pose.x >> entry.pose.y >> entry.pose.yaw) || (fields >> extra))
      throw InputError(source_name, where + ": expected 'time x y yaw', got '" + line + "'");
    if (!std::isfinite(entry.time) || !std::isfinite(entry.pose.x) || !std::isfinite(entry.pose.y) ||
        !std::isfinite(entry.pose.yaw))
      throw InputError(source_name, where + ": a value is not finite");
    if (!log.poses.empty() && entry.time <= log.poses.back().time)
      throw InputError(source_name, where + ": time " + std::to_string(entry.time) +
                                        " does not increase over the line before");
    log.poses.push_back(entry);
  }
  if (log.poses.empty()) throw InputError(source_name, "no poses");
  return log;
}

PoseLog loadPoseLog(const std::string& path) { return parsePoseLog(readTextFile(path, "pose log"), path); }

double preparePoseLogForAppend(const std::string& path) {
  constexpr double kNoPose = -std::numeric_limits<double>::infinity();
  std::error_code error;
  if (!std::filesystem::exists(path, error)) return kNoPose;
  std::string text = readTextFile(path, "pose log");
  const size_t complete = text.empty() || text.back() == '\n' ? text.size() : text.rfind('\n') + 1;  // npos + 1 = 0
  if (complete < text.size()) {
    std::filesystem::resize_file(path, complete, error);
    if (error) throw InputError(path, "cannot cut the unfinished last line: " + error.message());
    text.resize(complete);
  }
  // Lines that are not comments or blank make a pose log, which must parse.
  std::istringstream lines(text);
  std::string line;
  bool has_pose = false;
  while (!has_pose && std::getline(lines, line)) {
    const size_t first = line.find_first_not_of(" \t\r");
    has_pose = first != std::string::npos && line[first] != '#';
  }
  return has_pose ? parsePoseLog(text, path).poses.back().time : kNoPose;
}

std::string poseLogHeader(const std::string& parent_frame, const std::string& child_frame) {
  return "# frame: " + parent_frame + " -> " + child_frame + "\n# time x y yaw (s, m, m, rad)\n";
}

std::string poseLogLine(const TimedPose& pose) {
  std::ostringstream line;
  line << std::fixed << std::setprecision(4) << pose.time << ' ' << pose.pose.x << ' ' << pose.pose.y << ' '
       << std::setprecision(5) << pose.pose.yaw << '\n';
  return line.str();
}

Pose2 poseAt(const std::vector<TimedPose>& poses, double time) {
  const auto after = std::lower_bound(poses.begin(), poses.end(), time,
                                      [](const TimedPose& entry, double t) { return entry.time < t; });
  if (after == poses.begin()) return poses.front().pose;
  if (after == poses.end()) return poses.back().pose;
  const TimedPose& before = *(after - 1);
  const double fraction = (time - before.time) / (after->time - before.time);
  Pose2 pose;
  pose.x = before.pose.x + fraction * (after->pose.x - before.pose.x);
  pose.y = before.pose.y + fraction * (after->pose.y - before.pose.y);
  pose.yaw = wrapAngle(before.pose.yaw + fraction * wrapAngle(after->pose.yaw - before.pose.yaw));
  return pose;
}

double pathLength(const std::vector<TimedPose>& poses) {
  double length = 0.0;
  for (size_t k = 1; k < poses.size(); ++k)
    length += std::hypot(poses[k].pose.x - poses[k - 1].pose.x, poses[k].pose.y - poses[k - 1].pose.y);
  return length;
}

}  // namespace hidden_rooms::common
