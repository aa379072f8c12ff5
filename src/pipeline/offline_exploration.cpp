#include "hidden_rooms/pipeline/offline_exploration.h"

#include <cmath>
#include <string>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/range_scan.h"
#include "hidden_rooms/exploration/path_follower.h"

namespace hidden_rooms::pipeline {

namespace {

// Free cells of a mapper grid as the planner reads them (0 <= value <= free_threshold).
int freeCells(const common::OccupancyGrid& map, int free_threshold) {
  if (map.empty()) return 0;
  return cv::countNonZero((map.cells >= 0) & (map.cells <= free_threshold));
}

}  // namespace

void validate(const OfflineExplorationOptions& options) {
  const double step = options.simulation.physics_step;
  const auto require = [](bool ok, const std::string& problem) {
    if (!ok) throw common::InputError("offline exploration", problem);
  };
  require(std::isfinite(options.scan_period) && options.scan_period >= step,
          "scan_period must be at least the physics step");
  require(std::isfinite(options.control_period) && options.control_period >= step,
          "control_period must be at least the physics step");
  require(std::isfinite(options.map_update_interval) && options.map_update_interval >= 0.0,
          "map_update_interval must not be negative");
  require(std::isfinite(options.max_time) && options.max_time > 0.0, "max_time must be positive");
  require(std::isfinite(options.growth_interval) && options.growth_interval > 0.0,
          "growth_interval must be positive");
  require(std::isfinite(options.growth), "growth must be finite");
  require(options.patience >= 1, "patience must be at least 1");
}

const char* toString(ExplorationStop stop) {
  switch (stop) {
    case ExplorationStop::kDone:
      return "done";
    case ExplorationStop::kNoGrowth:
      return "no_growth";
    case ExplorationStop::kMaxTime:
      return "max_time";
  }
  return "max_time";
}

OfflineExplorationResult exploreOffline(const simulation::SimulationWorld& world,
                                        const OfflineExplorationOptions& options,
                                        const std::function<void(double)>& progress) {
  validate(options);
  simulation::Simulation simulation(world, options.simulation);
  mapping::RbpfMapper mapper(options.mapper);
  exploration::ExplorationPolicy policy(options.policy);

  const double step = options.simulation.physics_step;
  const uint64_t scan_steps = static_cast<uint64_t>(std::lround(options.scan_period / step));
  const uint64_t control_steps = static_cast<uint64_t>(std::lround(options.control_period / step));
  const uint64_t growth_steps = static_cast<uint64_t>(std::lround(options.growth_interval / step));
  const uint64_t last_step = static_cast<uint64_t>(std::lround(options.max_time / step));
  const int free_threshold = options.policy.planner.free_threshold;

  OfflineExplorationResult result;
  common::RangeScan scan;
  scan.angle_min = simulation.laserGeometry().angle_min;
  scan.angle_increment = simulation.laserGeometry().angle_increment;
  scan.range_min = options.simulation.laser.min_range;
  scan.range_max = simulation.laserGeometry().max_range;
  scan.sensor_pose = options.simulation.laser.mount;
  std::vector<common::Point2> points;
  bool scan_pending = false, have_map = false;
  double last_map_time = 0.0;
  int last_free = -1, flat_checks = 0;
  common::Point2 last_position(simulation.truePose().x, simulation.truePose().y);

  for (uint64_t k = 1; k <= last_step; ++k) {
    simulation.step();
    const double now = simulation.time();
    const common::Pose2 true_pose = simulation.truePose();
    result.distance_driven += std::hypot(true_pose.x - last_position.x(), true_pose.y - last_position.y());
    last_position = common::Point2(true_pose.x, true_pose.y);

    if (k % scan_steps == 0) {
      simulation.scan(&scan.ranges);
      if (mapper.addScan(simulation.odometryPose(), scan)) ++result.scans_inserted;
      ++result.scans;
      result.truth.push_back({now, true_pose});
      result.estimate.push_back({now, mapper.pose()});
      points = exploration::obstaclePoints(scan);
      scan_pending = true;
      if (!have_map || now - last_map_time >= options.map_update_interval - 0.5 * step) {
        result.map = mapper.map();
        if (!result.map.empty()) {
          policy.setMap(result.map);
          have_map = true;
          last_map_time = now;
          if (progress) progress(now);
        }
      }
    }
    if (have_map && k % control_steps == 0) {
      const common::Pose2 pose = common::composePoses(mapper.mapToOdom(), simulation.odometryPose());
      if (scan_pending) {
        policy.addScan(points, pose, now);
        scan_pending = false;
      }
      const exploration::ExplorationStep control = policy.update(pose, now);
      for (const exploration::ExplorationEvent& event : control.events)
        result.goals += event.type == exploration::ExplorationEventType::kGoalChosen ? 1 : 0;
      simulation.setCommand(control.command);
      if (policy.done()) {
        result.stop = ExplorationStop::kDone;
        break;
      }
    }
    if (k % growth_steps == 0 && options.growth >= 0.0) {
      const int free = freeCells(result.map, free_threshold);
      const bool grew = last_free < 0 || free >= last_free * (1.0 + options.growth);
      flat_checks = grew ? 0 : flat_checks + 1;
      last_free = free;
      if (flat_checks >= options.patience) {
        result.stop = ExplorationStop::kNoGrowth;
        break;
      }
    }
  }
  result.simulated_seconds = simulation.time();
  result.map = mapper.map();
  return result;
}

}  // namespace hidden_rooms::pipeline
