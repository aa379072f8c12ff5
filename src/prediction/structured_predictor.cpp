#include "hidden_rooms/prediction/structured_predictor.h"

#include <chrono>

#include "hidden_rooms/prediction/prediction_support.h"

namespace hidden_rooms::prediction {

std::map<std::string, double> StructuredPredictor::defaultParameters() const {
  return layoutParameters(LayoutOptions());
}

std::vector<int> structuredRoomCells(const Layout& layout, const DoorStart& start) {
  if (!start.found) return {};
  const CellGrid& grid = layout.grid;
  std::vector<bool> taken(grid.size(), false);
  std::vector<int> room{start.start_cell}, frontier{start.start_cell};
  taken[start.start_cell] = true;
  while (!frontier.empty()) {
    const int cell = frontier.back();
    frontier.pop_back();
    for (int next : grid.edgeNeighbours(cell)) {
      if (taken[next] || !grid.cells[next].out || grid.cells[next].border) continue;
      taken[next] = true;
      room.push_back(next);
      frontier.push_back(next);
    }
  }
  return room;
}

RoomPrediction roomFromCells(const common::OccupancyGrid& map, const Layout& layout, int door_id,
                             const std::vector<int>& cells) {
  RoomPrediction room;
  room.door_id = door_id;
  room.mask = cellsMask(layout, cells);
  room.mask.setTo(0, map.cells != common::OccupancyGrid::kUnknown);
  finishPrediction(map, &room);
  return room;
}

PredictionResult StructuredPredictor::predict(const PredictionRequest& request) const {
  const auto start_time = std::chrono::steady_clock::now();
  checkUsableRequest(request);
  const LayoutOptions options = layoutOptionsFromParameters(resolveParameters(*this, request.parameters));
  const Layout layout = analyzeLayout(request.map, request.doors.doors, options, request.debug_dir);

  PredictionResult result;
  for (size_t d = 0; d < request.doors.doors.size(); ++d) {
    const DoorStart& start = layout.doors[d];
    if (!start.found) {
      result.rooms.push_back(unplacedRoom(request.map, request.doors.doors[d].id, start.problem));
      continue;
    }
    const std::vector<int> cells = structuredRoomCells(layout, start);
    RoomPrediction room = roomFromCells(request.map, layout, start.door_id, cells);
    room.terms["cells"] = static_cast<double>(cells.size());
    room.terms["start_distance"] = start.distance;
    result.rooms.push_back(std::move(room));
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return result;
}

}  // namespace hidden_rooms::prediction
