#pragma once

// rviz markers of the package's nodes, built in one place: the prediction overlays (room_predictor), the layout
// analysis's debug overlays, and the explorer's frontiers, goal, path, blacklist and blocked passages. Every array
// starts with a DELETEALL marker, so that fewer markers than last time leave nothing behind.

#include <optional>
#include <string>
#include <vector>

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/exploration/frontier.h"
#include "hidden_rooms/prediction/layout.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "hidden_rooms/segmentation/floor.h"

namespace hidden_rooms {

// rviz overlays of a prediction, in `frame_id`: a DELETEALL marker first (so that fewer rooms than last time
// leave nothing behind), then per predicted room a filled area (namespace "rooms", the cells of its label in
// `labels`, colour of roomColour()), its outline ("outlines"), a text with door id and area ("labels"); every
// door as a thick line across its width ("doors": red when its room is predicted, grey when not placed).
visualization_msgs::MarkerArray toMarkers(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                                          const std::vector<prediction::RoomPrediction>& rooms, const cv::Mat1w& labels,
                                          const std::string& frame_id, const ros::Time& stamp);
// Debug overlays of the layout analysis: its extended lines ("debug_extended_lines": walls blue, door-pair lines
// orange, boundary lines grey) and its cells ("debug_in_out_cells": IN cells green, OUT cells red, translucent).
visualization_msgs::MarkerArray toDebugMarkers(const common::OccupancyGrid& map, const prediction::Layout& layout,
                                               const std::string& frame_id, const ros::Time& stamp);

// A segmented floor in `frame_id`: per room its outline ("room_outlines", room colour; predicted rooms paler), a
// text with its number, type and area ("room_labels"), a sphere at its centroid ("room_nodes"); the topological map's
// edges from each room's centroid to the passage ("room_graph": open doorways green, closed doors red, doors to
// predicted rooms orange).
visualization_msgs::MarkerArray toMarkers(const segmentation::SegmentedFloor& floor, const std::string& frame_id,
                                          const ros::Time& stamp);

// What the explorer shows of one plan (map frame).
struct ExplorationView {
  const exploration::FrontierMap* frontiers = nullptr;
  int goal_frontier_label = -1;  // the frontier the goal lies on; -1 without a goal
  std::optional<common::Point2> goal;
  std::vector<common::Point2> path;
  std::vector<common::Point2> blacklist;
  std::vector<common::Point2> blocked_passages;
  double blocked_passage_radius = 0.0;  // metres
};

// The explorer's overlays in `frame_id`: the frontier cells ("frontiers": the goal's frontier orange, others blue),
// the goal ("goal", orange sphere), the path to it ("path", green line), blacklisted places ("blacklist", red) and
// blocked passages ("blocked_passages", purple discs of their radius).
visualization_msgs::MarkerArray toMarkers(const common::OccupancyGrid& map, const ExplorationView& view,
                                          const std::string& frame_id, const ros::Time& stamp);

}  // namespace hidden_rooms
