#pragma once

#include <functional>
#include <vector>

#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/pose_log.h"
#include "hidden_rooms/exploration/exploration_policy.h"
#include "hidden_rooms/mapping/rbpf_mapper.h"
#include "hidden_rooms/simulation/simulation.h"

namespace hidden_rooms::pipeline {

// The exploration run of exploration_run.launch (simulator, mapper, explorer) in one process, on one simulated
// clock and as fast as the CPU allows: the same core simulation, RBPF mapper and exploration policy, with the
// nodes' rates. Scan and control ticks share the clock exactly (no message latency); otherwise it is the online
// run.
struct OfflineExplorationOptions {
  simulation::SimulationOptions simulation;
  mapping::RbpfMapperOptions mapper;          // config_file must be set (the package's config/rbpf.ini)
  exploration::ExplorationPolicyOptions policy;
  double scan_period = 0.1;           // seconds between scans (the simulator node's 10 Hz); each goes to the mapper
  double control_period = 0.1;        // seconds between explorer commands (its control_rate)
  double map_update_interval = 2.0;   // seconds between maps the mapper hands the explorer (the mapper node's)
  double max_time = 1800.0;           // simulated seconds at most
  // explore_worlds' no-growth stop: the map is checked every growth_interval seconds; after `patience` checks in
  // a row each with less than `growth` (a fraction) more free cells than the one before, the run stops.
  // growth < 0: never.
  double growth_interval = 120.0;
  double growth = 0.001;
  int patience = 3;
};

// Throws InputError("offline exploration", ...) for a non-positive period or time, or a period shorter than the
// simulation's physics step; the simulation options are checked by the Simulation.
void validate(const OfflineExplorationOptions& options);

// Why a run ended, named as explore_worlds names its statuses.
enum class ExplorationStop { kDone, kNoGrowth, kMaxTime };
const char* toString(ExplorationStop stop);  // "done", "no_growth", "max_time"

struct OfflineExplorationResult {
  common::OccupancyGrid map;                // the mapper's last map (map frame; -1 unknown, 0..100)
  std::vector<common::TimedPose> truth;     // base_link in the world frame at every scan
  std::vector<common::TimedPose> estimate;  // base_link in the map frame at every scan (the mapper's estimate)
  ExplorationStop stop = ExplorationStop::kMaxTime;
  double simulated_seconds = 0.0;
  double distance_driven = 0.0;  // metres, true path
  int scans = 0;
  int scans_inserted = 0;
  int goals = 0;  // goals chosen (a replan of the same goal is none)
};

// Explores `world` from the simulation's start pose until the policy reports done, the map stops growing or
// max_time. `progress` (optional) is called with the simulated time after each map update. Deterministic: the
// same world, options and seeds give the same result. MRPT's random generator is process-global: one run per
// process at a time.
OfflineExplorationResult exploreOffline(const simulation::SimulationWorld& world,
                                        const OfflineExplorationOptions& options,
                                        const std::function<void(double)>& progress = {});

}  // namespace hidden_rooms::pipeline
