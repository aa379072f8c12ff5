#pragma once

// The package's room segmentation and the survey's baselines behind the RoomSegmenter interface.

#include <map>
#include <string>

#include "hidden_rooms/segmentation/room_segmenter.h"

namespace hidden_rooms::segmentation {

// "default": rooms are the basins of the free space's distance to the nearest wall, split where the passage
// between two basins is a constriction: narrower than a door (`max_passage_width`) and narrower than
// `passage_ratio` times the smaller basin's widest point. Flooding the distance from its maxima downwards, two
// basins that meet at a wider passage become one room; rooms below `min_room_area`, or narrower than
// `min_room_width` (a robot cannot enter them), join the neighbour they share the longest border with; a free region
// without neighbours is a room unless a robot cannot enter or stand in it (below `min_isolated_area`). Before flooding, openings of straight walls up to `max_wall_gap` wide are closed where the
// wall line goes on beyond them (a room's open front on a corridor's wall line).
class PassageSegmenter : public RoomSegmenter {
 public:
  std::string name() const override { return "default"; }
  std::map<std::string, double> defaultParameters() const override;
  cv::Mat1i segment(const SegmentationInput& input, const std::map<std::string, double>& parameters) const override;
};

// "morphological" (the survey's): erodes the free space one cell at a time; every region that separates from
// the rest with an area between the room limits (measured on the eroded region) is a room's core and leaves the
// erosion; the cores then grow back into the free space.
class MorphologicalSegmenter : public RoomSegmenter {
 public:
  std::string name() const override { return "morphological"; }
  std::map<std::string, double> defaultParameters() const override;
  cv::Mat1i segment(const SegmentationInput& input, const std::map<std::string, double>& parameters) const override;
};

// "voronoi" (the survey's): critical points on the generalized Voronoi graph of the free space (after pruning its
// side branches, the point nearest to a wall in each neighbourhood along the graph, neighbourhoods the longer the
// narrower the passage); from each a critical line to the two nearest wall cells on either side, the one with the
// widest angle kept among close points; the regions the lines separate grow into the free space and merge by the
// survey's rules (small parts, parts closed off by walls, parts sharing much of their perimeter).
class VoronoiSegmenter : public RoomSegmenter {
 public:
  std::string name() const override { return "voronoi"; }
  std::map<std::string, double> defaultParameters() const override;
  cv::Mat1i segment(const SegmentationInput& input, const std::map<std::string, double>& parameters) const override;
};

}  // namespace hidden_rooms::segmentation
