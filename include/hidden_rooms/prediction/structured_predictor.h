#pragma once

// The thesis's structured baseline (docs/method.md#baselines) behind the RoomPredictor interface.

#include <map>
#include <string>
#include <vector>

#include "hidden_rooms/prediction/layout.h"
#include "hidden_rooms/prediction/room_predictor.h"

namespace hidden_rooms::prediction {

// "structured": the layout analysis (layout.h) places every door on the cell grid; from the door's starting
// cell the room floods every edge-adjacent OUT cell that is not a border cell. The room is the union of those
// cells clipped to the cells unknown in the input map. Parameters: the layout parameters (config/layout.yaml).
// terms: "cells" (grid cells in the room), "start_distance" (metres from the door to its grid edge).
class StructuredPredictor : public RoomPredictor {
 public:
  StructuredPredictor() = default;
  std::string name() const override { return "structured"; }
  std::map<std::string, double> defaultParameters() const override;
  PredictionResult predict(const PredictionRequest& request) const override;
};

// The structured flood from one door start: the start cell plus every OUT, non-border cell connected to it
// through shared edges of OUT, non-border cells. Empty when the door has no start cell.
std::vector<int> structuredRoomCells(const Layout& layout, const DoorStart& start);

// A prediction made of grid cells: mask = the cells' pixels that are unknown in `map`, polygon and area from
// the mask (placed = false with a problem when no pixel is left).
RoomPrediction roomFromCells(const common::OccupancyGrid& map, const Layout& layout, int door_id,
                             const std::vector<int>& cells);

}  // namespace hidden_rooms::prediction
