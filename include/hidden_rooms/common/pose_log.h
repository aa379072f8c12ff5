#pragma once

#include <string>
#include <vector>

#include "hidden_rooms/common/geometry.h"

namespace hidden_rooms::common {

// One logged pose: time (seconds, the ROS clock of the run) and the planar pose in the log's frame.
struct TimedPose {
  double time = 0.0;
  Pose2 pose;
};

// A pose log as the pose_logger node writes it (the thesis's listener, docs/method.md#exploration-runs): '#' comment
// lines, then one pose per line, "time x y yaw" (seconds, metres, metres, radians), times strictly increasing. The
// first comment names the frames ("# frame: map -> base_link").
struct PoseLog {
  std::string parent_frame;
  std::string child_frame;
  std::vector<TimedPose> poses;
};

// Throws InputError naming the file and line for a missing file, a malformed or non-finite line, times that do
// not increase, or a log without poses.
PoseLog loadPoseLog(const std::string& path);
PoseLog parsePoseLog(const std::string& text, const std::string& source_name);

// Prepares the log at `path` to be continued by a restarted pose_logger: a last line cut by a kill (no newline at
// its end) is removed from the file. Returns the time of its last pose; -infinity when the file is missing or
// holds no pose yet. Throws InputError naming the file when its complete lines are no pose log.
double preparePoseLogForAppend(const std::string& path);

// The header line pose_logger writes first, and one pose line (with its newline).
std::string poseLogHeader(const std::string& parent_frame, const std::string& child_frame);
std::string poseLogLine(const TimedPose& pose);

// The pose at `time`, linearly interpolated between the two logged poses around it (yaw along the shorter
// arc); the first or last pose outside the logged interval. `poses` must not be empty and its times increase.
Pose2 poseAt(const std::vector<TimedPose>& poses, double time);

// Length of the path through the logged positions, metres.
double pathLength(const std::vector<TimedPose>& poses);

}  // namespace hidden_rooms::common
