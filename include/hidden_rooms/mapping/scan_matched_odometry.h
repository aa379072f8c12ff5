#pragma once

#include <deque>
#include <memory>
#include <string>

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
};
// Reads [ScanMatching] (absent: disabled). Throws InputError naming the file for a bad value.
ScanMatchingOptions readScanMatchingOptions(const mrpt::config::CConfigFileBase& ini, const std::string& file);

// Odometry corrected by scan matching, as laser odometry front-ends do before a SLAM back-end: each scan is
// matched against a local map of the last keyframe scans (and, with map_radius, of the places seen before near the
// robot) by a correlative search (Olson, "Real-time correlative
// scan matching", 2009) over a window of poses around the odometry's prediction, each pose weighted by the scan's
// likelihood there times the prediction's Gaussian (the ini's motion model): the corrected pose is the mean of
// that posterior. Along a corridor, where the scan fits equally well at many positions, the odometry keeps the
// position along it; across it and in turns the scan corrects it.
class ScanMatchedOdometry {
 public:
  struct MotionNoise {  // the motion model's std. dev. growth: metres per metre, metres per radian, radians per
    double a1, a2, a3, a4, min_xy, min_phi;  // metre, radians per radian; floors in metres and radians
  };
  ScanMatchedOdometry(const ScanMatchingOptions& options, const MotionNoise& noise);
  ~ScanMatchedOdometry();

  // The corrected pose for this odometry pose and scan (the first one: the odometry pose itself).
  common::Pose2 correct(const common::Pose2& odometry, const mrpt::obs::CObservation2DRangeScan& scan);

 private:
  struct Keyframe;
  struct LocalMap;
  void rebuildLocalMap();
  ScanMatchingOptions options_;
  MotionNoise noise_;
  bool started_ = false;
  common::Pose2 last_odometry_, last_corrected_, last_keyframe_;
  std::deque<std::shared_ptr<Keyframe>> keyframes_;
  std::unique_ptr<LocalMap> local_map_;
};

}  // namespace hidden_rooms::mapping
