#pragma once
// One case of the thesis's batch analysis (docs/method.md#batch-analysis): an environment with some closable doors
// closed, the rooms behind them erased to unknown and the doors painted as walls, every method run on it and scored
// against the true rooms. `batch_cases` (src/tools) runs the cases of one batch; scripts/batch_analysis drives it.
#include <map>
#include <string>
#include <vector>

#include "hidden_rooms/evaluation/evaluation.h"
#include "hidden_rooms/prediction/room_predictor.h"
#include "hidden_rooms/world/environment.h"
#include "hidden_rooms/world/render.h"

namespace hidden_rooms::evaluation {

// The input of one case: what a robot maps with the doors closed, the doors file and the true rooms.
struct BatchCase {
  std::vector<int> closed_door_numbers;  // as given (closing order), 1-based door numbers
  world::HiddenRoomsCase input;          // map with the rooms erased, doors (environment order), true rooms
  double hidden_percent = 0.0;           // 100 * true room cells / free cells of the complete map
  // Per closed door (doors file order): the true room's area in the map / its free area in the rendering (of an
  // explored map: with every door open). Below 1 where an explored map shows only part of the room; 1 from a
  // rendering (measured on that rendering itself).
  std::vector<double> room_coverage;
  double seconds = 0.0;                  // time to build the case
};

// Renders the environment with the doors `closed_door_numbers` (1-based numbers, as in doors.yaml) closed and
// hides the rooms behind them (renderEnvironment + hideClosedRooms). Throws InputError for a door number that
// does not exist, a repeated one, or a door that is not closable.
BatchCase makeBatchCase(const world::Environment& environment, const std::vector<int>& closed_door_numbers,
                        const world::RenderOptions& options = world::RenderOptions());

// The same from a complete map that is not the rendering (e.g. a map built by exploration): `doors_in_map`
// gives the position of every door of the environment in the map's frame, by door number (at least the closed
// doors, and two doors in all). The environment is placed in the map by the least-squares rigid
// transform of the door centres, each closed room by its door's `map_from_world` where the file has one (an
// explored map's drift); each closed room's outline, grown by `wall_margin` metres, is erased to
// unknown (its true room: the map's free cells inside the outline, before erasing), and each closed door is
// painted as a wall across its width. Throws InputError when the doors are missing or do not fit.
BatchCase makeBatchCaseFromMap(const world::Environment& environment, const common::OccupancyGrid& complete_map,
                               const common::DoorsFile& doors_in_map, const std::vector<int>& closed_door_numbers,
                               double door_width = 0.9, double wall_margin = 0.15);

// One method on one case.
struct MethodOutcome {
  std::string method;
  RoomScores scores;      // IoU per door (environment order), mean IoU, IoU_tot
  int not_placed = 0;     // doors the method could not place (they score 0)
  double seconds = 0.0;   // prediction, label image and scoring
  std::string problem;    // empty on success; else why the method failed as a whole (scores are 0)
};

// Runs `method` on the case and scores it (roomLabels + scoreRooms). An InputError or other exception of the
// method is caught and reported in `problem` with zero scores.
MethodOutcome runMethodOnCase(const prediction::RoomPredictor& method, const BatchCase& batch_case,
                              const std::map<std::string, double>& parameters = {});

}  // namespace hidden_rooms::evaluation
