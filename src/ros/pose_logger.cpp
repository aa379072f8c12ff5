#include "hidden_rooms/ros/pose_logger.h"

#include <cmath>
#include <filesystem>
#include <limits>

#include <tf2/exceptions.h>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/pose_log.h"
#include "hidden_rooms/ros/conversions.h"
#include "hidden_rooms/ros/lockstep.h"
#include "hidden_rooms/ros/parameters.h"

namespace hidden_rooms {

namespace {

constexpr double kGiveUpDelay = 1.0;  // seconds of ROS time after which a pose tf cannot give is skipped
// In lockstep, a pose whose transforms are late (tf has none after it yet) waits up to this many seconds of wall
// time: ROS time runs many times faster than the transforms of a busy machine may arrive.
constexpr double kLockstepGiveUpWall = 5.0;
// tf messages held for the node's one thread: tf2_ros's listener keeps 100, which a lockstep run at 15 times real
// time fills in a fifth of a second of a busy machine's wall time, and then drops poses.
constexpr uint32_t kTransformQueue = 10000;

// Opens a log for writing (appending: after its last complete line), creating its folder; returns the time of
// the last pose already in it (-infinity: none). Throws InputError when that fails.
double openLog(const std::string& path, bool append, std::ofstream* log) {
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::error_code error;
  if (!folder.empty()) std::filesystem::create_directories(folder, error);
  const double last_time = append ? common::preparePoseLogForAppend(path) : -std::numeric_limits<double>::infinity();
  log->open(path, std::ios::out | (append ? std::ios::app : std::ios::trunc));
  if (!*log) throw common::InputError(path, "cannot be written (pose log)");
  return last_time;
}

bool emptyFile(const std::string& path) {
  std::error_code error;
  return std::filesystem::file_size(path, error) == 0 || error;
}

}  // namespace

const common::OptionTable<PoseLoggerOptions>& poseLoggerNodeOptionTable() {
  using O = PoseLoggerOptions;
  static const common::OptionTable<O> table{
      {"estimate_log", &O::estimate_log, "the map -> base_link log (its folder is created)", common::anyFinite(), true},
      {"ground_truth_log", &O::ground_truth_log, "the ground-truth log; \"\" = not logged"},
      {"map_frame", &O::map_frame, "parent frame of the estimate", common::anyFinite(), true},
      {"base_frame", &O::base_frame, "the robot's frame", common::anyFinite(), true},
      {"ground_truth_topic", &O::ground_truth_topic, "topic of the true pose"},
      {"period", &O::period, "seconds of ROS time between logged poses", common::above(0)},
      {"append", &O::append, "continue existing logs instead of starting them afresh"},
      {"lockstep", &O::lockstep, "until the clock runs, report ready on `lockstep` while subscribed to every "
       "publisher of tf and of the ground-truth topic (for the simulator's ~lockstep_start_nodes)"},
  };
  return table;
}

std::vector<common::OptionDescription> poseLoggerParameters() {
  return common::describeOptions(poseLoggerNodeOptionTable());
}

PoseLoggerOptions readPoseLoggerOptions(const ros::NodeHandle& private_nh) {
  PoseLoggerOptions options;
  readParameters(private_nh, poseLoggerNodeOptionTable(), &options);
  return options;
}

PoseLogger::PoseLogger(ros::NodeHandle nh, const PoseLoggerOptions& options)
    : options_(options), tf_buffer_(ros::Duration(10.0)) {
  // On the timer's queue: the transforms that came before a timer event are in the buffer when it is handled.
  tf_subscriber_ = nh.subscribe<tf2_msgs::TFMessage>(
      "/tf", kTransformQueue, [this](const tf2_msgs::TFMessage::ConstPtr& message) { addTransforms(*message, false); });
  tf_static_subscriber_ = nh.subscribe<tf2_msgs::TFMessage>(
      "/tf_static", kTransformQueue,
      [this](const tf2_msgs::TFMessage::ConstPtr& message) { addTransforms(*message, true); });
  last_estimate_time_ = openLog(options.estimate_log, options.append, &estimate_log_);
  if (emptyFile(options.estimate_log))
    estimate_log_ << common::poseLogHeader(options.map_frame, options.base_frame) << std::flush;
  if (!options.ground_truth_log.empty()) {
    // Its frames are written with the first message (its header names the world frame).
    last_ground_truth_time_ = openLog(options.ground_truth_log, options.append, &ground_truth_log_);
    ground_truth_header_written_ = !emptyFile(options.ground_truth_log);
    ground_truth_subscriber_ = nh.subscribe(options.ground_truth_topic, 100, &PoseLogger::onGroundTruth, this);
  }
  if (options.lockstep) {
    // On the wall clock: ROS time stands still while the simulator holds, and the last poses must still come.
    wall_timer_ = nh.createWallTimer(ros::WallDuration(0.02), [this](const ros::WallTimerEvent&) { logEstimates(); });
    lockstep_publisher_ = nh.advertise<hidden_rooms::LockstepAck>("lockstep", 10, true);
    ready_timer_ = nh.createWallTimer(ros::WallDuration(0.1), &PoseLogger::onReadyTimer, this);
  } else {
    timer_ = nh.createTimer(ros::Duration(options.period), [this](const ros::TimerEvent&) { logEstimates(); });
  }
}

void PoseLogger::onReadyTimer(const ros::WallTimerEvent&) {
  if (!ros::Time::now().isZero()) {  // the clock runs: the world has started
    ready_timer_.stop();
    return;
  }
  if (connectedToEveryPublisher(tf_subscriber_) &&
      (options_.ground_truth_log.empty() || connectedToEveryPublisher(ground_truth_subscriber_)))
    lockstep_publisher_.publish(lockstepReport(ros::Time()));
}

bool PoseLogger::transformsLate(const ros::Time& time) {
  try {
    if (tf_buffer_.lookupTransform(options_.map_frame, options_.base_frame, ros::Time(0)).header.stamp >= time)
      return false;  // tf has newer transforms: those at `time` are missing, not late
  } catch (const tf2::TransformException&) {
    // none yet
  }
  if (first_try_.isZero()) first_try_ = ros::WallTime::now();
  return (ros::WallTime::now() - first_try_).toSec() < kLockstepGiveUpWall;
}

void PoseLogger::logEstimates() {
  // Poses on the grid of multiples of the period, each logged once tf can give it (tf interpolates between the
  // odometry's and the mapper's transforms around it). A grid time tf still cannot give after kGiveUpDelay is
  // skipped (in lockstep, once tf has transforms after it, or after kLockstepGiveUpWall).
  const double now = ros::Time::now().toSec();
  if (now <= 0.0) return;
  // The grid starts where this logger came in, or in lockstep at the world's start, which waited for it.
  if (next_estimate_time_ <= 0.0)
    next_estimate_time_ = options_.lockstep ? options_.period : std::ceil(now / options_.period) * options_.period;
  if (last_estimate_time_ > now)
    ROS_WARN_ONCE("pose_logger: the continued log %s ends at %.2f s, after the ROS time now (%.2f s; a log of another "
                  "run?): poses are logged from then on", options_.estimate_log.c_str(), last_estimate_time_, now);
  while (next_estimate_time_ <= now) {
    if (next_estimate_time_ <= last_estimate_time_ + 1e-6) {  // already in the continued log
      next_estimate_time_ += options_.period;
      continue;
    }
    const ros::Time wanted(next_estimate_time_);
    std::string problem;
    if (tf_buffer_.canTransform(options_.map_frame, options_.base_frame, wanted, &problem)) {
      const geometry_msgs::TransformStamped transform =
          tf_buffer_.lookupTransform(options_.map_frame, options_.base_frame, wanted);
      estimate_log_ << common::poseLogLine({next_estimate_time_, fromRos(transform.transform)}) << std::flush;
      ++estimates_logged_;
    } else if (now - next_estimate_time_ < kGiveUpDelay || (options_.lockstep && transformsLate(wanted))) {
      return;  // the transforms around it may still come
    } else {
      ROS_WARN_THROTTLE(10.0, "pose_logger: no %s -> %s at %.2f s: %s", options_.map_frame.c_str(),
                        options_.base_frame.c_str(), next_estimate_time_, problem.c_str());
    }
    next_estimate_time_ += options_.period;
    first_try_ = ros::WallTime();
  }
}

void PoseLogger::addTransforms(const tf2_msgs::TFMessage& message, bool is_static) {
  // A bad transform is refused with tf2's own error message.
  for (const geometry_msgs::TransformStamped& transform : message.transforms)
    tf_buffer_.setTransform(transform, "tf", is_static);
}

void PoseLogger::onGroundTruth(const nav_msgs::Odometry::ConstPtr& message) {
  const ros::Time stamp = message->header.stamp;
  if (!last_ground_truth_stamp_.isZero() && (stamp - last_ground_truth_stamp_).toSec() < options_.period - 1e-6)
    return;
  const common::Pose2 pose = fromRos(message->pose.pose);
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.yaw)) {
    ROS_WARN_THROTTLE(10.0, "pose_logger: ground-truth pose with a non-finite value dropped");
    return;
  }
  if (stamp.toSec() <= last_ground_truth_time_ + 1e-6) return;  // already in the continued log
  if (!ground_truth_header_written_) {
    ground_truth_log_ << common::poseLogHeader(message->header.frame_id, message->child_frame_id + " (ground truth)");
    ground_truth_header_written_ = true;
  }
  last_ground_truth_stamp_ = stamp;
  ground_truth_log_ << common::poseLogLine({stamp.toSec(), pose}) << std::flush;
  ++ground_truth_logged_;
}

}  // namespace hidden_rooms
