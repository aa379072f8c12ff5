#pragma once

// The scan conversion of the mapper node and map_from_bag: sensor_msgs/LaserScan -> MRPT through mrpt-ros1bridge.
// Only these two link MRPT (library hidden_rooms_mapping_ros), so the other nodes keep their short start-up. A
// private header: packages that build against this one do not get MRPT's include folders.

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <sensor_msgs/LaserScan.h>

#include "hidden_rooms/simulation/laser_caster.h"

namespace hidden_rooms {

// The scan for RbpfMapper::addScan, with `sensor_pose` the pose of the scan's frame in base_link. Converted by
// mrpt::ros1bridge::fromROS after normalising the message to what it expects (counter-clockwise beams, angles
// symmetric about the laser's x axis: the sensor pose is yawed to the middle of the scan instead); the beams'
// ranges are then checked by index (fromROS can take a neighbouring beam). Beams that are NaN, infinite, at or
// below range_min or at or beyond 0.99 range_max (no return) are invalid: kept at range_max, not inserted nor
// matched. Throws InputError for fewer than 2 beams, a zero or non-finite angle increment, a
// non-positive or non-finite range_max or a non-finite sensor pose.
mrpt::obs::CObservation2DRangeScan toMrptScan(const sensor_msgs::LaserScan& message, const common::Pose2& sensor_pose);

// True when `range` is a return of `message` by toMrptScan's rule: finite and strictly between range_min and
// 0.99 range_max.
bool isValidRange(const sensor_msgs::LaserScan& message, float range);
// The beams of `message` with a valid range (0 for a scan of NaN, infinite or out-of-range values only).
size_t countValidRanges(const sensor_msgs::LaserScan& message);

}  // namespace hidden_rooms
