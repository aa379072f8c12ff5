#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/options.h"
#include "hidden_rooms/common/range_scan.h"

namespace mrpt::obs {
class CObservation2DRangeScan;
}

namespace hidden_rooms::mapping {

struct RbpfMapperOptions {
  // MRPT ini file (config/rbpf.ini): particle filter, proposal, insertion distances, grid, likelihood model and
  // the odometry motion model ([<section>_motionModel]).
  std::string config_file;
  std::string section = "MappingApplication";
  // Seed of MRPT's random generator: the same scans with the same seed give the same map.
  uint32_t seed = 0;
};

// The ini's file and section as parameters (config_file, config_section); the seed (unsigned) is not in it.
const common::OptionTable<RbpfMapperOptions>& rbpfMapperOptionTable();

// A particle of the filter: the robot pose (base_link in the map frame) and its normalised weight.
struct RbpfParticle {
  common::Pose2 pose;
  double weight = 0.0;
};

// SLAM with MRPT's Rao-Blackwellized particle filter (mrpt::slam::CMetricMapBuilderRBPF) over occupancy grids.
// Fed (odometry pose, scan) pairs in time order. The map frame starts at the first odometry pose, so map -> odom
// is the identity until the filter corrects the odometry. MRPT's random generator is process-global: run one
// mapper per process for reproducible maps.
class RbpfMapper {
 public:
  // Throws InputError naming the file for a missing file, a malformed or incomplete ini, or one without an
  // occupancy grid.
  explicit RbpfMapper(const RbpfMapperOptions& options);
  ~RbpfMapper();
  RbpfMapper(const RbpfMapper&) = delete;
  RbpfMapper& operator=(const RbpfMapper&) = delete;

  // One step: the odometry pose of base_link (odom frame) at the scan's time, and the scan. The filter updates
  // (and the map grows) only when the odometry moved beyond the ini's localize / insertion distances since the
  // last update. Returns true when the scan was inserted into the map. Throws InputError for a scan without
  // beams or with a non-finite geometry.
  bool addScan(const common::Pose2& odometry, const common::RangeScan& scan);
  // The same with a scan already in MRPT's form (ROS messages: src/ros/mrpt_scan.h, mrpt-ros1bridge);
  // its sensorPose is the laser in base_link. Throws InputError for a scan without beams.
  bool addScan(const common::Pose2& odometry, const mrpt::obs::CObservation2DRangeScan& scan);

  int scansAdded() const;
  int scansInserted() const;
  // The pose estimate of base_link in the map frame: the pose (with the odometry since the filter's last update)
  // of the particle whose grid map() returns, so that pose and map agree; the first odometry pose before any scan.
  common::Pose2 pose() const;
  // pose() after each scan added so far, as the mapper estimates them now: a loop closure of the scan-matching
  // front-end moves earlier poses with the keyframes they were anchored to.
  std::vector<common::Pose2> trajectory() const;
  // map -> odom (REP-105): the transform that puts the last odometry pose at pose().
  common::Pose2 mapToOdom() const;
  std::vector<RbpfParticle> particles() const;
  // The published grid in the map frame (-1 never observed, else 0..100 = occupancy probability in percent):
  // every inserted scan drawn along the path of the most likely particle with the [PublishedMap] certainties of
  // the ini. Empty before the first inserted scan.
  common::OccupancyGrid map() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hidden_rooms::mapping
