#pragma once

#include <deque>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "hidden_rooms/common/geometry.h"

namespace mrpt::config {
class CConfigFileBase;
}
namespace mrpt::obs {
class CObservation2DRangeScan;
}

namespace hidden_rooms::mapping {

// Options of the odometry front-end, the ini's [ScanMatching] section (config/rbpf_real_laser.ini).
struct ScanMatchingOptions {
  bool enabled = false;
  double keyframe_distance = 0.2;   // metres: a scan joins the local map after the robot moved this far ...
  double keyframe_angle_deg = 5.0;  // ... or turned this much since the last one that joined
  int local_map_scans = 30;         // scans in the local map the next scans are matched against
  double resolution = 0.025;        // metres: cells of the local map's likelihood field and of the search
  double angle_step_deg = 0.25;     // degrees between the headings searched
  double point_sigma = 0.05;        // metres: a scan point's distance to the local map's nearest point is this
                                    // noisy (the likelihood field's width)
  double min_goodness = 0.5;        // a match with fewer points within 2 point_sigma of the map is not used
  double max_range = 20.0;          // metres: returns farther away are not matched (nor kept in the local map)
  double map_radius = 0.0;          // metres: older keyframes this near the newest join the local map too
                                    // (places seen before pull the pose back to where they were mapped); 0 = none
  // Loop closure: the keyframes form a pose graph (edges: each keyframe's match to the one before it); when the
  // robot comes back to a place it left at least loop_min_travel metres of path before, its scan is searched for
  // in the map of that place over a wide window (loop_search_radius metres each way, loop_search_angle_deg), and
  // a good match (loop_min_goodness) is one more edge; the graph is then optimized, which moves the whole path.
  double loop_min_travel = 0.0;       // metres; 0 = no loop closure
  double loop_search_radius = 2.0;    // metres
  double loop_search_angle_deg = 15.0;
  double loop_min_goodness = 0.7;
  double loop_check_distance = 1.0;   // metres of path between two searches
};
// Reads [ScanMatching] (absent: disabled). Throws InputError naming the file for a bad value.
ScanMatchingOptions readScanMatchingOptions(const mrpt::config::CConfigFileBase& ini, const std::string& file);

class PoseGraph;
struct ScanLikelihoodField;  // the local map the scans are matched against (scan_matched_odometry.cpp)

// A pose held relative to a keyframe, so that it follows the keyframe when the pose graph moves it.
struct KeyframeAnchor {
  static constexpr size_t kNone = static_cast<size_t>(-1);  // no keyframe: offset is the pose itself
  size_t keyframe = kNone;
  common::Pose2 offset;  // the pose in the keyframe's frame
};

// Odometry corrected by scan matching, as laser odometry front-ends do before a SLAM back-end: each scan is
// matched against a local map of the last keyframe scans (and, with map_radius, of the places seen before near the
// robot) by a correlative search (Olson, "Real-time correlative scan matching", 2009) over a window of poses around
// the odometry's prediction, each pose weighted by the scan's likelihood there times the prediction's Gaussian (the
// ini's motion model): the corrected pose is the mean of that posterior. Along a corridor, where the scan fits
// equally well at many positions, the odometry keeps the position along it; across it and in turns the scan
// corrects it. With loop_min_travel, a pose graph of the keyframes is the back-end: a loop confirmed by two checks
// in a row adds its edges and the graph is optimized (PoseGraph), moving every keyframe.
class ScanMatchedOdometry {
 public:
  struct MotionNoise {  // the motion model's std. dev. growth: metres per metre, metres per radian, radians per
    double a1, a2, a3, a4, min_xy, min_phi;  // metre, radians per radian; floors in metres and radians
  };
  ScanMatchedOdometry(const ScanMatchingOptions& options, const MotionNoise& noise);
  ~ScanMatchedOdometry();

  // The corrected pose for this odometry pose and scan (the first one: the odometry pose itself). After a loop
  // closure the poses it returns are in the optimized frame: earlier poses move as resolve() says.
  common::Pose2 correct(const common::Pose2& odometry, const mrpt::obs::CObservation2DRangeScan& scan);

  // `pose` (a corrected pose) anchored to the newest keyframe; resolve() gives it back, moved with that keyframe
  // by every optimization since.
  KeyframeAnchor anchor(const common::Pose2& pose) const;
  common::Pose2 resolve(const KeyframeAnchor& anchor) const;
  // How many loops have closed, each moving the keyframes (0 without loop closure).
  int loopClosures() const { return loop_closures_; }

 private:
  struct Keyframe;
  void addKeyframe(const common::Pose2& pose, const std::vector<common::Point2>& points,
                   const Eigen::Matrix3d& covariance);
  void rebuildLocalMap();
  bool closeLoop();
  ScanMatchingOptions options_;
  MotionNoise noise_;
  bool started_ = false;
  common::Pose2 last_odometry_, last_corrected_, last_keyframe_;
  double travelled_ = 0.0, last_loop_check_ = 0.0;  // metres of corrected path
  std::deque<std::shared_ptr<Keyframe>> keyframes_;
  std::unique_ptr<ScanLikelihoodField> local_map_;
  std::unique_ptr<PoseGraph> graph_;  // with loop closure only
  struct LoopCandidate {  // a loop edge waiting for the next check to confirm it
    size_t from, to;
    common::Pose2 relative;
    Eigen::Matrix3d covariance;
    common::Pose2 correction;  // what it would move the newest keyframe by (world frame)
    double travelled;
  };
  std::optional<LoopCandidate> pending_loop_;
  int loop_closures_ = 0;
};

}  // namespace hidden_rooms::mapping
